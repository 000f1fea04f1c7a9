//! The RP2040 board's safety below the rig core: the panic and HardFault handlers, which drive
//! the outputs safe through the registers before anything else, and what is kept across resets
//! in the watchdog's scratch registers (the fault latch, the servo's last command:
//! `capstan_rig::reset`). Compiled into the board binary only.
//!
//! Why here and not in the drivers: a panic can strike in the middle of a driver call, before
//! the drivers exist, or with the rig's state half-updated. The handlers therefore use only
//! [`capstan_rig::force_safe`] on [`Registers`] (plain register writes, no driver, no lock, no
//! floating point, no log) with the one number computed at boot ([`arm`]), and only then log.
//!
//! What happens on a panic, by case:
//!
//! * **No probe attached:** `#[panic_handler]` (or defmt's, for `defmt::panic!`/`unwrap!`)
//!   disables interrupts, forces the outputs safe, logs the message, and raises a HardFault;
//!   the HardFault handler forces them safe again (idempotent) and resets the chip through the
//!   watchdog at once (reported at the next boot as a forced reset).
//! * **`probe-rs run` or `attach`:** the same up to the HardFault, where probe-rs halts the
//!   core and prints the backtrace. The outputs are already safe. The watchdog is not paused by
//!   the halt (`board::WATCHDOG_PAUSES_WHILE_HALTED`), so the chip resets within
//!   `WATCHDOG_TIMEOUT` and boots into the idle rig.
//! * **A HardFault not caused by a panic, with probe-rs attached:** probe-rs halts the core on
//!   the exception's entry, before any handler runs; only the watchdog covers that, resetting
//!   the chip (every output pin to an input, the pull-downs take amplifier and trigger low)
//!   within `WATCHDOG_TIMEOUT`. Without a probe, the handler below makes the outputs safe.
//!
//! Timing: [`force_safe`] is ~120 straight-line instructions of register writes, the
//! amplifier's first among them: a few microseconds from the handler's start at 125 MHz, even
//! with the code not yet in the XIP cache. The servo's PWM compare is double-buffered, so the
//! rest pulse goes out from the next 20 ms frame, as every servo command does.

use crate::board::{self, AMP_GPIO, AMP_SLICE, SERVO_GPIO, SERVO_SLICE, TRIGGER_GPIO};
use capstan_rig::reset::{recall_servo_duty, remembered_servo_word};
use capstan_rig::{force_safe, ForceOutputs, SafeDuties};
use core::sync::atomic::{AtomicBool, AtomicU16, Ordering};
use cortex_m_rt::{exception, ExceptionFrame};
use embassy_rp::pac;
use embassy_rp::pwm::{Pwm, PwmError};
use embedded_hal::pwm::{ErrorType, SetDutyCycle};

/// IO_BANK0 function select: the pin is driven by SIO (software).
const FUNCSEL_SIO: u8 = 5;
/// IO_BANK0 function select: the pin is driven by its PWM slice.
const FUNCSEL_PWM: u8 = 4;

/// The servo's rest duty for the handlers: 0 (no pulses) until [`arm`].
static SAFE_SERVO_DUTY: AtomicU16 = AtomicU16::new(0);
/// The servo duty last written: the handlers keep it if it releases more than rest
/// ([`SafeDuties::releasing`]).
static COMMANDED_SERVO_DUTY: AtomicU16 = AtomicU16::new(0);
/// Set by the first panic: a panic while logging the first one skips the log.
static PANICKED: AtomicBool = AtomicBool::new(false);

/// Give the handlers the rest duty, once the rig is made (before, they stop the servo pulses).
pub fn arm(duties: SafeDuties) {
    SAFE_SERVO_DUTY.store(duties.servo_rest, Ordering::Relaxed);
}

/// What the handlers command now: rest, or where the servo is if that releases more (jogged
/// past rest in setup mode), or no pulses.
fn armed() -> SafeDuties {
    SafeDuties {
        servo_rest: SAFE_SERVO_DUTY.load(Ordering::Relaxed),
    }
    .releasing(COMMANDED_SERVO_DUTY.load(Ordering::Relaxed))
}

/// The rig's outputs as raw RP2040 registers, whatever the drivers' state. A block still held
/// in reset is not touched (reading it could stall the bus): its pins are then inputs, and the
/// pull-downs hold the amplifier control and the trigger low, the servo gets no pulses.
pub struct Registers;

impl Registers {
    /// (IO_BANK0 and PADS_BANK0 usable, PWM usable).
    fn ready() -> (bool, bool) {
        let done = pac::RESETS.reset_done().read();
        (done.io_bank0() && done.pads_bank0(), done.pwm())
    }

    /// `gpio` driven low by software, whatever function it had.
    fn drive_low(gpio: usize) {
        let bit = 1u32 << gpio;
        pac::SIO.gpio_out(0).value_clr().write_value(bit);
        pac::SIO.gpio_oe(0).value_set().write_value(bit);
        pac::PADS_BANK0.gpio(gpio).modify(|w| w.set_od(false));
        pac::IO_BANK0
            .gpio(gpio)
            .ctrl()
            .write(|w| w.set_funcsel(FUNCSEL_SIO));
    }
}

impl ForceOutputs for Registers {
    fn force_amp_off(&mut self) {
        let (io, pwm) = Registers::ready();
        if pwm {
            pac::PWM.ch(AMP_SLICE).cc().modify(|w| w.set_a(0));
        }
        // The pin itself low: holds even if the PWM slice is misconfigured.
        if io {
            Registers::drive_low(AMP_GPIO);
        }
    }

    fn force_servo_duty(&mut self, duty: u16) {
        let (io, pwm) = Registers::ready();
        if duty == 0 || !pwm {
            if io {
                Registers::drive_low(SERVO_GPIO);
            }
            return;
        }
        // The slice set up from scratch (same values as at boot: writing them again is
        // harmless), the rest pulse in its compare, the pin given to the slice.
        let ch = pac::PWM.ch(SERVO_SLICE);
        ch.div().write(|w| {
            w.set_int(board::SERVO_PWM_DIVIDER);
            w.set_frac(0);
        });
        ch.top().write(|w| w.set_top(board::SERVO_PWM_TOP));
        ch.cc().modify(|w| w.set_a(duty));
        ch.csr().write(|w| w.set_en(true));
        if io {
            pac::PADS_BANK0.gpio(SERVO_GPIO).modify(|w| w.set_od(false));
            pac::IO_BANK0
                .gpio(SERVO_GPIO)
                .ctrl()
                .write(|w| w.set_funcsel(FUNCSEL_PWM));
        }
        remember_servo_duty(duty);
    }

    fn force_trigger_low(&mut self) {
        if Registers::ready().0 {
            Registers::drive_low(TRIGGER_GPIO);
        }
    }
}

/// Keep the servo's command in watchdog scratch register 0, which survives a watchdog reset
/// (not a power cycle), so the next boot can say where the horn was told to be.
fn remember_servo_duty(duty: u16) {
    pac::WATCHDOG
        .scratch0()
        .write_value(remembered_servo_word(duty));
}

/// The servo duty the firmware last commanded before this boot's reset, if it survived.
pub fn servo_duty_before_reset() -> Option<u16> {
    recall_servo_duty(pac::WATCHDOG.scratch0().read(), board::SERVO_FULL_SCALE)
}

/// Keep the rig's latch word (`capstan_rig::reset::latch_word`) in watchdog scratch register 1:
/// written every sample, read at the next boot. (Registers 4-7 belong to the boot ROM.)
pub fn remember_latch(word: u32) {
    pac::WATCHDOG.scratch1().write_value(word);
}

/// The latch word kept before this boot's reset (0 after a power cycle).
pub fn latch_word_before_reset() -> u32 {
    pac::WATCHDOG.scratch1().read()
}

/// An RP2040 PWM output on channel A whose duty is counted against the whole period: the
/// output is high for `compare` counts of every `top + 1`, so `max_duty_cycle()` is `top + 1`
/// and a duty of `top + 1` is 100 %. (embassy-rp's `Pwm` reports `top` as its full scale: every
/// duty the rig core converts would then come out `1/(top + 1)` short — the amplifier's 2.5 V
/// as 2.4992 V, one count low, which the emulated board's pin measurement showed.)
pub struct PeriodPwm {
    pwm: Pwm<'static>,
    slice: usize,
}

impl PeriodPwm {
    /// `pwm` (channel A of `slice`), configured with a `top` below 65 535.
    pub fn new(pwm: Pwm<'static>, slice: usize) -> Self {
        PeriodPwm { pwm, slice }
    }
}

impl ErrorType for PeriodPwm {
    type Error = PwmError;
}

impl SetDutyCycle for PeriodPwm {
    fn max_duty_cycle(&self) -> u16 {
        self.pwm.max_duty_cycle().saturating_add(1)
    }

    fn set_duty_cycle(&mut self, duty: u16) -> Result<(), PwmError> {
        let top = self.pwm.max_duty_cycle();
        if duty <= top {
            self.pwm.set_duty_cycle(duty)
        } else if duty == top.saturating_add(1) {
            // 100 %: a compare above `top`, which embassy-rp's driver refuses.
            pac::PWM.ch(self.slice).cc().modify(|w| w.set_a(duty));
            Ok(())
        } else {
            Err(PwmError::InvalidDutyCycle)
        }
    }
}

/// The servo PWM, remembering every duty it is given across a reset.
pub struct RememberingServo(pub PeriodPwm);

impl ErrorType for RememberingServo {
    type Error = PwmError;
}

impl SetDutyCycle for RememberingServo {
    fn max_duty_cycle(&self) -> u16 {
        self.0.max_duty_cycle()
    }

    fn set_duty_cycle(&mut self, duty: u16) -> Result<(), PwmError> {
        self.0.set_duty_cycle(duty)?;
        COMMANDED_SERVO_DUTY.store(duty, Ordering::Relaxed);
        remember_servo_duty(duty);
        Ok(())
    }
}

/// Raise a HardFault: probe-rs (if attached) halts here and prints the backtrace; otherwise
/// the HardFault handler resets the chip. (No UsageFault on a Cortex-M0+: `udf` faults hard.)
fn hard_fault() -> ! {
    cortex_m::asm::udf()
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    cortex_m::interrupt::disable();
    force_safe(&mut Registers, armed());
    if !PANICKED.load(Ordering::Relaxed) {
        PANICKED.store(true, Ordering::Relaxed);
        defmt::error!("panic (outputs made safe): {}", defmt::Display2Format(info));
    }
    hard_fault()
}

/// `defmt::panic!`, `unwrap!`, `assert!`: they have logged their message already.
#[defmt::panic_handler]
fn defmt_panic() -> ! {
    cortex_m::interrupt::disable();
    force_safe(&mut Registers, armed());
    PANICKED.store(true, Ordering::Relaxed);
    hard_fault()
}

// SAFETY (of declaring it): cortex-m-rt requires the HardFault handler to be an `unsafe fn`; it
// runs only as the exception, and touches nothing but registers.
#[exception]
unsafe fn HardFault(_frame: &ExceptionFrame) -> ! {
    force_safe(&mut Registers, armed());
    // Reset now, through the watchdog (everything but the oscillators, as `main` sets it up),
    // rather than wait for its timeout; the next boot reports a forced reset.
    pac::PSM
        .wdsel()
        .write_value(pac::psm::regs::Wdsel(0x0001_ffff & !0b11));
    pac::WATCHDOG.ctrl().modify(|w| {
        w.set_enable(true);
        w.set_pause_dbg0(false);
        w.set_pause_dbg1(false);
        w.set_pause_jtag(false);
        w.set_trigger(true);
    });
    loop {
        cortex_m::asm::nop();
    }
}
