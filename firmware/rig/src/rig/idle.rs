//! Between runs: the supervisor keeps watching (homing, a latched fault and a boot after a
//! reset included), homing brings the servo to rest unless a fault is latched, and only a
//! person clears a latch: a press (after the button was seen released) or, but for a latch a
//! reset left, the host's `ack`. A press starts a run only with both sensitivities measured or
//! typed; a run the host armed lapses after [`super::ARM_MS`].

use super::{Inputs, Outputs, Phase, Rig, HOMING_DEG_PER_S};
use crate::button::Edge;
use crate::record::{Fault, FaultKind, LogSink, Record};
use crate::safety::{SafetyInput, Supervisor};

impl Rig {
    /// One idle sample: `None` if the press started a run (the caller runs its first sample).
    #[inline]
    pub(super) fn step_idle(
        &mut self,
        inp: &Inputs,
        latched: Option<FaultKind>,
        edge: Edge,
        sink: &mut impl LogSink,
    ) -> Option<Outputs> {
        let mut latched = self.supervise_idle(inp, latched, sink);
        if edge == Edge::Held {
            self.latch_idle(Self::held_fault(inp), sink);
            latched = Some(FaultKind::ButtonHeld);
        }
        if self.armed_until_us.is_some_and(|t| inp.now_us >= t) {
            self.armed_until_us = None;
            warn!("the armed run lapsed: nobody pressed the rig's button in time");
        }
        if latched.is_none() && self.is_homing() {
            self.home_one_sample();
            if edge == Edge::Pressed {
                info!("press ignored: the servo is still on its way to rest");
            }
        } else if latched.is_some() {
            if edge == (Edge::Released { consumed: false }) {
                self.acknowledge();
                info!(
                    "fault acknowledged; press again to start run {=u32}",
                    self.runs + 1
                );
            }
        } else if edge == Edge::Pressed {
            if self.cal.unmeasured().is_none() {
                self.start(inp.now_us);
                return None;
            }
            self.button.consume();
            warn!("press ignored: a sensitivity was never measured (the built-in placeholder): weigh it or set it, then store");
        }
        let blink_ms = if self.latched_fault().is_some() {
            100
        } else {
            500
        };
        let mut out = self.idle_outputs();
        out.led = (inp.now_us / 1000 / blink_ms).is_multiple_of(2);
        if self.is_armed() && self.latched_fault().is_none() {
            // Armed: on, off for 0.1 s each second.
            out.led = inp.now_us / 1000 % 1000 < 900;
        }
        Some(out)
    }

    /// The button held too long, as a fault at `inp`.
    pub(super) fn held_fault(inp: &Inputs) -> Fault {
        Fault {
            kind: FaultKind::ButtonHeld,
            channel: None,
            value: crate::button::LONG_PRESS_MS as f32,
            t_us: inp.now_us as i64,
        }
    }

    /// Record and latch `f` while idle (the servo command only toward release).
    fn latch_idle(&mut self, f: Fault, sink: &mut impl LogSink) {
        self.idle_servo_deg = self.toward_release(self.idle_servo_deg);
        self.armed_until_us = None;
        warn!("fault {} while idle: latched", f.kind);
        self.emit(sink, Record::Fault(f));
        self.phase = Phase::Idle {
            latched: Some(f.kind),
        };
    }

    /// The supervisor on an idle sample (no cord check: no level is held). A fault is
    /// recorded and latched (a fault of the kind already latched is not recorded again), and
    /// the servo command moves only toward release. Returns what is latched now.
    fn supervise_idle(
        &mut self,
        inp: &Inputs,
        latched: Option<FaultKind>,
        sink: &mut impl LogSink,
    ) -> Option<FaultKind> {
        let input = SafetyInput {
            t_us: inp.now_us as i64,
            counts: inp.counts,
            force_n: self.forces(inp),
            driven: None,
        };
        let Some(f) = self.supervisor.check(&input) else {
            return latched;
        };
        // The counters start again: a condition that persists trips again 3-5 samples on.
        self.supervisor = Supervisor::new(self.limits);
        self.idle_servo_deg = self.toward_release(self.idle_servo_deg);
        if latched != Some(f.kind) {
            self.latch_idle(f, sink);
        }
        Some(f.kind)
    }

    /// One sample of homing toward rest at [`HOMING_DEG_PER_S`].
    fn home_one_sample(&mut self) {
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
    }

    /// A person acknowledged the latched fault (a press, or the host's `ack`). A servo left
    /// without pulses by a reset gets its first pulse now: the rest pulse (where the horn is
    /// after the reset is not known, but it can only have moved toward release).
    pub(super) fn acknowledge(&mut self) {
        self.phase = Phase::Idle { latched: None };
        if self.limp {
            self.limp = false;
            self.idle_servo_deg = self.protocol.rest_deg;
            self.settings_changed = true;
        }
    }

    /// At boot, after a reset that was not a clean power-up at rest
    /// ([`crate::reset::boot_latch`]): `kind` is latched and recorded, and the servo gets no
    /// pulses until a person acknowledges it. Nothing moves until then; the supervisor runs.
    pub fn boot_latched(&mut self, kind: FaultKind, sink: &mut impl LogSink) {
        if self.is_running() {
            return;
        }
        self.armed_until_us = None;
        self.phase = Phase::Idle {
            latched: Some(kind),
        };
        self.limp = true;
        self.idle_servo_deg = self.protocol.rest_deg;
        self.settings_changed = true;
        warn!(
            "fault {} latched at boot: the servo gets no pulses until a press or `ack`",
            kind
        );
        let f = Fault {
            kind,
            channel: None,
            value: f32::NAN,
            t_us: 0,
        };
        self.emit(sink, Record::Fault(f));
    }
}
