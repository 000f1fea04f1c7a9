//! The rig firmware on QEMU's lm3s6965evb (Cortex-M3): the same rig core as the Pico, on a
//! SysTick time driver, with the simulated plant compiled in and defmt over semihosting. It
//! presses its own button, makes one run of `qemu_fw::protocol()`, and exits QEMU.
//!
//! `cargo run --release -p qemu-fw --target thumbv7m-none-eabi` runs it (the runner is in
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

/// Leave QEMU with this exit code.
#[cfg(target_os = "none")]
fn exit(code: i32) -> ! {
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

#[cfg(target_os = "none")]
#[no_mangle]
extern "C" fn qemu_fw_main() -> ! {
    use embassy_executor::Executor;
    let peripherals = cortex_m::Peripherals::take().unwrap();
    time_driver::init(peripherals.SYST);
    static mut EXECUTOR: core::mem::MaybeUninit<Executor> = core::mem::MaybeUninit::uninit();
    // SAFETY: `qemu_fw_main` runs once; nothing else touches EXECUTOR.
    let executor: &'static mut Executor =
        unsafe { (*core::ptr::addr_of_mut!(EXECUTOR)).write(Executor::new()) };
    executor.run(|spawner| spawner.spawn(rig().unwrap()))
}

#[cfg(target_os = "none")]
#[embassy_executor::task]
async fn rig() {
    use core::cell::RefCell;
    use firmware::defmt_sink::DefmtSink;
    use firmware::{run_once, Rig, RigIo};
    use qemu_fw::placeholder::{Adc, Amp, Button, Dog, Pin, Plant, Servo};

    let plant = RefCell::new(Plant::new(qemu_fw::SEED));
    let mut io = RigIo {
        servo: Servo(&plant),
        amp: Amp,
        trigger: Pin,
        led: Pin,
        button: Button(&plant),
        adc: Adc(&plant),
        watchdog: Dog,
    };
    let mut rig = match Rig::new(
        qemu_fw::protocol(),
        qemu_fw::calibration(),
        qemu_fw::limits(),
    ) {
        Ok(rig) => rig,
        Err(e) => {
            defmt::error!("qemu-fw: protocol refused: {}", e);
            exit(4)
        }
    };
    let code = match run_once(&mut io, &mut rig, &mut DefmtSink).await {
        Ok(end) if end.fault.is_none() => 0,
        Ok(_) => 0,
        Err(e) => {
            defmt::error!("qemu-fw: hardware error {}", e);
            1
        }
    };
    exit(code)
}
