//! The rig firmware on an emulated Cortex-M3 (QEMU's lm3s6965evb, a Stellaris LM3S6965 with
//! 256 KiB of flash and 64 KiB of SRAM): the same rig core as the Pico, on a SysTick time
//! driver, with the simulated plant compiled in and defmt over semihosting. It runs
//! `capstan_qemu_fw::scenario` (two runs; the plant presses the button) and exits QEMU, after writing
//! its RAM use (the stack's high-water mark, read back from the paint the reset handler put on
//! it) to QEMU's stderr; stdout carries only the defmt stream.
//!
//! `cargo run --release -p capstan-qemu-fw --target thumbv7m-none-eabi` runs it (the runner is in
//! `.cargo/config.toml`); its stdout is the defmt stream `capstan log --from -` decodes.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!(
        "qemu-fw is the emulated-ARM firmware; build it with --target thumbv7m-none-eabi \
         (see docs/README-log.md)"
    );
}

#[cfg(target_os = "none")]
mod rt;
#[cfg(target_os = "none")]
mod time_driver;

#[cfg(target_os = "none")]
use defmt_semihosting as _;

/// Report the RAM use on stderr (tests/log_qemu.rs reads it) and leave QEMU with this exit
/// code.
#[cfg(target_os = "none")]
fn exit(code: i32) -> ! {
    let ram = rt::ram_usage();
    semihosting::eprintln!(
        "qemu-fw: stack high-water mark {} of {} bytes; statics {} bytes",
        ram.stack_used,
        ram.stack_size,
        ram.statics
    );
    semihosting::process::exit(code)
}

#[cfg(target_os = "none")]
#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    if let Some(loc) = info.location() {
        defmt::error!("qemu-fw panicked at {=str}:{=u32}", loc.file(), loc.line());
    } else {
        defmt::error!("qemu-fw panicked");
    }
    exit(2)
}

#[cfg(target_os = "none")]
#[defmt::panic_handler]
fn defmt_panic() -> ! {
    exit(2)
}

/// Set by the executor's pender when a task was woken.
#[cfg(target_os = "none")]
static WOKEN: core::sync::atomic::AtomicBool = core::sync::atomic::AtomicBool::new(true);

#[cfg(target_os = "none")]
#[export_name = "__pender"]
fn pender(_context: *mut ()) {
    WOKEN.store(true, core::sync::atomic::Ordering::SeqCst);
}

/// Thread-mode executor that sleeps with WFI (embassy's own uses WFE, which QEMU treats as a
/// spin): an idle core then lets QEMU's `-icount ...,sleep=off` jump straight to the next
/// SysTick, so the emulated run is deterministic and faster than real time.
#[cfg(target_os = "none")]
#[no_mangle]
extern "C" fn qemu_fw_main() -> ! {
    use core::sync::atomic::Ordering;
    use embassy_executor::raw::Executor;
    let peripherals = cortex_m::Peripherals::take().unwrap();
    time_driver::init(peripherals.SYST);
    static mut EXECUTOR: core::mem::MaybeUninit<Executor> = core::mem::MaybeUninit::uninit();
    // SAFETY: `qemu_fw_main` runs once; nothing else touches EXECUTOR.
    let executor: &'static Executor =
        unsafe { (*core::ptr::addr_of_mut!(EXECUTOR)).write(Executor::new(core::ptr::null_mut())) };
    executor.spawner().spawn(rig().unwrap());
    loop {
        if WOKEN.swap(false, Ordering::SeqCst) {
            // SAFETY: not reentrant: only this loop polls.
            unsafe { executor.poll() };
            continue;
        }
        // With interrupts masked, an interrupt that arrives after the check still ends the WFI.
        cortex_m::interrupt::free(|_| {
            if !WOKEN.load(Ordering::SeqCst) {
                cortex_m::asm::wfi();
            }
        });
    }
}

#[cfg(target_os = "none")]
#[embassy_executor::task]
async fn rig() {
    use capstan_qemu_fw::ScenarioError;
    use capstan_rig::defmt_sink::DefmtSink;

    // A banner with nested and slice formats: besides saying what runs, it gives the decoder
    // tests' recorded stream (and the fuzzer) frames of every shape, not only flat records.
    let seeds = [capstan_qemu_fw::RUNS[0].seed, capstan_qemu_fw::RUNS[1].seed];
    defmt::info!(
        "qemu-fw {=[u8]:a}: {=usize} runs, plant seeds {=[?]}, protocol {}",
        &b"capstan"[..],
        capstan_qemu_fw::RUNS.len(),
        &seeds[..],
        capstan_qemu_fw::protocol()
    );
    let code = match capstan_qemu_fw::scenario(&mut DefmtSink::default()).await {
        Ok(_) => 0,
        Err(ScenarioError::Plant(_)) => {
            defmt::error!("qemu-fw: the plant refused its configuration");
            4
        }
        Err(ScenarioError::Protocol(e)) => {
            defmt::error!("qemu-fw: protocol refused: {}", e);
            4
        }
        Err(ScenarioError::Run(e)) => {
            defmt::error!("qemu-fw: hardware error {}", e);
            1
        }
    };
    exit(code)
}
