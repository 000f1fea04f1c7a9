//! The rig as a pure state machine: one call per sample period, inputs in, actuator commands
//! out, records to a sink. No hardware, no clock, no async: `runner.rs` does that.
//!
//! * this file: the state, what the rig commands when nothing runs, one sample's dispatch;
//! * `rig/run.rs`: a run (tare and its bound, the raw log, the supervisor, the end);
//! * `rig/steps.rs`: a run's steps (which is held, its window, its pair);
//! * `rig/idle.rs`: between runs (supervision, homing, the fault latch and its
//!   acknowledgement, the latch a reset leaves);
//! * `rig/commands.rs`: host commands and setup mode.
//!
//! The safety supervisor runs in every phase. Outside a run the servo never moves toward
//! tension without a person: a latched fault freezes homing, and a fault moves the servo only
//! toward release (rest is the end of a run's travel that releases the cord). A run starts
//! only from a press at the rig (the host may arm one, [`ARM_MS`]), on sensitivities a person
//! measured or typed; its tare begins at the press and its drive comes on only after the
//! release (`button.rs`).

use crate::button::{Debouncer, Edge, LONG_PRESS_MS};
use crate::calib::Calibration;
use crate::command::Command;
use crate::force::ForceRun;
use crate::hal::AdcError;
use crate::protocol::{Protocol, ProtocolError};
use crate::record::{FaultKind, LogSink, Record, RunEnd, Sequencer};
use crate::safety::{SafetyLimits, Supervisor};
use crate::settings::Settings;
use crate::setup::Measure;
use steps::Steps;

mod commands;
mod idle;
mod run;
mod steps;

/// Debounce time of the button, ms.
/// (10 ms: longer than contact bounce, short enough that an abort is safe well inside 20 ms.)
pub const DEBOUNCE_MS: u32 = 10;

/// The cord-break checks arm this long after each step to a tension level, ms (the servo has
/// moved and the tensions settled by then).
pub const CORD_CHECK_SETTLE_MS: u32 = 200;

/// How fast the idle rig brings the servo command to rest when it starts away from it (after
/// setup mode, or new settings that moved rest: [`Rig::home_from`]), deg/s. 60° then take 6 s,
/// where the HS-322HD alone would swing there in 0.2 s. Homing is supervised like a run and
/// stops (latched) at a fault.
pub const HOMING_DEG_PER_S: f32 = 10.0;

/// How long a run the host armed (`run`) waits for the press at the rig that starts it, ms.
/// The host never starts the drive: a person at the rig does, within this time, or the arm
/// lapses (and is said so in the log).
pub const ARM_MS: u32 = 30_000;

/// The tare's bound ([`crate::calib::TARE_MAX_N`]: the calibration's, which the zero walk shares).
pub use crate::calib::TARE_MAX_N;

/// `now_us` on the sample grid that runs through `origin_us` (the nearest sample instant).
/// The clock is read a few tens of µs after each tick, and that latency wanders by a µs or so
/// from sample to sample (the work before the read varies): unrounded, a step, the trigger,
/// the end of a run or a live record could slip by a whole sample.
pub(crate) fn on_grid(now_us: u64, origin_us: u64, period_us: u32) -> u64 {
    let period_us = period_us as u64;
    let since = now_us.saturating_sub(origin_us);
    origin_us + (since + period_us / 2) / period_us * period_us
}

/// What the rig reads each sample period.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Inputs {
    /// Monotonic time, µs (any origin).
    pub now_us: u64,
    /// Both force channels, raw counts (T1, T2).
    pub counts: [Result<u16, AdcError>; 2],
    /// The button's raw level: true = pressed.
    pub button_pressed: bool,
    /// A command line from the host, parsed, if one arrived this period.
    pub command: Option<Result<Command, crate::command::CommandError>>,
}

/// What the rig commands each sample period.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outputs {
    /// Servo angle, deg.
    pub servo_deg: f32,
    /// The servo gets pulses. False: none at all (the servo is unpowered and holds nothing:
    /// the cord back-drives it toward release), after a reset that was not a clean power-up,
    /// until a person acknowledges it.
    pub servo_pulses: bool,
    /// Power amplifier control voltage, V.
    pub amp_control_v: f32,
    /// Logger trigger line.
    pub trigger: bool,
    /// Status LED.
    pub led: bool,
    /// Set on the sample the run ended (normally or by a fault).
    pub finished: Option<RunEnd>,
    /// The host asked to keep these settings in flash: the runner writes them, then reports
    /// with [`Rig::stored`].
    pub store: Option<Settings>,
    /// The settings changed this sample (a host command), or the servo's pulses were switched
    /// on or off: duties must be recomputed.
    pub settings_changed: bool,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Phase {
    /// Waiting for the button (LED blinks slowly). After a fault, `latched` holds it (LED
    /// blinks fast) until a press acknowledges it; only the press after that starts a run.
    Idle { latched: Option<FaultKind> },
    /// Sampling the preloaded cord with the capstan stopped. `waiting`: the tare is done, but
    /// the press that started the run has not been released: the drive waits for it (the
    /// run's clock held), until [`LONG_PRESS_MS`], when the run is cancelled.
    Tare {
        sum: [u64; 2],
        n: u32,
        waiting: bool,
    },
    /// Setup mode: the servo where the host jogged it, amplifier at 0 V, live values.
    Setup {
        /// Servo angle commanded now, deg: on its way to `target_deg` at
        /// [`crate::setup::SETUP_DEG_PER_S`].
        servo_deg: f32,
        /// Where the host asked the servo to go, deg.
        target_deg: f32,
        measure: Option<Measure>,
        /// The zeros measured in this setup session (counts) and the servo angle they were
        /// measured at (deg): `weigh` measures from the zero in force, so it is refused unless
        /// that is this one (a zero from flash, `defaults` or a `set` may be days old, or never
        /// measured) with the servo where it was (the cord's pull would add to the weight).
        zeroed: Option<([f32; 2], f32)>,
        /// The sample on which setup mode began: the origin of its sample grid.
        origin_us: u64,
        next_live_us: u64,
    },
    /// Running the protocol: the step being held and its conditioning.
    Run(Steps),
}

/// The rig: protocol, calibration and the state of the current run.
#[derive(Clone, Debug)]
pub struct Rig {
    /// The firmware's built-in settings (`defaults` goes back to them).
    defaults: Settings,
    protocol: Protocol,
    cal: Calibration,
    /// The zeros of the settings in force: a run's tare may move them by [`TARE_MAX_N`] for
    /// that run only.
    zeros: [f32; 2],
    limits: SafetyLimits,
    phase: Phase,
    button: Debouncer,
    seq: Sequencer,
    supervisor: Supervisor,
    runs: u32,
    pairs: u32,
    press_us: u64,
    /// The run's last sample, µs from the press, on its grid.
    elapsed_us: u64,
    /// The sample period, µs: fixed by `new` (settings with other rates are refused).
    period_us: u32,
    /// Samples until the next raw record of the run (a countdown, not a division per sample).
    raw_in: u32,
    /// Servo command while idle, deg: the rest angle, or on its way there ([`Rig::home_from`]).
    idle_servo_deg: f32,
    /// No servo pulses: set at a boot after a reset that was not a clean power-up
    /// ([`Rig::boot_latched`]), cleared by the person who acknowledges the fault.
    limp: bool,
    /// Where the settings in force came from (what `show` reports).
    settings_source: crate::record::SettingsSource,
    /// A flash write held the loop: setup mode re-anchors its sample grid on the next sample.
    reanchor: bool,
    /// The run in progress began at a press that has not been released yet.
    awaiting_release: bool,
    /// The host armed a run (`run`): until then (µs) the LED says so, and a press starts it.
    armed_until_us: Option<u64>,
    /// [`Rig::use_settings`] ran since the last sample's outputs.
    settings_changed: bool,
    /// Force control's controller (used in force mode; made anew at every run's start).
    force: ForceRun,
}

impl Rig {
    /// A rig ready to run `protocol`; refused if the protocol is invalid. (A calibration under
    /// which the over-force check could not trip is refused at each run's tare.)
    pub fn new(
        protocol: Protocol,
        cal: Calibration,
        limits: SafetyLimits,
    ) -> Result<Self, ProtocolError> {
        protocol.validate()?;
        let debounce = (DEBOUNCE_MS * protocol.sample_hz / 1000) as u16;
        let long = LONG_PRESS_MS * (protocol.sample_hz / 1000);
        Ok(Rig {
            defaults: Settings {
                protocol,
                calibration: cal,
            },
            protocol,
            cal,
            zeros: cal.zeros(),
            limits,
            phase: Phase::Idle { latched: None },
            button: Debouncer::new(debounce, long),
            seq: Sequencer::default(),
            supervisor: Supervisor::new(limits),
            runs: 0,
            pairs: 0,
            press_us: 0,
            elapsed_us: 0,
            period_us: protocol.sample_period_us(),
            raw_in: 0,
            idle_servo_deg: protocol.rest_deg,
            limp: false,
            settings_source: crate::record::SettingsSource::DefaultsNoRecord,
            reanchor: false,
            awaiting_release: false,
            armed_until_us: None,
            settings_changed: false,
            force: ForceRun::new(&protocol, &limits),
        })
    }

    /// The servo command is at `angle_deg` (e.g. where setup mode left it): the idle rig
    /// brings it to rest at [`HOMING_DEG_PER_S`], supervised, and takes no press until it is
    /// there. Ignored during a run. Without this call the rig assumes the servo is at rest
    /// (where every run, fault and panic leaves it).
    pub fn home_from(&mut self, angle_deg: f32) {
        if self.is_running() || !angle_deg.is_finite() {
            return;
        }
        // Not `f32::clamp` (its assertion links float formatting into the board image).
        #[allow(clippy::manual_clamp)]
        let angle_deg = if angle_deg < 0.0 {
            0.0
        } else if angle_deg > 180.0 {
            180.0
        } else {
            angle_deg
        };
        // Within a few PWM counts of rest (a duty read back through the map) is rest.
        self.idle_servo_deg = if (angle_deg - self.protocol.rest_deg).abs() < 0.1 {
            self.protocol.rest_deg
        } else {
            angle_deg
        };
    }

    /// True while the idle servo command is still on its way to rest.
    pub fn is_homing(&self) -> bool {
        self.idle_servo_deg != self.protocol.rest_deg
    }

    /// The fault latched until a person acknowledges it (a run's, one seen while idle or in
    /// setup mode, or one a reset left).
    pub fn latched_fault(&self) -> Option<FaultKind> {
        match self.phase {
            Phase::Idle { latched } => latched,
            _ => None,
        }
    }

    /// True while the servo gets no pulses (after a reset, until acknowledged).
    pub fn is_limp(&self) -> bool {
        self.limp
    }

    /// The protocol in force.
    pub fn protocol(&self) -> &Protocol {
        &self.protocol
    }

    /// The calibration in force (during a run, with the zeros of its tare).
    pub fn calibration(&self) -> &Calibration {
        &self.cal
    }

    /// The safety limits.
    pub fn limits(&self) -> &SafetyLimits {
        &self.limits
    }

    /// True while a run is in progress (tare included).
    pub fn is_running(&self) -> bool {
        matches!(self.phase, Phase::Tare { .. } | Phase::Run { .. })
    }

    /// True in setup mode.
    pub fn is_in_setup(&self) -> bool {
        matches!(self.phase, Phase::Setup { .. })
    }

    /// True when nothing moves: idle, the servo commanded to rest (not homing, not limp).
    pub fn is_at_rest(&self) -> bool {
        matches!(self.phase, Phase::Idle { .. }) && !self.is_homing() && !self.limp
    }

    /// What the idle rig commands now: [`Rig::safe_outputs`] with the servo where homing has
    /// brought it (at rest unless [`Rig::home_from`] was called). The runner writes this at
    /// boot, before the first sample.
    pub fn idle_outputs(&self) -> Outputs {
        Outputs {
            servo_deg: self.idle_servo_deg,
            ..self.safe_outputs()
        }
    }

    /// The state outputs hold when nothing runs: servo at rest (no pulses while limp),
    /// amplifier off, trigger low.
    pub fn safe_outputs(&self) -> Outputs {
        Outputs {
            servo_deg: self.protocol.rest_deg,
            servo_pulses: !self.limp,
            amp_control_v: 0.0,
            trigger: false,
            led: false,
            finished: None,
            store: None,
            settings_changed: false,
        }
    }

    /// True while a run the host armed waits for its press.
    pub fn is_armed(&self) -> bool {
        self.armed_until_us.is_some()
    }

    /// One sample period.
    #[inline]
    pub fn step(&mut self, inp: &Inputs, sink: &mut impl LogSink) -> Outputs {
        let mut edge = self.button.step(inp.button_pressed);
        // A run stops at the press's edge (a button that sticks stops it too).
        let mut abort = edge == Edge::Pressed;
        let mut store = None;
        // Only a command changes the mode outside the run's own course.
        let before = core::mem::discriminant(&self.phase);
        match inp.command {
            Some(Ok(Command::Abort)) if self.is_running() => {
                // Answered now; the run then ends as by the button (fault `abort`, `run_end`).
                // 1: a run's abort (0 would be setup mode's).
                self.reply(sink, crate::command::CommandKind::Abort, Ok([1.0, 0.0]));
                abort = true;
            }
            Some(cmd) => store = self.command(cmd, inp.now_us, sink),
            None => {}
        }
        let changed_phase = core::mem::discriminant(&self.phase) != before;
        if (changed_phase || store.is_some()) && !self.is_running() && edge == Edge::Pressed {
            // A press in the very sample a command changed the mode, or asked for a flash
            // write, must not start a run on top of it: the person presses again.
            self.button.consume();
            edge = Edge::None;
        }
        let mut out = self.step_phase(inp, edge, abort, sink);
        // (`step_phase` never asks for a write: the settings are copied only when there are some.)
        if store.is_some() {
            out.store = store;
        }
        out.settings_changed = core::mem::take(&mut self.settings_changed);
        out
    }

    #[inline]
    fn step_phase(
        &mut self,
        inp: &Inputs,
        edge: Edge,
        abort: bool,
        sink: &mut impl LogSink,
    ) -> Outputs {
        // One call of `step_running` (the sample path of a run), for the run's samples and the
        // press that starts one alike.
        let (edge, abort) = match self.phase {
            Phase::Idle { latched } => match self.step_idle(inp, latched, edge, sink) {
                Some(out) => return out,
                // The press that started the run does not abort it.
                None => (Edge::None, false),
            },
            Phase::Setup { .. } => return self.step_setup(inp, edge, sink),
            _ => (edge, abort),
        };
        self.step_running(inp, edge, abort, sink)
    }

    /// Both channels in newtons (NaN where a conversion failed).
    #[inline]
    fn forces(&self, inp: &Inputs) -> [f32; 2] {
        [
            inp.counts[0].map_or(f32::NAN, |c| self.cal.t1.newtons(c as f32)),
            inp.counts[1].map_or(f32::NAN, |c| self.cal.t2.newtons(c as f32)),
        ]
    }

    fn emit(&mut self, sink: &mut impl LogSink, record: Record) {
        sink.emit(self.seq.next_seq(), &record);
    }

    /// µs since the trigger's rising edge.
    fn since_trigger_us(&self, elapsed_us: u64) -> i64 {
        elapsed_us as i64 - self.protocol.trigger_at_ms() as i64 * 1000
    }

    /// The servo command moved only toward release: `angle_deg` or rest, whichever releases
    /// more (rest is the longest pulse of a run: a larger angle releases).
    fn toward_release(&self, angle_deg: f32) -> f32 {
        if angle_deg > self.protocol.rest_deg {
            angle_deg
        } else {
            self.protocol.rest_deg
        }
    }
}
