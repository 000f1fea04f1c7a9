//! The rig as a pure state machine: one call per sample period, inputs in, actuator commands
//! out, records to a sink. No hardware, no clock, no async: `runner.rs` does that.

use crate::button::Debouncer;
use crate::calib::Calibration;
use crate::command::{Command, CommandError};
use crate::condition::Window;
use crate::hal::AdcError;
use crate::protocol::{Protocol, ProtocolError};
use crate::record::{
    Fault, FaultKind, LogSink, RawSample, Record, RunEnd, RunStart, Sequencer, StepPair,
};
use crate::safety::{SafetyInput, SafetyLimits, Supervisor};
use crate::settings::Settings;
use crate::setup::Measure;

mod commands;

/// Debounce time of the button, ms.
/// (10 ms: longer than contact bounce, short enough that an abort is safe well inside 20 ms.)
pub const DEBOUNCE_MS: u32 = 10;

/// The cord-break checks arm this long after each step to a tension level, ms (the servo has
/// moved and the tensions settled by then).
pub const CORD_CHECK_SETTLE_MS: u32 = 200;

/// How fast the idle rig brings the servo command to rest when it starts away from it (after a
/// reset that left the horn elsewhere: [`Rig::home_from`]), deg/s. 60° then take 6 s, where
/// the HS-322HD alone would swing there in 0.2 s.
pub const HOMING_DEG_PER_S: f32 = 10.0;

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
    pub command: Option<Result<Command, CommandError>>,
}

/// What the rig commands each sample period.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outputs {
    /// Servo angle, deg.
    pub servo_deg: f32,
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
    /// The settings changed this sample (a host command): duties must be recomputed.
    pub settings_changed: bool,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Phase {
    /// Waiting for the button (LED blinks slowly). After a fault, `latched` holds it (LED
    /// blinks fast) until a press acknowledges it; only the press after that starts a run.
    Idle { latched: Option<FaultKind> },
    /// Sampling the preloaded cord with the capstan stopped.
    Tare { sum: [u64; 2], n: u32 },
    /// Setup mode: the servo where the host jogged it, amplifier at 0 V, live values.
    Setup {
        /// Servo angle commanded now, deg: on its way to `target_deg` at
        /// [`crate::setup::SETUP_DEG_PER_S`].
        servo_deg: f32,
        /// Where the host asked the servo to go, deg.
        target_deg: f32,
        measure: Option<Measure>,
        /// The sample on which setup mode began: the origin of its sample grid.
        origin_us: u64,
        next_live_us: u64,
    },
    /// Running the protocol; `step` is the step being held, `window` its conditioning.
    Run {
        step: u32,
        window: Window,
        /// The step's pair is emitted on the last sample before this, µs from the press (the
        /// end of its window; `u64::MAX`: no pair to come in this step).
        pair_due_us: u64,
        /// When the next step starts, ms from the press (`u32::MAX`: the run is over). The
        /// step is worked out anew only then, not with a division every sample.
        next_ms: u32,
        /// From when the step's level is held ([`Rig::level_held`]), ms (`u32::MAX`: never).
        armed_ms: u32,
        /// The step's servo angle, deg.
        servo_deg: f32,
    },
}

/// The rig: protocol, calibration and the state of the current run.
#[derive(Clone, Debug)]
pub struct Rig {
    /// The firmware's built-in settings (`defaults` goes back to them).
    defaults: Settings,
    protocol: Protocol,
    cal: Calibration,
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
    /// Where the settings in force came from (what `show` reports).
    settings_source: crate::record::SettingsSource,
    /// A flash write held the loop: setup mode re-anchors its sample grid on the next sample.
    reanchor: bool,
    /// [`Rig::use_settings`] ran since the last sample's outputs.
    settings_changed: bool,
}

impl Rig {
    /// A rig ready to run `protocol`; refused if the protocol is invalid.
    pub fn new(
        protocol: Protocol,
        cal: Calibration,
        limits: SafetyLimits,
    ) -> Result<Self, ProtocolError> {
        protocol.validate()?;
        let debounce = (DEBOUNCE_MS * protocol.sample_hz / 1000) as u16;
        Ok(Rig {
            defaults: Settings {
                protocol,
                calibration: cal,
            },
            protocol,
            cal,
            limits,
            phase: Phase::Idle { latched: None },
            button: Debouncer::new(debounce),
            seq: Sequencer::default(),
            supervisor: Supervisor::new(limits),
            runs: 0,
            pairs: 0,
            press_us: 0,
            elapsed_us: 0,
            period_us: protocol.sample_period_us(),
            raw_in: 0,
            idle_servo_deg: protocol.rest_deg,
            settings_source: crate::record::SettingsSource::DefaultsNoRecord,
            reanchor: false,
            settings_changed: false,
        })
    }

    /// The servo is believed to be at `angle_deg` (e.g. the last command before a reset): the
    /// idle rig starts its command there and brings it to rest at [`HOMING_DEG_PER_S`]; a press
    /// is not accepted until it is there. Ignored during a run. Without this call the rig
    /// assumes the servo is at rest (where every run, fault and panic leaves it).
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

    /// The fault that ended the last run, while it waits to be acknowledged by a press.
    pub fn latched_fault(&self) -> Option<FaultKind> {
        match self.phase {
            Phase::Idle { latched } => latched,
            _ => None,
        }
    }

    /// The protocol in force.
    pub fn protocol(&self) -> &Protocol {
        &self.protocol
    }

    /// The calibration in force (changed by each tare).
    pub fn calibration(&self) -> &Calibration {
        &self.cal
    }

    /// True while a run is in progress (tare included).
    pub fn is_running(&self) -> bool {
        matches!(self.phase, Phase::Tare { .. } | Phase::Run { .. })
    }

    /// True in setup mode.
    pub fn is_in_setup(&self) -> bool {
        matches!(self.phase, Phase::Setup { .. })
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

    /// The state outputs hold when nothing runs: servo at rest, amplifier off, trigger low.
    pub fn safe_outputs(&self) -> Outputs {
        Outputs {
            servo_deg: self.protocol.rest_deg,
            amp_control_v: 0.0,
            trigger: false,
            led: false,
            finished: None,
            store: None,
            settings_changed: false,
        }
    }

    /// One sample period.
    // Inlined on the host, with `step_phase` and `step_running`, into the simulator's sample
    // loop (its one hot call site there): the call returned the outputs through memory and
    // saved and restored six registers every sample. The board's image is unchanged.
    #[cfg_attr(not(target_os = "none"), inline(always))]
    pub fn step(&mut self, inp: &Inputs, sink: &mut impl LogSink) -> Outputs {
        let mut pressed = self.button.step(inp.button_pressed);
        let mut abort = pressed;
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
        if (changed_phase || store.is_some()) && !self.is_running() {
            // A press in the very sample a command changed the mode, or asked for a flash
            // write, must not start a run on top of it: the person presses again.
            pressed = false;
        }
        let mut out = self.step_phase(inp, pressed, abort, sink);
        // (`step_phase` never asks for a write: the settings are copied only when there are some.)
        if store.is_some() {
            out.store = store;
        }
        out.settings_changed = core::mem::take(&mut self.settings_changed);
        out
    }

    #[cfg_attr(not(target_os = "none"), inline(always))]
    fn step_phase(
        &mut self,
        inp: &Inputs,
        pressed: bool,
        abort: bool,
        sink: &mut impl LogSink,
    ) -> Outputs {
        // One call of `step_running` (the sample path of a run), for the run's samples and the
        // press that starts one alike: inlined here, and only once on the board.
        let abort = match self.phase {
            Phase::Idle { latched } => {
                let mut started = false;
                if self.is_homing() {
                    let rest = self.protocol.rest_deg;
                    let step = HOMING_DEG_PER_S / self.protocol.sample_hz as f32;
                    let gap = rest - self.idle_servo_deg;
                    self.idle_servo_deg = if gap.abs() <= step {
                        rest
                    } else if gap > 0.0 {
                        self.idle_servo_deg + step
                    } else {
                        self.idle_servo_deg - step
                    };
                    if pressed {
                        info!("press ignored: the servo is still on its way to rest");
                    }
                } else if pressed {
                    if latched.is_some() {
                        self.phase = Phase::Idle { latched: None };
                        info!(
                            "fault acknowledged; press again to start run {=u32}",
                            self.runs + 1
                        );
                    } else {
                        self.start(inp.now_us);
                        started = true;
                    }
                }
                if !started {
                    let blink_ms = if self.latched_fault().is_some() {
                        100
                    } else {
                        500
                    };
                    let mut out = self.idle_outputs();
                    out.led = (inp.now_us / 1000 / blink_ms).is_multiple_of(2);
                    return out;
                }
                // The press that started the run does not abort it.
                false
            }
            // (On the host, a copy for the out-of-line setup step: the sample loop's inputs are
            // then only read, and stay in registers.)
            #[cfg(not(target_os = "none"))]
            Phase::Setup { .. } => return self.step_setup(&{ *inp }, pressed, sink),
            #[cfg(target_os = "none")]
            Phase::Setup { .. } => return self.step_setup(inp, pressed, sink),
            _ => abort,
        };
        self.step_running(inp, abort, sink)
    }

    fn start(&mut self, now_us: u64) {
        self.press_us = now_us;
        self.runs += 1;
        self.pairs = 0;
        self.raw_in = 0;
        self.elapsed_us = 0;
        self.supervisor = Supervisor::new(self.limits);
        self.phase = Phase::Tare { sum: [0; 2], n: 0 };
        info!("run {=u32}: button pressed, taring", self.runs);
    }

    /// A tension level (≥ 1) has been held for `CORD_CHECK_SETTLE_MS`: the cord is loaded.
    /// (The step is the one of the previous sample: at most one sample late at a change.)
    fn level_held(&self, elapsed_ms: u32) -> bool {
        matches!(self.phase, Phase::Run { armed_ms, .. } if elapsed_ms >= armed_ms)
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

    fn begin_run(&mut self, tare: Option<([u64; 2], u32)>) -> Phase {
        if let Some((sum, n)) = tare.filter(|&(_, n)| n > 0) {
            let r = self.cal.tare_reference_n;
            self.cal.t1.tare(sum[0] as f32 / n as f32, r);
            self.cal.t2.tare(sum[1] as f32 / n as f32, r);
        }
        // Step 0 (rest, no window) until the first step starts.
        Phase::Run {
            step: 0,
            window: Window::new(0, 0),
            pair_due_us: u64::MAX,
            next_ms: self.protocol.step_start_ms(0),
            armed_ms: u32::MAX,
            servo_deg: self.protocol.rest_deg,
        }
    }

    #[cfg_attr(not(target_os = "none"), inline(always))]
    fn step_running(&mut self, inp: &Inputs, pressed: bool, sink: &mut impl LogSink) -> Outputs {
        // Borrowed, not copied: the protocol is ~60 bytes, and a sample needs a few of them.
        let p = &self.protocol;
        let period_us = self.period_us as u64;
        // A sample comes one period after the last, give or take the clock's latency: then it
        // is on the grid without `on_grid`'s 64-bit division (in software on the board).
        let since_us = inp.now_us.saturating_sub(self.press_us) + period_us / 2;
        let next_us = self.elapsed_us + period_us;
        let elapsed_us = if since_us.wrapping_sub(next_us) < period_us {
            next_us
        } else {
            on_grid(inp.now_us, self.press_us, self.period_us) - self.press_us
        };
        self.elapsed_us = elapsed_us;
        let elapsed_ms = (elapsed_us / 1000) as u32;
        let t_us = self.since_trigger_us(elapsed_us);
        let counts_ok = match inp.counts {
            [Ok(a), Ok(b)] => Some([a, b]),
            _ => None,
        };
        // (`forces`, without its NaN cases on the usual sample with both conversions done.)
        let force_n = match counts_ok {
            Some([a, b]) => [self.cal.t1.newtons(a as f32), self.cal.t2.newtons(b as f32)],
            None => self.forces(inp),
        };

        // Tare, then announce the run with the calibration it will use.
        if let Phase::Tare { sum, n } = &mut self.phase {
            if let Some(c) = counts_ok {
                sum[0] += c[0] as u64;
                sum[1] += c[1] as u64;
                *n += 1;
            }
            if elapsed_us + period_us >= p.tare_ms as u64 * 1000 {
                // tare_ms = 0 keeps the stored zero (the one sample taken is not a tare).
                let tare = (p.tare_ms > 0).then_some((*sum, *n));
                self.phase = self.begin_run(tare);
                let rec = RunStart {
                    run: self.runs,
                    protocol: self.protocol,
                    calibration: self.cal,
                };
                self.emit(sink, Record::RunStart(rec));
            }
        }
        let p = &self.protocol;

        // Safety first: a fault ends the run in this very sample.
        let fault = if pressed {
            Some(Fault {
                kind: FaultKind::Abort,
                channel: None,
                value: 0.0,
                t_us,
            })
        } else {
            self.supervisor.check(&SafetyInput {
                t_us,
                counts: inp.counts,
                force_n,
                cord_check_armed: self.level_held(elapsed_ms),
            })
        };
        if let Some(f) = fault {
            warn!("fault {}", f.kind);
            self.emit(sink, Record::Fault(f));
            return self.finish(t_us, Some(f.kind), sink);
        }

        // Decimated raw samples for the log, from the run start on.
        if !matches!(self.phase, Phase::Tare { .. }) {
            if self.raw_in == 0 {
                let raw = RawSample {
                    t_us,
                    counts: [inp.counts[0].unwrap_or(0), inp.counts[1].unwrap_or(0)],
                    force_n,
                };
                sink.emit(self.seq.next_seq(), &Record::Raw(raw));
                self.raw_in = p.sample_hz / p.raw_log_hz;
            }
            self.raw_in -= 1;
        }

        // The phase is updated in place: a run's window is too large to copy every sample.
        if let Phase::Run {
            step,
            window,
            pair_due_us,
            next_ms,
            armed_ms,
            servo_deg,
        } = &mut self.phase
        {
            if elapsed_ms >= *next_ms {
                // Which step is being held: steps start at step_start_ms(k).
                let n = p.levels();
                let k = ((elapsed_ms - p.step_start_ms(0)) / p.dwell_ms).min(n + 1);
                if k != *step {
                    *step = k;
                    let (a, b) = p.window_ms(k);
                    *window = Window::new(a as u64 * 1000, b as u64 * 1000);
                    *pair_due_us = if k == 0 || k > n {
                        u64::MAX
                    } else {
                        b as u64 * 1000
                    };
                    *servo_deg = p.angle_deg(k);
                    *armed_ms = if k >= 1 && p.level(k) >= 1 {
                        p.step_start_ms(k) + CORD_CHECK_SETTLE_MS
                    } else {
                        u32::MAX
                    };
                }
                *next_ms = if k > n {
                    u32::MAX
                } else {
                    p.step_start_ms(k + 1)
                };
            }
            if let Some(c) = counts_ok {
                window.push(elapsed_us, c);
            }
            let mut pair = None;
            if elapsed_us + period_us >= *pair_due_us {
                *pair_due_us = u64::MAX;
                let (a, b) = p.window_ms(*step);
                let [t1, t2] = window.stats(&self.cal);
                pair = Some(StepPair {
                    step: *step,
                    level: p.level(*step),
                    angle_deg: *servo_deg,
                    t_mid_ms: (a + b) / 2 - p.trigger_at_ms(),
                    t1,
                    t2,
                });
            }
            let (ended, servo_deg) = (*next_ms == u32::MAX, *servo_deg);
            if let Some(pair) = pair {
                self.pairs += 1;
                sink.emit(self.seq.next_seq(), &Record::Pair(pair));
            }
            if ended {
                return self.finish(t_us, None, sink);
            }
            let trigger_ms = elapsed_ms.wrapping_sub(p.trigger_at_ms());
            return Outputs {
                servo_deg,
                amp_control_v: p.amp_control_v,
                trigger: elapsed_ms >= p.trigger_at_ms() && trigger_ms < p.trigger_ms,
                led: true,
                finished: None,
                store: None,
                settings_changed: false,
            };
        }
        // Taring: capstan stopped, servo at rest.
        let mut out = self.safe_outputs();
        out.led = true;
        out
    }

    fn finish(&mut self, t_us: i64, fault: Option<FaultKind>, sink: &mut impl LogSink) -> Outputs {
        let end = RunEnd {
            t_us,
            pairs: self.pairs,
            fault,
        };
        self.emit(sink, Record::RunEnd(end));
        info!("run {=u32} ended: {=u32} pairs", self.runs, self.pairs);
        self.phase = Phase::Idle { latched: fault };
        self.idle_servo_deg = self.protocol.rest_deg;
        if fault.is_some() {
            warn!(
                "run {=u32}: fault latched; press once to acknowledge it",
                self.runs
            );
        }
        let mut out = self.safe_outputs();
        out.finished = Some(end);
        out
    }
}
