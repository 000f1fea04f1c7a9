//! A bench session on the simulated board: the board's boot (settings from flash, or the
//! defaults, said in a `settings` record; the latch a reset left, `capstan_rig::reset`), then
//! `capstan_rig::runner::serve` with a host sending command lines, a person hanging known weights
//! and pressing the button, power cycles and a loop that hangs until the watchdog resets the
//! chip, all on one plant and one flash, in virtual time. It is what `capstan rig --sim` drives
//! and what the setup and safety tests run: the same commands the board takes over RTT.
//!
//! A reset releases every pin (no servo pulses, amplifier and trigger low), as on the board;
//! what survives it is the board's: the flash, and across a watchdog reset (not a power cycle)
//! the watchdog's scratch registers, here [`SessionOutput::resets`]' latch words.

use crate::flash::RamFlash;
use crate::run::{sample_plant, time_limit_us, SetupError, TraceSample};
use crate::time;
use capstan_plant::hal::CordRef;
use capstan_plant::{
    rig_io, CordSetup, ForcedOutputs, Injection, Plant, PlantConfig, SERVO_MAX_DUTY,
};
use capstan_rig::hal::{Channel, Console};
use capstan_rig::record::{LogSink, Record};
use capstan_rig::reset::{latch_word, ResetCause};
use capstan_rig::runner::{serve, WATCHDOG_MS};
use capstan_rig::safety::SafetyLimits;
use capstan_rig::store::SettingsStore;
use capstan_rig::{Calibration, Protocol, Rig, SafeDuties};
use core::cell::{Cell, RefCell};
use embassy_futures::select::{select3, Either3};
use embassy_time::{Duration, Timer};
use std::collections::VecDeque;

/// The settings range of the simulated board's flash: all of it (four 4 KiB pages).
pub const FLASH_PAGES: usize = 4;

/// Longest a command may wait for its reply, virtual ms (a store erases pages: well under).
pub const REPLY_TIMEOUT_MS: u64 = 5_000;

/// One thing that happens at the bench.
#[derive(Clone, Debug, PartialEq)]
pub enum Step {
    /// The host sends a command line and waits for its reply.
    Send(String),
    /// Time passes, ms.
    Wait(u32),
    /// A known weight (N) hangs on a sensor from now on (0: nothing hangs there).
    Hang(Channel, f64),
    /// The button is pressed for this long, ms.
    Press(u32),
    /// The button is pressed for this long, ms, if the last command sent was answered without
    /// a refusal (the person at the rig presses to start the run the host armed; not when the
    /// board refused to arm it).
    PressIfArmed(u32),
    /// Wait for the run in progress to end (or for the limit of its protocol).
    UntilRunEnd,
    /// The board is power cycled: every pin released, the flash and the plant stay, the
    /// watchdog's scratch registers are lost; it boots again at once.
    Reset,
    /// The firmware's loop hangs (a conversion that never completes, a lockup): the pins keep
    /// what they had until the watchdog resets the chip [`WATCHDOG_MS`] later (the worst case:
    /// the hang right after a feed), which releases them; the board boots [`BOOT_MS`] later
    /// with the scratch registers kept.
    Freeze,
    /// The button is held down from now for this long, ms, and the next step follows at once
    /// (a button held across a reset, or stuck).
    HoldButton(u32),
    /// A sensor is fitted the wrong way round from now on: a tension lowers its reading.
    ReverseSensor(Channel),
    /// A sensor's true sensitivity is this factor times its nominal one from now on (counts
    /// per newton; `capstan rig --sim` draws one per sensor, hidden from the firmware). Give
    /// it before any weight is hung.
    ScaleSensor(Channel, f64),
    /// The RUN pin pulled low (a reset button, a supply supervisor): the whole chip resets,
    /// every pin released, the scratch registers lost; it boots again [`BOOT_MS`] later.
    RunPin,
    /// The firmware panics now: the panic handler makes the outputs safe through the
    /// registers (`capstan_rig::force_safe`, as `board_safe.rs` does) and resets the chip through
    /// the watchdog at once (forced; the scratch registers kept); it boots [`BOOT_MS`] later.
    Panic,
    /// A fault of the rig's parts, from now on (the plant's injections, e.g. a frozen sensor,
    /// a cord that parts, a stalled servo).
    Inject(capstan_plant::InjectionKind),
}

/// From a reset to the firmware's first sample on the simulated board, ms (the RP2040 boots
/// its clocks and loads the settings in ~1 ms; the pins stay released meanwhile).
pub const BOOT_MS: u64 = 2;

/// The simulated bench.
#[derive(Clone, Debug)]
pub struct SessionSpec {
    /// The rig's constants.
    pub plant: PlantConfig,
    /// The cord (its `press_at_us` is ignored: presses are steps).
    pub cord: CordSetup,
    /// The firmware's built-in protocol.
    pub protocol: Protocol,
    /// The firmware's built-in calibration.
    pub calibration: Calibration,
    /// The firmware's safety limits.
    pub limits: SafetyLimits,
    /// Seed of the plant.
    pub seed: u64,
    /// Sample the plant's true state every this many ms into [`SessionOutput::trace`] (0 =
    /// never).
    pub trace_every_ms: u32,
    /// Faults of the rig's parts, timed from the trigger's first rising edge (as a run's).
    pub injections: Vec<Injection>,
}

impl Default for SessionSpec {
    fn default() -> Self {
        SessionSpec {
            plant: PlantConfig::default(),
            cord: CordSetup::default(),
            protocol: Protocol::default(),
            calibration: Calibration::default(),
            limits: SafetyLimits::default(),
            seed: 1,
            trace_every_ms: 0,
            injections: Vec::new(),
        }
    }
}

/// One record as the host received it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Event {
    /// Virtual time, µs since the session began.
    pub t_us: u64,
    /// Boots so far (1 = the first).
    pub boot: u32,
    /// The record's sequence number.
    pub seq: u32,
    /// The record.
    pub record: Record,
}

/// What a session produced.
#[derive(Clone, Debug)]
pub struct SessionOutput {
    /// Every record, in order.
    pub events: Vec<Event>,
    /// The flash afterwards.
    pub flash: RamFlash,
    /// Commands that got no reply in [`REPLY_TIMEOUT_MS`].
    pub unanswered: Vec<String>,
    /// The plant afterwards (its truth, servo events, sensor zeros).
    pub plant: Plant,
    /// Each reset: when (µs), why the next boot saw it, and the latch word it found.
    pub resets: Vec<(u64, ResetCause, u32)>,
    /// The plant's true state every `trace_every_ms`, through resets too.
    pub trace: Vec<TraceSample>,
    /// Steps done: all of them, or those up to where the observer stopped the session
    /// ([`run_session_observed`]).
    pub steps_done: usize,
}

impl SessionOutput {
    /// The records of one kind, via `pick`.
    pub fn records<T>(&self, pick: impl Fn(&Record) -> Option<T>) -> Vec<T> {
        self.events.iter().filter_map(|e| pick(&e.record)).collect()
    }

    /// The settings report of boot `boot` (1 = the first), if it made one.
    pub fn settings_at_boot(&self, boot: u32) -> Option<capstan_rig::record::SettingsReport> {
        self.events
            .iter()
            .filter(|e| e.boot == boot)
            .find_map(|e| match e.record {
                Record::Settings(s) => Some(s),
                _ => None,
            })
    }
}

/// The records, shared by the board's sink and the host.
struct Shared {
    events: RefCell<Vec<Event>>,
    console: RefCell<VecDeque<u8>>,
    boot: core::cell::Cell<u32>,
    /// The weights hanging on the sensors, N (they stay across a reset: they are the rig's).
    hung: Cell<[f64; 2]>,
}

struct Sink<'a>(&'a Shared);

impl LogSink for Sink<'_> {
    fn emit(&mut self, seq: u32, record: &Record) {
        let boot = self.0.boot.get();
        let e = Event {
            t_us: time::now_us(),
            boot,
            seq,
            record: *record,
        };
        self.0.events.borrow_mut().push(e);
    }
}

struct HostConsole<'a>(&'a Shared);

impl Console for HostConsole<'_> {
    fn read_byte(&mut self) -> Option<u8> {
        self.0.console.borrow_mut().pop_front()
    }
}

/// Run `steps` at the simulated bench with `flash` in the board.
pub fn run_session(
    spec: &SessionSpec,
    flash: RamFlash,
    steps: &[Step],
) -> Result<SessionOutput, SetupError> {
    run_session_observed(spec, flash, steps, &mut |_, _| true)
}

/// What the host has after each step: how many steps are done, and every record so far;
/// `false` ends the session there (a host that streams the records as they come, and stops
/// between steps on a signal).
pub type Observer<'a> = &'a mut dyn FnMut(usize, &[Event]) -> bool;

/// [`run_session`], calling `observe` after every step that is not a reset or a freeze.
pub fn run_session_observed(
    spec: &SessionSpec,
    flash: RamFlash,
    steps: &[Step],
    observe: Observer<'_>,
) -> Result<SessionOutput, SetupError> {
    time::reset(0);
    let cord = CordSetup {
        press_at_us: None,
        ..spec.cord
    };
    let mut plant = Plant::new_at(spec.plant, &[cord], spec.seed, 0).map_err(SetupError::Plant)?;
    for inj in &spec.injections {
        plant.inject(*inj).map_err(SetupError::Plant)?;
    }
    let plant = RefCell::new(plant);
    let shared = Shared {
        events: RefCell::new(Vec::new()),
        console: RefCell::new(VecDeque::new()),
        boot: core::cell::Cell::new(0),
        hung: Cell::new([0.0; 2]),
    };
    let range = 0..(FLASH_PAGES * crate::flash::ERASE_BYTES) as u32;
    let mut store = SettingsStore::new(flash, range).expect("whole pages");
    let mut unanswered = Vec::new();
    let run_limit_us = time_limit_us(&spec.protocol, &cord);
    let trace = RefCell::new(Vec::new());
    // The watchdog's scratch register 1: the latch word, kept across a watchdog reset.
    let scratch = Cell::new(0u32);
    let mut cause = ResetCause::PowerOn;
    let mut resets = Vec::new();
    let mut rest = steps;
    let mut done_total = 0;
    let observe = RefCell::new(observe);
    loop {
        shared.boot.set(shared.boot.get() + 1);
        shared.console.borrow_mut().clear();
        let mut rig =
            Rig::new(spec.protocol, spec.calibration, spec.limits).map_err(SetupError::Protocol)?;
        let board = board(&plant, &shared, &mut store, &mut rig, cause, &scratch);
        let host = host(
            &shared,
            &plant,
            rest,
            (&mut unanswered, run_limit_us),
            (done_total, &observe),
        );
        let probe = probe(&plant, spec.trace_every_ms, &trace);
        let limit = time::now_us() + steps_limit_us(rest, run_limit_us);
        let (done, stopped) = match time::block_on_until(select3(board, host, probe), limit) {
            Ok(Either3::Second(done)) => done,
            _ => (rest.len(), false),
        };
        rest = &rest[done..];
        done_total += done;
        if stopped {
            break;
        }
        cause = match rest.first() {
            Some(Step::Reset) => {
                release_pins(&plant);
                scratch.set(0);
                ResetCause::PowerOn
            }
            Some(Step::RunPin) => {
                release_pins(&plant);
                scratch.set(0);
                watch(&plant, BOOT_MS, spec.trace_every_ms, &trace);
                ResetCause::RunPin
            }
            Some(Step::Freeze) => {
                watch(&plant, WATCHDOG_MS as u64, spec.trace_every_ms, &trace);
                release_pins(&plant);
                watch(&plant, BOOT_MS, spec.trace_every_ms, &trace);
                ResetCause::Watchdog
            }
            Some(Step::Panic) => {
                panic_path(&plant, &rig);
                release_pins(&plant);
                watch(&plant, BOOT_MS, spec.trace_every_ms, &trace);
                ResetCause::Forced
            }
            _ => break,
        };
        resets.push((time::now_us(), cause, scratch.get()));
        rest = &rest[1..];
        done_total += 1;
    }
    let mut plant = plant.into_inner();
    plant.advance_to(time::now_us());
    Ok(SessionOutput {
        events: shared.events.into_inner(),
        flash: store.into_flash(),
        unanswered,
        plant,
        resets,
        trace: trace.into_inner(),
        steps_done: done_total,
    })
}

/// The board from a reset on: its settings, the latch the reset left, then `serve`, keeping
/// the latch word in its scratch register every sample (as `firmware/board/src/main.rs` does).
async fn board(
    plant: &RefCell<Plant>,
    shared: &Shared,
    store: &mut SettingsStore<RamFlash>,
    rig: &mut Rig,
    cause: ResetCause,
    scratch: &Cell<u32>,
) {
    let mut sink = Sink(shared);
    let mut io = rig_io(plant, 0);
    store.load_into(rig, &mut sink).await;
    capstan_rig::reset::boot(rig, cause, scratch.get(), &mut sink);
    scratch.set(latch_word(rig));
    let _ = io.boot(rig);
    let keep = |_: &capstan_rig::rig::Outputs, rig: &Rig| {
        scratch.set(latch_word(rig));
        None::<()>
    };
    let _ = serve(
        &mut io,
        rig,
        &mut sink,
        &mut HostConsole(shared),
        store,
        keep,
    )
    .await;
}

/// The plant's truth every `every_ms` into `trace` (never ends; nothing if 0).
async fn probe(plant: &RefCell<Plant>, every_ms: u32, trace: &RefCell<Vec<TraceSample>>) {
    if every_ms == 0 {
        return core::future::pending().await;
    }
    let every = Duration::from_millis(every_ms as u64);
    sample_plant(plant, every, |p| {
        trace.borrow_mut().push(TraceSample::of(p))
    })
    .await
}

/// Nothing drives the plant for `ms` (a hung loop, a chip booting): time passes, traced.
fn watch(plant: &RefCell<Plant>, ms: u64, every_ms: u32, trace: &RefCell<Vec<TraceSample>>) {
    let end = time::now_us() + ms * 1000;
    let _ = time::block_on_until(Timer::at(embassy_time::Instant::from_micros(end)), end);
    if every_ms > 0 {
        // (The probe samples on the session's grid: fill the gap on the same grid.)
        let mut p = plant.borrow_mut();
        let last = trace.borrow().last().map_or(0, |s| s.t_us);
        let mut t = last + every_ms as u64 * 1000;
        while t <= end {
            p.advance_to(t);
            trace.borrow_mut().push(TraceSample::of(&p));
            t += every_ms as u64 * 1000;
        }
    }
    plant.borrow_mut().advance_to(end);
}

/// A reset: every output pin an input. The servo gets no pulses; the pull-downs hold the
/// amplifier's control input and the trigger low (the control input falls through the filter
/// and the pull-down, `MotorConfig::amp_filter_released_tau_s`).
fn release_pins(plant: &RefCell<Plant>) {
    let mut p = plant.borrow_mut();
    p.advance_to(time::now_us());
    p.set_servo_duty(0, 0, SERVO_MAX_DUTY);
    p.release_amp(0);
    p.set_trigger(0, false);
}

/// What the board's panic handler does first: `force_safe` on the pins, with the rest duty
/// computed from the rig (`board_safe::arm`) and the servo kept where it is if that releases
/// more (`SafeDuties::releasing`, with the duty last written).
fn panic_path(plant: &RefCell<Plant>, rig: &Rig) {
    let commanded = {
        let mut p = plant.borrow_mut();
        p.advance_to(time::now_us());
        let pulse_us = p.truth(0).commanded_pulse_us;
        (pulse_us / p.config().servo.frame_us as f64 * SERVO_MAX_DUTY as f64).round() as u16
    };
    let duties = SafeDuties::for_rig(rig, SERVO_MAX_DUTY).releasing(commanded);
    capstan_rig::force_safe(&mut ForcedOutputs(CordRef::new(plant, 0)), duties);
}

/// Virtual time the steps may take at most.
fn steps_limit_us(steps: &[Step], run_limit_us: u64) -> u64 {
    let each = |s: &Step| match s {
        Step::Send(_) => REPLY_TIMEOUT_MS * 1000,
        Step::Wait(ms) | Step::Press(ms) | Step::PressIfArmed(ms) => *ms as u64 * 1000,
        Step::Freeze => (WATCHDOG_MS as u64 + BOOT_MS) * 1000,
        Step::RunPin | Step::Panic => BOOT_MS * 1000,
        Step::UntilRunEnd => run_limit_us,
        _ => 0,
    };
    steps.iter().map(each).sum::<u64>() + 1_000_000
}

/// The person and the host at the bench: do the steps up to a reset; how many were done, and
/// whether the observer stopped the session (`before`: steps done before these).
async fn host(
    shared: &Shared,
    plant: &RefCell<Plant>,
    steps: &[Step],
    (unanswered, run_limit_us): (&mut Vec<String>, u64),
    (before, observe): (usize, &RefCell<Observer<'_>>),
) -> (usize, bool) {
    // Let the board boot and settle (and a homing servo reach rest) first.
    Timer::after(Duration::from_millis(50)).await;
    let mut last_refused = false;
    for (i, step) in steps.iter().enumerate() {
        match step {
            Step::Send(line) => {
                let seen = shared.events.borrow().len();
                shared
                    .console
                    .borrow_mut()
                    .extend(line.bytes().chain([b'\n']));
                let replied = until(shared, seen, REPLY_TIMEOUT_MS * 1000, |r| {
                    matches!(r, Record::Reply(_))
                })
                .await;
                if !replied {
                    unanswered.push(line.clone());
                }
                last_refused = shared.events.borrow()[seen..]
                    .iter()
                    .any(|e| matches!(e.record, Record::Reply(r) if r.error.is_some()));
            }
            Step::PressIfArmed(_) if last_refused => {}
            Step::Wait(ms) => Timer::after(Duration::from_millis(*ms as u64)).await,
            Step::Hang(ch, n) => {
                let k = *ch as usize;
                let mut hung = shared.hung.get();
                plant.borrow_mut().hang(0, *ch, n - hung[k]);
                hung[k] = *n;
                shared.hung.set(hung);
            }
            Step::Press(ms) | Step::PressIfArmed(ms) => {
                let now = time::now_us();
                plant.borrow_mut().press(0, now, *ms as u64 * 1000);
                Timer::after(Duration::from_millis(*ms as u64)).await;
            }
            Step::ReverseSensor(ch) => plant.borrow_mut().reverse_sensor(0, *ch),
            Step::Inject(kind) => inject_now(plant, *kind),
            Step::ScaleSensor(ch, factor) => plant.borrow_mut().scale_sensor(0, *ch, *factor),
            Step::HoldButton(ms) => {
                let now = time::now_us();
                plant.borrow_mut().press(0, now, *ms as u64 * 1000);
            }
            Step::UntilRunEnd => {
                let seen = shared.events.borrow().len();
                until(shared, seen, run_limit_us, |r| {
                    matches!(r, Record::RunEnd(_))
                })
                .await;
            }
            Step::Reset | Step::Freeze | Step::RunPin | Step::Panic => return (i, false),
        }
        let go_on = (observe.borrow_mut())(before + i + 1, &shared.events.borrow());
        if !go_on {
            return (i + 1, true);
        }
    }
    (steps.len(), false)
}

/// `kind` strikes the rig now, whatever the trigger did.
fn inject_now(plant: &RefCell<Plant>, kind: capstan_plant::InjectionKind) {
    let mut p = plant.borrow_mut();
    p.advance_to(time::now_us());
    p.strike(0, kind);
}

/// Wait until a record after the first `seen` matches, checking every ms; false at the timeout.
async fn until(
    shared: &Shared,
    seen: usize,
    timeout_us: u64,
    hit: impl Fn(&Record) -> bool,
) -> bool {
    let end = time::now_us() + timeout_us;
    while time::now_us() < end {
        if shared.events.borrow()[seen..]
            .iter()
            .any(|e| hit(&e.record))
        {
            return true;
        }
        Timer::after(Duration::from_millis(1)).await;
    }
    false
}
