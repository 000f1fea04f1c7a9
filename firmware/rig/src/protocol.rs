//! The test protocol as data, its validation, and the schedule it implies.
//!
//! Timeline of one run (times from the accepted button press):
//!
//! ```text
//! 0            tare (amplifier at 0 V, servo at rest) for `tare_ms`
//! tare_ms      amplifier to its control voltage (the capstan spins up)
//! pre_trigger  trigger high for `trigger_ms` (the logger arms on the rising edge)
//! +trigger_ms  step 0: servo at rest; then step k = 1..=N every `dwell_ms`
//! end          servo back to rest, amplifier to 0 V, run end
//! ```
//!
//! Step k (1..=N) holds servo level `level(k)`, at angle `rest_deg - level * step_deg`; its
//! pair is conditioned over [change + `window_after_change_ms`, next change −
//! `window_before_next_ms`).

/// The order in which the N tension levels are visited (its code and name are the wire
/// schema's).
pub use capstan_wire::StepOrder;

use crate::force::{ForceConfig, ForceError};

/// Everything the rig does in a run. `Protocol::default()` is the thesis's protocol.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub struct Protocol {
    /// Servo angle at rest and for step 0, deg (thesis: 125).
    pub rest_deg: f32,
    /// Servo angle change per level, deg (thesis: 5).
    pub step_deg: f32,
    /// Angle of the highest level, deg (thesis: 65, the last angle above 60).
    pub final_deg: f32,
    /// Order of the levels.
    pub order: StepOrder,
    /// Time per step, ms (thesis: 10 000).
    pub dwell_ms: u32,
    /// Press to trigger rising edge, ms (thesis: 1000).
    pub pre_trigger_ms: u32,
    /// Trigger pulse length, ms (thesis: 500).
    pub trigger_ms: u32,
    /// Tare window at the start of the pre-trigger wait, ms (0 = keep the stored zero).
    pub tare_ms: u32,
    /// Power amplifier control voltage during the run, V.
    pub amp_control_v: f32,
    /// Sampling rate of both force channels, Hz (≥ 1000).
    pub sample_hz: u32,
    /// Rate of the raw samples sent to the log, Hz (divides `sample_hz`).
    pub raw_log_hz: u32,
    /// Conditioning window starts this long after a tension change, ms (thesis: 2000).
    pub window_after_change_ms: u32,
    /// Conditioning window ends this long before the next change, ms (thesis: 1000).
    pub window_before_next_ms: u32,
    /// Capstan diameter, mm, as set up on the rig (metadata for the log; 0 = not given).
    pub capstan_diameter_mm: f32,
    /// Wrap angle, deg, as set up on the rig (metadata for the log; 0 = not given; in force
    /// mode the fitted law's wrap, and required).
    pub wrap_deg: f32,
    /// Force control (issue 43): in force mode the steps are the T2 target's segments and the
    /// servo holds T2 at the target; the angles above bound its travel (rest to final).
    pub force: ForceConfig,
}

impl Default for Protocol {
    fn default() -> Self {
        Protocol {
            rest_deg: 125.0,
            step_deg: 5.0,
            final_deg: 65.0,
            order: StepOrder::Monotone,
            dwell_ms: 10_000,
            pre_trigger_ms: 1_000,
            trigger_ms: 500,
            tare_ms: 500,
            amp_control_v: 2.5,
            sample_hz: 1_000,
            raw_log_hz: 100,
            window_after_change_ms: 2_000,
            window_before_next_ms: 1_000,
            capstan_diameter_mm: 0.0,
            wrap_deg: 0.0,
            force: ForceConfig::default(),
        }
    }
}

/// Why a protocol is refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub enum ProtocolError {
    /// An angle is outside the servo's 0..=180 deg, or not finite.
    AngleOutOfRange,
    /// `step_deg` must be positive and `final_deg` below `rest_deg`.
    NoSteps,
    /// (rest − final) must be a whole number of steps, at most 64 of them.
    StepsNotWhole,
    /// The trigger pulse or the dwell is zero.
    ZeroDuration,
    /// The tare must end before the trigger rises.
    TareTooLong,
    /// The window would be empty: after + before must leave at least one sample of the dwell.
    EmptyWindow,
    /// Sampling must be 1000..=10000 Hz with a whole number of µs per sample.
    SampleRate,
    /// The raw log rate must divide the sample rate.
    RawLogRate,
    /// The amplifier control voltage must be 0..=3.3 V.
    AmpVoltage,
    /// The whole run must fit in u32 milliseconds (49 days) — and in practice much less.
    TooLong,
    /// Force control's settings are refused.
    Force(ForceError),
}

impl ProtocolError {
    /// What is wrong, for a person (the same words on every host and in the board's log).
    pub const fn message(self) -> &'static str {
        match self {
            ProtocolError::AngleOutOfRange => "an angle is outside 0..=180°",
            ProtocolError::NoSteps => "it needs a positive step and a final angle below rest",
            ProtocolError::StepsNotWhole => {
                "rest − final must be a whole number of steps (at most 64)"
            }
            ProtocolError::ZeroDuration => "the dwell and the trigger pulse must be > 0",
            ProtocolError::TareTooLong => "the tare must end before the trigger",
            ProtocolError::EmptyWindow => {
                "window-after + window-before must leave at least 1 ms of the dwell"
            }
            ProtocolError::SampleRate => "sampling must be 1000..=10000 Hz",
            ProtocolError::RawLogRate => "the raw log rate must divide the sample rate",
            ProtocolError::AmpVoltage => "the amplifier control voltage must be 0..=3.3 V",
            ProtocolError::TooLong => "the run is too long",
            ProtocolError::Force(e) => e.message(),
        }
    }
}

impl core::fmt::Display for ProtocolError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.message())
    }
}

/// Most levels a protocol may have.
pub const MAX_LEVELS: u32 = 64;

impl Protocol {
    /// Refuse a protocol that cannot be run, with the reason.
    pub fn validate(&self) -> Result<(), ProtocolError> {
        let angle_ok = |a: f32| a.is_finite() && (0.0..=180.0).contains(&a);
        if !(angle_ok(self.rest_deg) && angle_ok(self.final_deg) && self.step_deg.is_finite()) {
            return Err(ProtocolError::AngleOutOfRange);
        }
        if self.step_deg <= 0.0 || self.final_deg >= self.rest_deg {
            return Err(ProtocolError::NoSteps);
        }
        let span = (self.rest_deg - self.final_deg) / self.step_deg;
        let levels = libm::roundf(span);
        if (span - levels).abs() > 1e-3 || levels < 1.0 || levels > MAX_LEVELS as f32 {
            return Err(ProtocolError::StepsNotWhole);
        }
        if self.dwell_ms == 0 || self.trigger_ms == 0 {
            return Err(ProtocolError::ZeroDuration);
        }
        if self.tare_ms > self.pre_trigger_ms {
            return Err(ProtocolError::TareTooLong);
        }
        if !(1_000..=10_000).contains(&self.sample_hz) || 1_000_000 % self.sample_hz != 0 {
            return Err(ProtocolError::SampleRate);
        }
        let sample_ms_ceil = 1;
        let window_ms = self.dwell_ms as u64;
        if (self.window_after_change_ms as u64 + self.window_before_next_ms as u64 + sample_ms_ceil)
            > window_ms
        {
            return Err(ProtocolError::EmptyWindow);
        }
        if self.raw_log_hz == 0
            || self.raw_log_hz > self.sample_hz
            || !self.sample_hz.is_multiple_of(self.raw_log_hz)
        {
            return Err(ProtocolError::RawLogRate);
        }
        if !(self.amp_control_v.is_finite() && (0.0..=3.3).contains(&self.amp_control_v)) {
            return Err(ProtocolError::AmpVoltage);
        }
        self.force
            .validate(self.wrap_deg)
            .map_err(ProtocolError::Force)?;
        let total = self.pre_trigger_ms as u64
            + self.trigger_ms as u64
            + (self.levels().max(levels as u32) as u64 + 1) * self.dwell_ms as u64;
        if total > u32::MAX as u64 / 1000 {
            return Err(ProtocolError::TooLong);
        }
        Ok(())
    }

    /// Number of tension levels N (steps 1..=N; in force mode the target's segments).
    /// Meaningful once validated.
    pub fn levels(&self) -> u32 {
        if self.force.is_on() {
            return self.force.segments();
        }
        // Called several times per sample: a validated span is within 1e-3 of a whole number,
        // so adding ½ and truncating rounds it as `roundf` would, without the libm call.
        let span = (self.rest_deg - self.final_deg) / self.step_deg;
        (span + 0.5) as u32
    }

    /// Level held during step `k` (0 = rest, 1..=N the levels in this protocol's order; in
    /// force mode the segment, in order).
    pub fn level(&self, k: u32) -> u32 {
        let n = self.levels();
        if k == 0 || k > n {
            return 0;
        }
        if self.force.is_on() {
            return k;
        }
        match self.order {
            StepOrder::Monotone => k,
            StepOrder::UpDown => {
                let odd = n.div_ceil(2);
                if k <= odd {
                    2 * k - 1
                } else {
                    2 * (n / 2) - 2 * (k - odd - 1)
                }
            }
            StepOrder::Pulse => {
                if k % 2 == 1 {
                    1
                } else {
                    n
                }
            }
        }
    }

    /// Servo angle during step `k`, deg (in force mode the controller's: rest is where it
    /// starts).
    pub fn angle_deg(&self, k: u32) -> f32 {
        if self.force.is_on() {
            return self.rest_deg;
        }
        self.rest_deg - self.level(k) as f32 * self.step_deg
    }

    /// Press to trigger rising edge, ms.
    pub fn trigger_at_ms(&self) -> u32 {
        self.pre_trigger_ms
    }

    /// When step `k` starts (k = 0..=N+1; N+1 is the return to rest), ms from the press.
    pub fn step_start_ms(&self, k: u32) -> u32 {
        self.pre_trigger_ms + self.trigger_ms + k * self.dwell_ms
    }

    /// End of the run (servo back at rest), ms from the press.
    pub fn end_ms(&self) -> u32 {
        self.step_start_ms(self.levels() + 1)
    }

    /// Conditioning window of step `k`, [start, end) in ms from the press.
    pub fn window_ms(&self, k: u32) -> (u32, u32) {
        (
            self.step_start_ms(k) + self.window_after_change_ms,
            self.step_start_ms(k + 1) - self.window_before_next_ms,
        )
    }

    /// Sample period, µs.
    pub fn sample_period_us(&self) -> u32 {
        1_000_000 / self.sample_hz
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thesis_protocol_is_valid_and_has_twelve_levels() {
        let p = Protocol::default();
        assert_eq!(p.validate(), Ok(()));
        assert_eq!(p.levels(), 12);
        assert_eq!(p.angle_deg(0), 125.0);
        assert_eq!(p.angle_deg(1), 120.0);
        assert_eq!(p.angle_deg(12), 65.0);
        assert_eq!(p.step_start_ms(1), 11_500);
        // Window centre of step k is 10 k + 6 s after the trigger, as in the thesis.
        for k in 1..=12 {
            let (a, b) = p.window_ms(k);
            assert_eq!(b - a, 7_000);
            assert_eq!((a + b) / 2 - p.trigger_at_ms(), 10_000 * k + 6_000);
        }
        assert_eq!(p.end_ms(), 131_500);
    }

    #[test]
    fn updown_visits_every_level_once_and_decorrelates_level_from_time() {
        for n in [5u32, 12, 13] {
            let p = Protocol {
                final_deg: 125.0 - 5.0 * n as f32,
                order: StepOrder::UpDown,
                ..Protocol::default()
            };
            assert_eq!(p.validate(), Ok(()), "n={n}");
            let mut seen: std::vec::Vec<u32> = (1..=n).map(|k| p.level(k)).collect();
            for w in seen.windows(2) {
                assert!(w[0].abs_diff(w[1]) <= 2, "n={n}: {seen:?}");
            }
            seen.sort();
            assert_eq!(seen, (1..=n).collect::<std::vec::Vec<_>>());
        }
        let p = Protocol {
            order: StepOrder::UpDown,
            ..Protocol::default()
        };
        let levels: std::vec::Vec<f64> = (1..=12).map(|k| p.level(k) as f64).collect();
        let times: std::vec::Vec<f64> = (1..=12).map(|k| k as f64).collect();
        let corr = correlation(&levels, &times);
        assert!(corr.abs() < 0.2, "level-time correlation {corr}");
    }

    fn correlation(a: &[f64], b: &[f64]) -> f64 {
        let n = a.len() as f64;
        let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
        let cov: f64 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
        let va: f64 = a.iter().map(|x| (x - ma).powi(2)).sum();
        let vb: f64 = b.iter().map(|y| (y - mb).powi(2)).sum();
        cov / (va * vb).sqrt()
    }

    #[test]
    fn bad_protocols_are_refused_with_a_reason() {
        let ok = Protocol::default();
        let cases = [
            (
                Protocol {
                    rest_deg: 190.0,
                    ..ok
                },
                ProtocolError::AngleOutOfRange,
            ),
            (
                Protocol {
                    final_deg: f32::NAN,
                    ..ok
                },
                ProtocolError::AngleOutOfRange,
            ),
            (
                Protocol {
                    step_deg: 0.0,
                    ..ok
                },
                ProtocolError::NoSteps,
            ),
            (
                Protocol {
                    final_deg: 130.0,
                    ..ok
                },
                ProtocolError::NoSteps,
            ),
            (
                Protocol {
                    step_deg: 7.0,
                    ..ok
                },
                ProtocolError::StepsNotWhole,
            ),
            (Protocol { dwell_ms: 0, ..ok }, ProtocolError::ZeroDuration),
            (
                Protocol {
                    trigger_ms: 0,
                    ..ok
                },
                ProtocolError::ZeroDuration,
            ),
            (
                Protocol {
                    tare_ms: 1_500,
                    ..ok
                },
                ProtocolError::TareTooLong,
            ),
            (
                Protocol {
                    dwell_ms: 3_000,
                    ..ok
                },
                ProtocolError::EmptyWindow,
            ),
            (
                Protocol {
                    sample_hz: 500,
                    ..ok
                },
                ProtocolError::SampleRate,
            ),
            (
                Protocol {
                    sample_hz: 3_000,
                    ..ok
                },
                ProtocolError::SampleRate,
            ),
            (
                Protocol {
                    raw_log_hz: 300,
                    ..ok
                },
                ProtocolError::RawLogRate,
            ),
            (
                Protocol {
                    raw_log_hz: 0,
                    ..ok
                },
                ProtocolError::RawLogRate,
            ),
            (
                Protocol {
                    amp_control_v: 5.0,
                    ..ok
                },
                ProtocolError::AmpVoltage,
            ),
            (
                Protocol {
                    dwell_ms: 400_000_000,
                    ..ok
                },
                ProtocolError::TooLong,
            ),
        ];
        for (p, want) in cases {
            assert_eq!(p.validate(), Err(want), "{p:?}");
            assert!(!want.message().is_empty());
            assert_eq!(std::format!("{want}"), want.message());
        }
    }
}
