//! Virtual time: an embassy-time driver whose clock only moves when every future is waiting.
//!
//! Each thread has its own clock and timer queue (thread-locals), so simulations run in
//! parallel threads without seeing each other. [`block_on`] polls a future; when it is pending
//! and nothing woke it, the clock jumps straight to the earliest deadline in the queue and the
//! wakers due are woken. 140 s of a 1 kHz protocol is ~140 000 jumps: milliseconds of wall time.
//!
//! This crate is the only embassy-time driver of any host binary it is linked into.

use std::cell::{Cell, RefCell};
use std::future::{poll_fn, Future};
use std::pin::{pin, Pin};
use std::task::{Context, Poll, RawWaker, RawWakerVTable, Waker};

/// A timer: wake `waker` at `at`.
struct Entry {
    at: u64,
    waker: Waker,
}

/// Deadlines of [`block_on`]'s own waker kept apart (see [`Clock`]).
const FLAG_SLOTS: usize = 8;

/// One thread's clock: its time, its "poll again" flag and the deadlines of its own waker's
/// timers. No destructor (unlike the queue of other timers, `QUEUE`), so using it (several
/// times per simulated sample) checks no lazily registered destructor's state, and one
/// thread-local for all of it is one address to work out per use.
///
/// Timers come in two kinds. Those with our own waker (every future `block_on` polls passes it
/// down, so in practice all of them): waking one only raises `woken`, so its waker need not be
/// kept, nor woken in any order, and two of them due at the same instant are one. Their
/// deadlines are kept distinct in `flag_at[..flag_len]`, latest first. Any other waker (or one
/// of ours when those slots are full) goes with its waker into `QUEUE`: a short vector sorted
/// by deadline, latest first, equal deadlines in FIFO order (pushing is a scan from the end,
/// popping the earliest is `Vec::pop`). The clock jumps to the earliest deadline of either and
/// every timer due by then, of either kind, is woken: the same jumps, and the same wakes of
/// other wakers in the same order, as one queue of every timer would give.
struct Clock {
    now: Cell<u64>,
    woken: Cell<bool>,
    flag_len: Cell<usize>,
    flag_at: [Cell<u64>; FLAG_SLOTS],
    /// The earliest deadline in `QUEUE` (kept here: the queue need not be looked at while it
    /// is empty, as it usually is).
    other_next: Cell<Option<u64>>,
}

impl Clock {
    /// Keep `at` among our waker's deadlines; false if the slots are full (and `at` is not
    /// there).
    #[inline]
    fn schedule_flag(&self, at: u64) -> bool {
        // A rig has one timer pending at a time (its ticker): usually there is none now.
        if self.flag_len.get() == 0 {
            self.flag_at[0].set(at);
            self.flag_len.set(1);
            return true;
        }
        self.insert_flag(at)
    }

    /// [`Clock::schedule_flag`] with other deadlines pending.
    #[inline(never)]
    fn insert_flag(&self, at: u64) -> bool {
        let slots = &self.flag_at;
        let n = self.flag_len.get();
        // The earliest deadlines are at the end: find where `at` goes from there.
        let mut pos = n;
        while pos > 0 && slots[pos - 1].get() < at {
            pos -= 1;
        }
        if pos > 0 && slots[pos - 1].get() == at {
            return true;
        }
        if n == FLAG_SLOTS {
            return false;
        }
        // Usually the new deadline is the earliest: no shifting.
        for k in (pos..n).rev() {
            slots[k + 1].set(slots[k].get());
        }
        slots[pos].set(at);
        self.flag_len.set(n + 1);
        true
    }

    /// The earliest of our waker's deadlines.
    #[inline]
    fn earliest_flag(&self) -> Option<u64> {
        match self.flag_len.get() {
            0 => None,
            n => Some(self.flag_at[n - 1].get()),
        }
    }

    /// Drop our waker's deadlines due by `now`.
    #[inline]
    fn take_flags_due(&self, now: u64) {
        let mut k = self.flag_len.get();
        while k > 0 && self.flag_at[k - 1].get() <= now {
            k -= 1;
        }
        self.flag_len.set(k);
    }
}

thread_local! {
    static CLOCK: Clock = const {
        Clock {
            now: Cell::new(0),
            woken: Cell::new(false),
            flag_len: Cell::new(0),
            flag_at: [const { Cell::new(0) }; FLAG_SLOTS],
            other_next: Cell::new(None),
        }
    };
    static QUEUE: RefCell<Vec<Entry>> = const { RefCell::new(Vec::new()) };
}

struct VirtualTime;

impl embassy_time_driver::Driver for VirtualTime {
    fn now(&self) -> u64 {
        CLOCK.with(|c| c.now.get())
    }

    fn schedule_wake(&self, at: u64, waker: &Waker) {
        if !(is_flag_waker(waker) && CLOCK.with(|c| c.schedule_flag(at))) {
            schedule_other(at, waker);
        }
    }
}

/// Queue a timer with its waker (another waker than ours, or ours with its slots full).
#[inline(never)]
fn schedule_other(at: u64, waker: &Waker) {
    QUEUE.with_borrow_mut(|q| {
        // After the later deadlines, ahead of equal ones: equal deadlines pop in FIFO order.
        let pos = q.iter().rposition(|e| e.at > at).map_or(0, |p| p + 1);
        let entry = Entry {
            at,
            waker: waker.clone(),
        };
        // Usually the queue is empty or the new deadline the earliest: no shifting then.
        if pos == q.len() {
            q.push(entry);
        } else {
            q.insert(pos, entry);
        }
        CLOCK.with(|c| c.other_next.set(q.last().map(|e| e.at)));
    })
}

embassy_time_driver::time_driver_impl!(static DRIVER: VirtualTime = VirtualTime);

/// This thread's virtual time, µs (embassy-time ticks at 1 MHz).
#[inline]
pub fn now_us() -> u64 {
    CLOCK.with(|c| c.now.get())
}

/// This thread's virtual time as the plant adapters read it: the clock `embassy_time::Instant`
/// reads through this crate's driver, held by reference, so each of the ~5 reads per simulated
/// sample is a load (not a call to the driver's symbol and the thread-local's accessor).
#[derive(Clone, Copy, Debug)]
pub struct VirtualClock<'a>(&'a Cell<u64>);

impl capstan_plant::hal::Clock for VirtualClock<'_> {
    #[inline]
    fn now_us(&self) -> u64 {
        self.0.get()
    }
}

/// Run `f` with this thread's [`VirtualClock`].
pub fn with_clock<R>(f: impl FnOnce(VirtualClock<'_>) -> R) -> R {
    CLOCK.with(|c| f(VirtualClock(&c.now)))
}

/// Start this thread's clock afresh at `now_us` with no timer pending.
pub fn reset(now_us: u64) {
    CLOCK.with(|c| {
        c.now.set(now_us);
        c.woken.set(false);
        c.flag_len.set(0);
        c.other_next.set(None);
    });
    QUEUE.with_borrow_mut(Vec::clear);
}

// The waker of `block_on`: it only raises this thread's "poll again" flag. A static, not a
// const: its one address tells our wakers from any other.
static VTABLE: RawWakerVTable = RawWakerVTable::new(clone_raw, wake_raw, wake_raw, drop_raw);

fn clone_raw(_: *const ()) -> RawWaker {
    RawWaker::new(std::ptr::null(), &VTABLE)
}

/// Is `waker` one of `block_on`'s (waking it only raises `woken`)?
#[inline]
fn is_flag_waker(waker: &Waker) -> bool {
    std::ptr::eq(waker.vtable(), &VTABLE)
}

fn wake_raw(_: *const ()) {
    CLOCK.with(|c| c.woken.set(true));
}

fn drop_raw(_: *const ()) {}

fn flag_waker() -> Waker {
    // SAFETY: the vtable's functions ignore the (null) data pointer and are thread-safe in the
    // only sense that matters here: they touch a thread-local.
    unsafe { Waker::from_raw(clone_raw(std::ptr::null())) }
}

/// Why [`block_on_until`] stopped before the future was done.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stalled {
    /// The next deadline is past the limit.
    Limit,
    /// The future is pending with no timer that could ever wake it.
    Deadlock,
}

/// Run `fut` to completion in virtual time, or stop when the clock would pass `limit_us`.
pub fn block_on_until<F: Future>(fut: F, limit_us: u64) -> Result<F::Output, Stalled> {
    let waker = flag_waker();
    let mut cx = Context::from_waker(&waker);
    let mut fut = pin!(fut);
    CLOCK.with(|clock| {
        QUEUE.with(|queue| loop {
            clock.woken.set(false);
            if let Poll::Ready(v) = fut.as_mut().poll(&mut cx) {
                return Ok(v);
            }
            if clock.woken.get() {
                continue;
            }
            // Usually one timer is pending, the ticker's, with our waker: jump to it. (What
            // the general case below does then, without its scans.)
            if clock.flag_len.get() == 1 && clock.other_next.get().is_none() {
                let next = clock.flag_at[0].get();
                if next > limit_us {
                    return Err(Stalled::Limit);
                }
                clock.now.set(clock.now.get().max(next));
                clock.flag_len.set(0);
                continue;
            }
            let next = match (clock.earliest_flag(), clock.other_next.get()) {
                (Some(a), Some(b)) => a.min(b),
                (Some(a), None) | (None, Some(a)) => a,
                (None, None) => return Err(Stalled::Deadlock),
            };
            if next > limit_us {
                return Err(Stalled::Limit);
            }
            let now = clock.now.get().max(next);
            clock.now.set(now);
            // Our own timers due: waking them would only raise `woken`, and the future is
            // polled again after every jump anyway.
            clock.take_flags_due(now);
            // Other wakers due, in deadline order (waking them with the queue borrowed is
            // fine: they cannot be ours).
            if clock.other_next.get().is_some_and(|at| at <= now) {
                let mut q = queue.borrow_mut();
                while q.last().is_some_and(|e| e.at <= now) {
                    q.pop().unwrap().waker.wake();
                }
                clock.other_next.set(q.last().map(|e| e.at));
            }
        })
    })
}

/// Run `fut` to completion in virtual time. Panics if it can never complete.
pub fn block_on<F: Future>(fut: F) -> F::Output {
    match block_on_until(fut, u64::MAX) {
        Ok(v) => v,
        Err(e) => panic!("virtual time: the future cannot complete ({e:?})"),
    }
}

/// Poll every future to completion; outputs in the same order.
pub(crate) async fn join_all<F: Future>(futs: Vec<F>) -> Vec<F::Output> {
    let mut futs: Vec<Pin<Box<F>>> = futs.into_iter().map(Box::pin).collect();
    let mut outs: Vec<Option<F::Output>> = futs.iter().map(|_| None).collect();
    poll_fn(move |cx| {
        for (f, o) in futs.iter_mut().zip(outs.iter_mut()) {
            if o.is_none() {
                if let Poll::Ready(v) = f.as_mut().poll(cx) {
                    *o = Some(v);
                }
            }
        }
        if outs.iter().all(Option::is_some) {
            Poll::Ready(outs.iter_mut().map(|o| o.take().unwrap()).collect())
        } else {
            Poll::Pending
        }
    })
    .await
}

#[cfg(test)]
mod tests {
    use super::*;
    use embassy_time::{Duration, Instant, Ticker, Timer};

    #[test]
    fn virtual_time_jumps_to_deadlines() {
        reset(0);
        let ticks = block_on(async {
            let mut t = Ticker::every(Duration::from_millis(1));
            let mut n = 0u32;
            while Instant::now() < Instant::from_secs(140) {
                t.next().await;
                n += 1;
            }
            n
        });
        assert_eq!(ticks, 140_000);
        assert_eq!(now_us(), 140_000_000);
        // Timers in a join wake in deadline order.
        reset(5);
        let order = RefCell::new(Vec::new());
        block_on(embassy_futures::join::join(
            async {
                Timer::after_millis(3).await;
                order.borrow_mut().push((3, now_us()));
            },
            async {
                Timer::after_millis(2).await;
                order.borrow_mut().push((2, now_us()));
            },
        ));
        assert_eq!(*order.borrow(), vec![(2, 2_005), (3, 3_005)]);
    }

    #[test]
    fn many_timers_and_other_wakers_wake_in_deadline_order() {
        use std::sync::atomic::{AtomicU32, Ordering};
        use std::sync::Arc;
        use std::task::Wake;
        // More pending deadlines of our own waker than it keeps apart, in scrambled order,
        // with repeats: each wakes at its time.
        reset(0);
        let order = RefCell::new(Vec::new());
        let delays: Vec<u64> = (0..20u64).map(|k| 1 + (k * 7) % 13).collect();
        block_on(join_all(
            delays
                .iter()
                .map(|&ms| {
                    let order = &order;
                    async move {
                        Timer::after_millis(ms).await;
                        order.borrow_mut().push((ms, now_us()));
                    }
                })
                .collect(),
        ));
        let got = order.into_inner();
        assert_eq!(got.len(), delays.len());
        assert!(got.iter().all(|&(ms, t)| t == ms * 1000));
        assert!(got.windows(2).all(|w| w[0].1 <= w[1].1));
        // A future that polls a timer with a waker of its own (a nested executor would): the
        // clock still jumps to its deadline, and that waker is woken there.
        struct Count(AtomicU32);
        impl Wake for Count {
            fn wake(self: Arc<Self>) {
                self.0.fetch_add(1, Ordering::Relaxed);
            }
        }
        reset(0);
        let count = Arc::new(Count(AtomicU32::new(0)));
        let own = Waker::from(count.clone());
        let mut timer = Timer::after_millis(5);
        let woken_at = block_on(poll_fn(|_| {
            let mut cx = Context::from_waker(&own);
            match Pin::new(&mut timer).poll(&mut cx) {
                Poll::Ready(()) => Poll::Ready(now_us()),
                Poll::Pending => Poll::Pending,
            }
        }));
        assert_eq!(woken_at, 5_000);
        assert_eq!(count.0.load(Ordering::Relaxed), 1);
    }

    #[test]
    fn limits_and_deadlocks_are_reported() {
        reset(0);
        let r = block_on_until(Timer::after_secs(10), 5_000_000);
        assert_eq!(r, Err(Stalled::Limit));
        reset(0);
        let r = block_on_until(std::future::pending::<()>(), u64::MAX);
        assert_eq!(r, Err(Stalled::Deadlock));
    }

    #[test]
    fn threads_have_their_own_clocks() {
        let handles: Vec<_> = (1..=4u64)
            .map(|k| {
                std::thread::spawn(move || {
                    reset(0);
                    block_on(Timer::after_secs(k));
                    now_us()
                })
            })
            .collect();
        let got: Vec<u64> = handles.into_iter().map(|h| h.join().unwrap()).collect();
        assert_eq!(got, vec![1_000_000, 2_000_000, 3_000_000, 4_000_000]);
    }
}
