//! A run, sample by sample: the tare and its bound, the steps, the conditioning windows, the
//! raw log, the supervisor, and the end (normal or by a fault, which is latched).

use super::steps::Steps;
use super::{on_grid, Inputs, Outputs, Phase, Rig, TARE_MAX_N};
use crate::button::Edge;
use crate::calib::ChannelCal;
use crate::force::ForceRun;
use crate::hal::Channel;
use crate::record::{Fault, FaultKind, LogSink, RawSample, Record, RunEnd, RunStart};
use crate::safety::{DriveContext, Driven, SafetyInput, Supervisor};

impl Rig {
    /// A press at the rig starts a run: its tare now (nothing moves), its drive once the press
    /// is released.
    pub(super) fn start(&mut self, now_us: u64) {
        self.press_us = now_us;
        self.runs += 1;
        self.pairs = 0;
        self.raw_in = 0;
        self.elapsed_us = 0;
        self.supervisor = Supervisor::new(self.limits);
        self.phase = Phase::Tare {
            sum: [0; 2],
            n: 0,
            waiting: false,
        };
        self.awaiting_release = true;
        self.armed_until_us = None;
        self.button.consume();
        info!("run {=u32}: button pressed, taring", self.runs);
    }

    /// What stays fixed while this run drives the capstan, for the supervisor.
    fn drive_context(&self) -> DriveContext {
        let p = &self.protocol;
        let given = p.capstan_diameter_mm > 0.0;
        let diameter_mm = if given {
            p.capstan_diameter_mm
        } else {
            self.limits.default_capstan_diameter_mm
        };
        let wrap_rad = p.wrap_deg * (core::f32::consts::PI / 180.0);
        let max_amplification = if p.wrap_deg > 0.0 && self.limits.max_mu > 0.0 {
            libm::expf(self.limits.max_mu * wrap_rad)
        } else {
            f32::INFINITY
        };
        DriveContext {
            tare_reference_n: self.cal.tare_reference_n,
            n_per_count: [self.cal.t1.n_per_count, self.cal.t2.n_per_count],
            zero_counts: [self.cal.t1.zero_counts, self.cal.t2.zero_counts],
            capstan_radius_m: diameter_mm * 0.5e-3,
            max_amplification,
            drive_v: self.cal.amp.drive_v(p.amp_control_v),
        }
    }

    /// The tare is over: check the load it saw against the stored zeros ([`TARE_MAX_N`]),
    /// re-zero both channels for this run (unless `tare_ms` is 0), and check that the
    /// over-force limit stays visible under the run's calibration. Returns the run's first
    /// phase, and the fault that refuses the run, if any.
    fn begin_run(&mut self, sum: [u64; 2], n: u32, t_us: i64) -> (Phase, Option<Fault>) {
        let mut fault = None;
        if n > 0 {
            let r = self.cal.tare_reference_n;
            let means = [sum[0] as f32 / n as f32, sum[1] as f32 / n as f32];
            for ch in Channel::BOTH {
                let k = ch as usize;
                let stored = ChannelCal {
                    zero_counts: self.zeros[k],
                    ..self.channel(ch)
                };
                let load_n = stored.newtons(means[k]) - r;
                if fault.is_none() && (load_n.is_nan() || load_n.abs() > TARE_MAX_N) {
                    fault = Some((FaultKind::TareLoad, ch, load_n));
                }
            }
            // tare_ms = 0 keeps the stored zero (the one sample taken is not a tare).
            if self.protocol.tare_ms > 0 {
                self.cal.t1.tare(means[0], r);
                self.cal.t2.tare(means[1], r);
            }
        }
        if fault.is_none() {
            if let Err(b) = self.limits.visible(&self.cal) {
                fault = Some((FaultKind::Blind, b.channel, b.readable_n));
            }
        }
        let phase = Phase::Run(Steps::new(&self.protocol));
        // (Force mode: the controller starts at rest, nothing learned.)
        self.force = ForceRun::new(&self.protocol, &self.limits);
        self.supervisor.drive(self.drive_context());
        let fault = fault.map(|(kind, ch, value)| Fault {
            kind,
            channel: Some(ch),
            value,
            t_us,
        });
        (phase, fault)
    }

    fn channel(&self, ch: Channel) -> ChannelCal {
        match ch {
            Channel::T1 => self.cal.t1,
            Channel::T2 => self.cal.t2,
        }
    }

    /// One sample of a run (its tare included): a fault ends it in this very sample. `edge`:
    /// the button's; `abort`: the run is stopped (its press's edge, or the host's `abort`).
    #[inline]
    pub(super) fn step_running(
        &mut self,
        inp: &Inputs,
        edge: Edge,
        abort: bool,
        sink: &mut impl LogSink,
    ) -> Outputs {
        if abort {
            self.button.consume();
        }
        if let Edge::Released { .. } = edge {
            self.awaiting_release = false;
        }
        // Held from the start of the run, never released: cancelled before the drive is on.
        let held = edge == Edge::Held && self.awaiting_release;
        if let Phase::Tare { waiting: true, .. } = self.phase {
            // The run's clock stands still while the drive waits for the release.
            self.press_us += self.period_us as u64;
        }
        let elapsed_us = self.run_clock(inp.now_us);
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
        let tare_fault = self.tare_sample(counts_ok, elapsed_us, t_us, sink);

        // Safety first: a fault ends the run in this very sample (a tare that is refused,
        // before the amplifier is ever on).
        let fault = if abort || held {
            Some(Fault {
                kind: if held {
                    FaultKind::ButtonHeld
                } else {
                    FaultKind::Abort
                },
                channel: None,
                value: 0.0,
                t_us,
            })
        } else if tare_fault.is_some() {
            tare_fault
        } else {
            let driven = self.driven((elapsed_us / 1000) as u32);
            self.supervisor.check(&SafetyInput {
                t_us,
                counts: inp.counts,
                force_n,
                driven,
            })
        };
        if let Some(f) = fault {
            warn!("fault {}", f.kind);
            self.emit(sink, Record::Fault(f));
            return self.finish(t_us, Some(f.kind), sink);
        }
        if matches!(self.phase, Phase::Tare { .. }) {
            // Taring: capstan stopped, servo at rest.
            let mut out = self.safe_outputs();
            out.led = true;
            return out;
        }
        self.step_sample(inp, force_n, elapsed_us, counts_ok, t_us, sink)
    }

    /// The run's clock on this sample: µs from the press, on the sample grid.
    #[inline]
    fn run_clock(&mut self, now_us: u64) -> u64 {
        let period_us = self.period_us as u64;
        // A sample comes one period after the last, give or take the clock's latency: then it
        // is on the grid without `on_grid`'s 64-bit division (in software on the board).
        let since_us = now_us.saturating_sub(self.press_us) + period_us / 2;
        let next_us = self.elapsed_us + period_us;
        self.elapsed_us = if since_us.wrapping_sub(next_us) < period_us {
            next_us
        } else {
            on_grid(now_us, self.press_us, self.period_us) - self.press_us
        };
        self.elapsed_us
    }

    /// The capstan as the supervisor sees it on this sample: driven once the tare is over,
    /// with the servo's command and whether a level is held.
    #[inline]
    fn driven(&self, elapsed_ms: u32) -> Option<Driven> {
        let Phase::Run(steps) = &self.phase else {
            return None;
        };
        let servo_deg = steps.servo_deg();
        Some(Driven {
            servo_deg,
            at_rest: servo_deg == self.protocol.rest_deg,
            level_held: steps.level_held(elapsed_ms),
        })
    }

    /// While taring: add the sample to the tare; on its last sample (once the press that
    /// started the run is released), announce the run with the calibration it will use.
    /// Returns the fault that refuses the run, if any.
    #[inline]
    fn tare_sample(
        &mut self,
        counts: Option<[u16; 2]>,
        elapsed_us: u64,
        t_us: i64,
        sink: &mut impl LogSink,
    ) -> Option<Fault> {
        let period_us = self.period_us as u64;
        let tare_end_us = self.protocol.tare_ms as u64 * 1000;
        let awaiting = self.awaiting_release;
        let Phase::Tare { sum, n, waiting } = &mut self.phase else {
            return None;
        };
        if !*waiting {
            if let Some(c) = counts {
                sum[0] += c[0] as u64;
                sum[1] += c[1] as u64;
                *n += 1;
            }
            if elapsed_us + period_us < tare_end_us {
                return None;
            }
        }
        if awaiting {
            if !*waiting {
                info!("the tare is done: the drive waits for the button's release");
            }
            *waiting = true;
            return None;
        }
        let (sum, n) = (*sum, *n);
        let tare_fault;
        (self.phase, tare_fault) = self.begin_run(sum, n, t_us);
        let rec = RunStart {
            run: self.runs,
            protocol: self.protocol,
            calibration: self.cal,
        };
        self.emit(sink, Record::RunStart(rec));
        tare_fault
    }

    /// Decimated raw samples for the log, from the run start on.
    #[inline]
    fn log_raw(
        &mut self,
        inp: &Inputs,
        force_n: [f32; 2],
        t2_target_n: f32,
        t_us: i64,
        sink: &mut impl LogSink,
    ) {
        if self.raw_in == 0 {
            let raw = RawSample {
                t_us,
                counts: [inp.counts[0].unwrap_or(0), inp.counts[1].unwrap_or(0)],
                force_n,
                t2_target_n,
            };
            sink.emit(self.seq.next_seq(), &Record::Raw(raw));
            self.raw_in = self.protocol.sample_hz / self.protocol.raw_log_hz;
        }
        self.raw_in -= 1;
    }

    /// One sample of the steps (after the tare): the step held (in force mode, the servo
    /// command of the controller holding its T2 target), the raw log, its window, its pair when
    /// due, the run's end after the last.
    #[inline]
    fn step_sample(
        &mut self,
        inp: &Inputs,
        force_n: [f32; 2],
        elapsed_us: u64,
        counts: Option<[u16; 2]>,
        t_us: i64,
        sink: &mut impl LogSink,
    ) -> Outputs {
        let p = &self.protocol;
        let Phase::Run(steps) = &mut self.phase else {
            return self.safe_outputs();
        };
        steps.sample(p, elapsed_us, counts);
        let mut t2_target_n = 0.0;
        if p.force.is_on() {
            let k = steps.step();
            let in_ms = ((elapsed_us / 1000) as u32).saturating_sub(p.step_start_ms(k));
            steps.set_servo_deg(self.force.sample(p, k, in_ms, force_n));
            t2_target_n = self.force.target_n();
        }
        self.log_raw(inp, force_n, t2_target_n, t_us, sink);
        let p = &self.protocol;
        let Phase::Run(steps) = &mut self.phase else {
            return self.safe_outputs();
        };
        let pair = steps.pair_due(p, &self.cal, elapsed_us, self.period_us as u64);
        let (ended, servo_deg) = (steps.ended(), steps.servo_deg());
        if let Some(pair) = pair {
            self.pairs += 1;
            sink.emit(self.seq.next_seq(), &Record::Pair(pair));
        }
        if ended {
            return self.finish(t_us, None, sink);
        }
        let p = &self.protocol;
        let elapsed_ms = (elapsed_us / 1000) as u32;
        let trigger_ms = elapsed_ms.wrapping_sub(p.trigger_at_ms());
        Outputs {
            servo_deg,
            servo_pulses: true,
            amp_control_v: p.amp_control_v,
            trigger: elapsed_ms >= p.trigger_at_ms() && trigger_ms < p.trigger_ms,
            led: true,
            finished: None,
            store: None,
            settings_changed: false,
        }
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
        self.awaiting_release = false;
        self.idle_servo_deg = self.protocol.rest_deg;
        // The tare's zeros were for this run only; the idle checks start afresh.
        [self.cal.t1.zero_counts, self.cal.t2.zero_counts] = self.zeros;
        self.supervisor = Supervisor::new(self.limits);
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
