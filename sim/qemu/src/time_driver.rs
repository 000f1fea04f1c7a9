//! embassy-time driver on SysTick: one interrupt per millisecond, `now()` in whole milliseconds
//! (on embassy-time's 1 MHz tick), wake-ups checked at each interrupt.
//!
//! Millisecond resolution is deliberate: every instant the rig core and the plant see is a whole
//! millisecond, exactly as in host-sim's virtual time, so the emulated run and the simulated
//! run sample the plant at the same instants (a sub-millisecond read of the counter would make
//! QEMU's timing jitter leak into the data).

use core::cell::{Cell, RefCell};
use core::task::Waker;
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::SYST;
use critical_section::Mutex;
use embassy_time_driver::Driver;
use embassy_time_queue_utils::Queue;

/// Ticks (µs) per SysTick interrupt.
const TICK_US: u64 = 1_000;

/// Core clock of QEMU's lm3s6965evb after reset, Hz: QEMU derives it from the system control
/// block's RCC register, whose reset value selects the 200 MHz PLL output divided by 16
/// (SYSDIV = 15). Checked: with this reload a real-time run (`-icount` off) of the 4.5 s
/// scenario takes 4.5 s; with 25 MHz it took 9.1 s. (Under `-icount` the tick follows the
/// instruction count either way.)
pub const CORE_HZ: u32 = 12_500_000;

struct SysTickDriver {
    ms: Mutex<Cell<u64>>,
    queue: Mutex<RefCell<Queue>>,
}

impl Driver for SysTickDriver {
    fn now(&self) -> u64 {
        critical_section::with(|cs| self.ms.borrow(cs).get()) * TICK_US
    }

    fn schedule_wake(&self, at: u64, waker: &Waker) {
        critical_section::with(|cs| {
            let mut queue = self.queue.borrow_ref_mut(cs);
            queue.schedule_wake(at, waker);
            // Already due: wake now rather than at the next interrupt.
            queue.next_expiration(self.ms.borrow(cs).get() * TICK_US);
        })
    }
}

embassy_time_driver::time_driver_impl!(static DRIVER: SysTickDriver = SysTickDriver {
    ms: Mutex::new(Cell::new(0)),
    queue: Mutex::new(RefCell::new(Queue::new())),
});

/// Start the millisecond interrupt.
pub fn init(mut syst: SYST) {
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(CORE_HZ / 1_000 - 1);
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();
}

/// The SysTick exception handler (installed in the vector table by `rt.rs`).
pub unsafe extern "C" fn on_systick() {
    critical_section::with(|cs| {
        let ms = DRIVER.ms.borrow(cs);
        ms.set(ms.get() + 1);
        DRIVER
            .queue
            .borrow_ref_mut(cs)
            .next_expiration(ms.get() * TICK_US);
    });
}
