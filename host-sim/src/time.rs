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

// One thread's clock: its time, its "poll again" flag and its timer queue. The queue is a short
// vector kept sorted by deadline, latest first (a rig has one ticker pending, two-control a
// handful): pushing is a scan from the end, popping the earliest is `Vec::pop`. Three
// thread-locals, not one struct: the time and the flag have no destructor, so reading them
// (several times per simulated sample) checks no lazily registered destructor's state.
thread_local! {
    static NOW: Cell<u64> = const { Cell::new(0) };
    static WOKEN: Cell<bool> = const { Cell::new(false) };
    static QUEUE: RefCell<Vec<Entry>> = const { RefCell::new(Vec::new()) };
}

struct VirtualTime;

impl embassy_time_driver::Driver for VirtualTime {
    fn now(&self) -> u64 {
        NOW.get()
    }

    fn schedule_wake(&self, at: u64, waker: &Waker) {
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
        })
    }
}

embassy_time_driver::time_driver_impl!(static DRIVER: VirtualTime = VirtualTime);

/// This thread's virtual time, µs (embassy-time ticks at 1 MHz).
#[inline]
pub fn now_us() -> u64 {
    NOW.get()
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
    NOW.with(|now| f(VirtualClock(now)))
}

/// Start this thread's clock afresh at `now_us` with an empty timer queue.
pub fn reset(now_us: u64) {
    NOW.set(now_us);
    WOKEN.set(false);
    QUEUE.with_borrow_mut(Vec::clear);
}

// The waker of `block_on`: it only raises this thread's "poll again" flag.
const VTABLE: RawWakerVTable = RawWakerVTable::new(clone_raw, wake_raw, wake_raw, drop_raw);

fn clone_raw(_: *const ()) -> RawWaker {
    RawWaker::new(std::ptr::null(), &VTABLE)
}

fn wake_raw(_: *const ()) {
    WOKEN.set(true);
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
    QUEUE.with(|queue| loop {
        WOKEN.set(false);
        if let Poll::Ready(v) = fut.as_mut().poll(&mut cx) {
            return Ok(v);
        }
        if WOKEN.get() {
            continue;
        }
        let mut q = queue.borrow_mut();
        let Some(first) = q.pop() else {
            return Err(Stalled::Deadlock);
        };
        if first.at > limit_us {
            q.push(first);
            return Err(Stalled::Limit);
        }
        let now = NOW.get().max(first.at);
        NOW.set(now);
        // Our wakers only raise `WOKEN`: waking with the queue borrowed is fine.
        first.waker.wake();
        while q.last().is_some_and(|e| e.at <= now) {
            q.pop().unwrap().waker.wake();
        }
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
