//! A run, sample by sample: the tare and its bound, the steps, the conditioning windows, the
//! raw log, the supervisor, and the end (normal or by a fault, which is latched).

use super::{on_grid, Inputs, Outputs, Phase, Rig, CORD_CHECK_SETTLE_MS, TARE_MAX_N};
use crate::calib::ChannelCal;
use crate::condition::Window;
use crate::hal::Channel;
use crate::record::{Fault, FaultKind, LogSink, RawSample, Record, RunEnd, RunStart, StepPair};
use crate::safety::{SafetyInput, Supervisor};

impl Rig {
    pub(super) fn start(&mut self, now_us: u64) {
        self.press_us = now_us;
        self.runs += 1;
        self.pairs = 0;
        self.raw_in = 0;
        self.elapsed_us = 0;
        self.supervisor = Supervisor::new(self.limits);
        self.phase = Phase::Tare { sum: [0; 2], n: 0 };
        info!("run {=u32}: button pressed, taring", self.runs);
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
        // Step 0 (rest, no window) until the first step starts.
        let phase = Phase::Run {
            step: 0,
            window: Window::new(0, 0),
            pair_due_us: u64::MAX,
            next_ms: self.protocol.step_start_ms(0),
            armed_ms: u32::MAX,
            servo_deg: self.protocol.rest_deg,
        };
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

    #[cfg_attr(not(target_os = "none"), inline(always))]
    pub(super) fn step_running(
        &mut self,
        inp: &Inputs,
        pressed: bool,
        sink: &mut impl LogSink,
    ) -> Outputs {
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
        let mut tare_fault = None;
        if let Phase::Tare { sum, n } = &mut self.phase {
            if let Some(c) = counts_ok {
                sum[0] += c[0] as u64;
                sum[1] += c[1] as u64;
                *n += 1;
            }
            if elapsed_us + period_us >= p.tare_ms as u64 * 1000 {
                let (sum, n) = (*sum, *n);
                (self.phase, tare_fault) = self.begin_run(sum, n, t_us);
                let rec = RunStart {
                    run: self.runs,
                    protocol: self.protocol,
                    calibration: self.cal,
                };
                self.emit(sink, Record::RunStart(rec));
            }
        }
        let p = &self.protocol;

        // Safety first: a fault ends the run in this very sample (a tare that is refused,
        // before the amplifier is ever on).
        let fault = if pressed {
            Some(Fault {
                kind: FaultKind::Abort,
                channel: None,
                value: 0.0,
                t_us,
            })
        } else if tare_fault.is_some() {
            tare_fault
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
                servo_pulses: true,
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
