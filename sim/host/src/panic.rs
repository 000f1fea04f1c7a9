//! A firmware panic in the middle of a run, and the board's last-resort path, in virtual time.
//!
//! On the RP2040 a panic runs the handler in `firmware/board/src/board_safe.rs`: interrupts off, then
//! `capstan_rig::force_safe` on the raw registers, with the rest duty computed at boot — before it
//! logs, before the HardFault that probe-rs halts on, before any reset. Here the firmware's own
//! runner and rig run against the plant as in [`crate::run`], the simulated ADC panics at a
//! chosen moment (a stand-in for any bug in the loop), the panic unwinds out of the runner at
//! that virtual instant, and host-sim does exactly what the board's handler does:
//! `capstan_rig::force_safe` with `SafeDuties::for_rig` (computed before the run, as at boot) on
//! the plant's pins, [`capstan_plant::ForcedOutputs`]. Nothing of the runner's own safe-state
//! paths runs (a panic skips them), so the plant shows what the handler alone achieves.
//!
//! After the panic nothing drives the plant: on the board the core is halted (probe attached)
//! or resetting (no probe), and in both cases the pins keep what the handler wrote until the
//! chip resets. The plant is advanced [`AFTER_PANIC_US`] further to see the drive voltage fall
//! through the amplifier's RC filter and the servo reach rest.

use crate::run::{time_limit_us, RunSpec, SetupError, VecSink};
use crate::time;
use capstan_plant::hal::TriggerPin;
use capstan_plant::hal::{AmpPwm, ButtonPin, CordRef, LedPin, ServoPwm, SimAdc, SimWatchdog};
use capstan_plant::{CordTruth, ForcedOutputs, Plant, SERVO_MAX_DUTY};
use capstan_rig::hal::{AdcError, Channel, ForceAdc};
use capstan_rig::{force_safe, Rig, RigIo, SafeDuties};
use core::cell::RefCell;
use std::panic::{catch_unwind, AssertUnwindSafe};

/// How long the plant is watched after the panic, µs.
pub const AFTER_PANIC_US: u64 = 300_000;

/// The message of the injected panic.
pub const PANIC_MESSAGE: &str = "injected firmware panic (host-sim)";

/// The force ADC, panicking at its first conversion `after_trigger_us` after the trigger rose.
struct PanickingAdc<'a> {
    inner: SimAdc<'a>,
    plant: &'a RefCell<Plant>,
    after_trigger_us: u64,
}

impl ForceAdc for PanickingAdc<'_> {
    fn read_counts(&mut self, channel: Channel) -> Result<u16, AdcError> {
        let rise = self.plant.borrow().trigger_rise_us(0);
        if rise.is_some_and(|r| time::now_us() >= r + self.after_trigger_us) {
            panic!("{PANIC_MESSAGE}");
        }
        self.inner.read_counts(channel)
    }
}

/// What the plant saw around the panic.
#[derive(Clone, Debug)]
pub struct PanicOutcome {
    /// When the firmware panicked, plant µs.
    pub panic_at_us: u64,
    /// The plant's state at the panic, before the handler ran.
    pub before: CordTruth,
    /// Right after the handler, at the same instant.
    pub after: CordTruth,
    /// Since when the plant has seen the safe state commanded (servo pulse at rest, amplifier
    /// duty 0): `Plant::safe_since_us` at the end.
    pub safe_since_us: Option<u64>,
    /// The servo's horn reached its rest angle (within 0.05°), plant µs.
    pub servo_at_rest_us: Option<u64>,
    /// The drive voltage fell below 1 % of what it was at the panic (the RC filter), plant µs.
    pub drive_below_1pct_us: Option<u64>,
    /// The drive voltage at the panic, V.
    pub drive_v_at_panic: f64,
    /// The plant's state [`AFTER_PANIC_US`] after the panic.
    pub end: CordTruth,
    /// The firmware's records up to the panic.
    pub records: u32,
}

/// Why a panic run did not give a panic.
#[derive(Clone, Debug, PartialEq)]
pub enum PanicRunError {
    /// The run could not be set up.
    Setup(SetupError),
    /// The run ended (or timed out) before the panic was due.
    NoPanic,
}

impl std::fmt::Display for PanicRunError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PanicRunError::Setup(e) => write!(f, "{e}"),
            PanicRunError::NoPanic => f.write_str("the run ended before the panic was due"),
        }
    }
}

impl std::error::Error for PanicRunError {}

/// Run `spec` (its injections are ignored) with the firmware panicking at its first ADC
/// conversion `after_trigger_us` after the trigger, then run the board's panic path on the
/// plant and watch it for [`AFTER_PANIC_US`].
pub fn run_with_panic(
    spec: &RunSpec,
    after_trigger_us: u64,
) -> Result<PanicOutcome, PanicRunError> {
    time::reset(0);
    let setup = PanicRunError::Setup;
    let mut rig = Rig::new(spec.protocol, spec.calibration, spec.limits)
        .map_err(|e| setup(SetupError::Protocol(e)))?;
    // At boot, as `main` does on the board (board_safe::arm).
    let duties = SafeDuties::for_rig(&rig, SERVO_MAX_DUTY);
    let plant = Plant::new_at(spec.plant, &[spec.cord], spec.seed, 0)
        .map_err(|e| setup(SetupError::Plant(e)))?;
    let plant = RefCell::new(plant);
    let c = CordRef::new(&plant, 0);
    let mut io = RigIo {
        servo: ServoPwm(c),
        amp: AmpPwm(c),
        trigger: TriggerPin(c),
        led: LedPin(c),
        button: ButtonPin(c),
        adc: PanickingAdc {
            inner: SimAdc(c),
            plant: &plant,
            after_trigger_us,
        },
        watchdog: SimWatchdog(c),
    };
    let mut sink = VecSink::new(false);
    let limit = time_limit_us(&spec.protocol, &spec.cord);
    let outcome = catch_unwind(AssertUnwindSafe(|| {
        time::block_on_until(capstan_rig::run_once(&mut io, &mut rig, &mut sink), limit)
    }));
    if outcome.is_ok() {
        return Err(PanicRunError::NoPanic);
    }
    // The panic handler, at the instant of the panic.
    let panic_at_us = time::now_us();
    plant.borrow_mut().advance_to(panic_at_us);
    let before = plant.borrow().truth(0);
    let drive_v_at_panic = plant.borrow().drive().drive_v;
    // The servo kept where it is if that releases more than rest (the duty last written).
    let commanded = (before.commanded_pulse_us / 20_000.0 * SERVO_MAX_DUTY as f64).round() as u16;
    force_safe(&mut ForcedOutputs(c), duties.releasing(commanded));
    let after = plant.borrow().truth(0);
    // Nothing drives the plant any more; watch it, 1 ms at a time.
    let rest_deg = {
        let p = plant.borrow();
        let s = &p.config().servo;
        s.characteristic.angle_deg(s.rest_pulse_us)
    };
    let (mut servo_at_rest_us, mut drive_below_1pct_us) = (None, None);
    let mut p = plant.into_inner();
    for k in 0..=AFTER_PANIC_US / 1_000 {
        let t = panic_at_us + k * 1_000;
        p.advance_to(t);
        if servo_at_rest_us.is_none() && (p.truth(0).angle_deg - rest_deg).abs() < 0.05 {
            servo_at_rest_us = Some(t);
        }
        if drive_below_1pct_us.is_none() && p.drive().drive_v < 0.01 * drive_v_at_panic {
            drive_below_1pct_us = Some(t);
        }
    }
    Ok(PanicOutcome {
        panic_at_us,
        before,
        after,
        safe_since_us: p.safe_since_us(0),
        servo_at_rest_us,
        drive_below_1pct_us,
        drive_v_at_panic,
        end: p.truth(0),
        records: sink.log.records,
    })
}
