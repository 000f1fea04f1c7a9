//! The WebAssembly interface the harness (`sim/emu/harness.mjs`) calls: plain C-ABI functions on
//! one bench per instance. Times are emulator ns as f64 (exact to 2^53 ns, 104 days).

use crate::bench::{Bench, ResetReason};
use std::cell::RefCell;

thread_local! {
    static BENCH: RefCell<Option<Bench>> = const { RefCell::new(None) };
    static BUF: RefCell<Vec<u8>> = const { RefCell::new(Vec::new()) };
}

#[link(wasm_import_module = "env")]
extern "C" {
    /// Prints a message (UTF-8) on the harness's stderr.
    fn bench_log(ptr: *const u8, len: usize);
}

fn log(msg: &str) {
    // SAFETY: the harness reads `len` bytes at `ptr` from this instance's memory, during the
    // call, while `msg` is alive.
    unsafe { bench_log(msg.as_ptr(), msg.len()) }
}

fn with<R>(f: impl FnOnce(&mut Bench) -> R) -> R {
    BENCH.with(|b| f(b.borrow_mut().as_mut().expect("bench_new first")))
}

/// A buffer of `len` bytes for the harness to write the case's name into.
#[no_mangle]
pub extern "C" fn bench_buffer(len: usize) -> *mut u8 {
    BUF.with(|b| {
        let mut b = b.borrow_mut();
        b.clear();
        b.resize(len, 0);
        b.as_mut_ptr()
    })
}

/// Length of the buffer's content (after `bench_report`).
#[no_mangle]
pub extern "C" fn bench_buffer_len() -> usize {
    BUF.with(|b| b.borrow().len())
}

/// Where the buffer is (after `bench_report`).
#[no_mangle]
pub extern "C" fn bench_buffer_ptr() -> *const u8 {
    BUF.with(|b| b.borrow().as_ptr())
}

/// Make the bench for the case named in the buffer: 1, or 0 if there is no such case.
#[no_mangle]
pub extern "C" fn bench_new() -> u32 {
    std::panic::set_hook(Box::new(|info| log(&format!("emu-bench: {info}"))));
    let name = BUF.with(|b| String::from_utf8_lossy(&b.borrow()).into_owned());
    match crate::cases::by_name(&name) {
        Some(c) => {
            BENCH.with(|b| *b.borrow_mut() = Some(Bench::new(c)));
            1
        }
        None => 0,
    }
}

/// Output pin `gpio` is driven low (0), high (1) or not driven (2: an input) at `t_ns`;
/// `tick_ns`: its PWM counter's period.
#[no_mangle]
pub extern "C" fn bench_pin(gpio: u32, level: u32, t_ns: f64, tick_ns: f64) {
    with(|b| b.pin(gpio, level, t_ns, tick_ns))
}

/// A conversion of `channel` starts: its code, or -1 if it never completes.
#[no_mangle]
pub extern "C" fn bench_adc(channel: u32, t_ns: f64) -> i32 {
    with(|b| b.adc(channel, t_ns).map_or(-1, i32::from))
}

/// When `bench_wake` is due, ns, or -1.
#[no_mangle]
pub extern "C" fn bench_deadline() -> f64 {
    with(|b| b.deadline().unwrap_or(-1.0))
}

/// Time is `t_ns`: the `WAKE_*` flags.
#[no_mangle]
pub extern "C" fn bench_wake(t_ns: f64) -> u32 {
    with(|b| b.wake(t_ns))
}

/// 1 if the case has a debug probe attached (the harness then halts the core on HardFault
/// entry, as probe-rs does).
#[no_mangle]
pub extern "C" fn bench_probe_attached() -> u32 {
    with(|b| b.case().probe_attached as u32)
}

/// 1 while the operator holds the button down.
#[no_mangle]
pub extern "C" fn bench_button() -> u32 {
    with(|b| b.button_pressed() as u32)
}

/// The core was busy for `cycles` from `t_ns`.
#[no_mangle]
pub extern "C" fn bench_burst(t_ns: f64, cycles: f64) {
    with(|b| b.burst(t_ns, cycles as u32))
}

/// The harness diverted the core into the panic path at `t_ns`.
#[no_mangle]
pub extern "C" fn bench_panicked(t_ns: f64) {
    with(|b| b.panicked(t_ns))
}

/// The chip was reset at `t_ns`; `reason` is the watchdog's REASON register (1 timer, 2 force).
#[no_mangle]
pub extern "C" fn bench_reset(t_ns: f64, reason: u32) {
    let reason = if reason & 2 != 0 {
        ResetReason::Forced
    } else {
        ResetReason::Timeout
    };
    with(|b| b.reset(t_ns, reason))
}

/// The report as JSON, into the buffer; returns its length.
#[no_mangle]
pub extern "C" fn bench_report(t_ns: f64) -> usize {
    let report = with(|b| b.report(t_ns));
    let json = serde_json::to_vec(&report).expect("the report serialises");
    BUF.with(|b| {
        let mut b = b.borrow_mut();
        *b = json;
        b.len()
    })
}
