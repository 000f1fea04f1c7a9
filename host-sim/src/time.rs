//! Virtual time: an embassy-time driver whose clock only moves when every future is waiting.
//!
//! Each thread has its own clock and timer queue (thread-locals), so simulations run in
//! parallel threads without seeing each other. [`block_on`] polls a future; when it is pending
//! and nothing woke it, the clock jumps straight to the earliest deadline in the queue and the
//! wakers due are woken. 140 s of a 1 kHz protocol is ~140 000 jumps: milliseconds of wall time.
//!
//! This crate is the only embassy-time driver of any host binary it is linked into.

use std::cell::{Cell, RefCell};
use std::cmp::Ordering;
use std::collections::BinaryHeap;
use std::future::Future;
use std::pin::pin;
use std::task::{Context, Poll, RawWaker, RawWakerVTable, Waker};

struct Entry {
    at: u64,
    seq: u64,
    waker: Waker,
}

impl PartialEq for Entry {
    fn eq(&self, other: &Self) -> bool {
        (self.at, self.seq) == (other.at, other.seq)
    }
}

impl Eq for Entry {}

impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Entry {
    /// Reversed: `BinaryHeap` is a max-heap and we want the earliest (then oldest) first.
    fn cmp(&self, other: &Self) -> Ordering {
        (other.at, other.seq).cmp(&(self.at, self.seq))
    }
}

thread_local! {
    static NOW: Cell<u64> = const { Cell::new(0) };
    static SEQ: Cell<u64> = const { Cell::new(0) };
    static WOKEN: Cell<bool> = const { Cell::new(false) };
    static QUEUE: RefCell<BinaryHeap<Entry>> = const { RefCell::new(BinaryHeap::new()) };
}

struct VirtualTime;

impl embassy_time_driver::Driver for VirtualTime {
    fn now(&self) -> u64 {
        NOW.with(Cell::get)
    }

    fn schedule_wake(&self, at: u64, waker: &Waker) {
        let seq = SEQ.with(|s| {
            let v = s.get();
            s.set(v + 1);
            v
        });
        QUEUE.with(|q| {
            q.borrow_mut().push(Entry {
                at,
                seq,
                waker: waker.clone(),
            })
        });
    }
}

embassy_time_driver::time_driver_impl!(static DRIVER: VirtualTime = VirtualTime);

/// This thread's virtual time, µs (embassy-time ticks at 1 MHz).
pub fn now_us() -> u64 {
    NOW.with(Cell::get)
}

/// Start this thread's clock afresh at `now_us` with an empty timer queue.
pub fn reset(now_us: u64) {
    NOW.with(|n| n.set(now_us));
    WOKEN.with(|w| w.set(false));
    QUEUE.with(|q| q.borrow_mut().clear());
}

// The waker of `block_on`: it only raises this thread's "poll again" flag.
const VTABLE: RawWakerVTable = RawWakerVTable::new(clone_raw, wake_raw, wake_raw, drop_raw);

fn clone_raw(_: *const ()) -> RawWaker {
    RawWaker::new(std::ptr::null(), &VTABLE)
}

fn wake_raw(_: *const ()) {
    WOKEN.with(|w| w.set(true));
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
    loop {
        WOKEN.with(|w| w.set(false));
        if let Poll::Ready(v) = fut.as_mut().poll(&mut cx) {
            return Ok(v);
        }
        if WOKEN.with(Cell::get) {
            continue;
        }
        QUEUE.with(|q| {
            let mut q = q.borrow_mut();
            let Some(first) = q.pop() else {
                return Err(Stalled::Deadlock);
            };
            let now = NOW.with(Cell::get);
            if first.at > limit_us {
                q.push(first);
                return Err(Stalled::Limit);
            }
            let now = now.max(first.at);
            NOW.with(|n| n.set(now));
            first.waker.wake();
            while q.peek().is_some_and(|e| e.at <= now) {
                q.pop().unwrap().waker.wake();
            }
            Ok(())
        })?;
    }
}

/// Run `fut` to completion in virtual time. Panics if it can never complete.
pub fn block_on<F: Future>(fut: F) -> F::Output {
    match block_on_until(fut, u64::MAX) {
        Ok(v) => v,
        Err(e) => panic!("virtual time: the future cannot complete ({e:?})"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use embassy_time::{Duration, Instant, Ticker, Timer};

    #[test]
    fn virtual_time_jumps_to_deadlines() {
        reset(0);
        let wall = std::time::Instant::now();
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
        assert!(wall.elapsed().as_secs_f64() < 2.0);
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
