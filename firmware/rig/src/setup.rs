//! Setup mode's measurements, as pure data: a zero or a known-weight reading is the mean of
//! both channels over [`MEASURE_MS`], then turned into calibration values.
//!
//! In setup mode the rig (`rig.rs`, `rig/commands.rs`) holds the amplifier at 0 V and the
//! trigger low, moves the servo only where the host jogs it, keeps every safety check but the
//! cord-break ones (no level is held), and reports live values every [`LIVE_EVERY_MS`].

use crate::calib::Calibration;
use crate::command::CommandError;
use crate::hal::Channel;

/// A zero or a weigh averages this long, ms (500 samples at 1 kHz: the mean of a 0.02 N-noise
/// channel to ~1 mN).
pub const MEASURE_MS: u32 = 500;

/// Live values are reported this often, ms (10 Hz).
pub const LIVE_EVERY_MS: u32 = 100;

/// How fast setup mode moves the servo to where the host asked, deg/s: a jog of 5° takes
/// 0.17 s, `servo 65` from rest 2 s, where the HS-322HD alone would swing 60° in 0.2 s and
/// jerk the cord (a typo like `servo 0` must not do that).
pub const SETUP_DEG_PER_S: f32 = 30.0;

/// A known weight must move the mean reading at least this much, counts (at 0.015 N/count,
/// 0.3 N: below that the sensitivity would be mostly noise).
pub const MIN_WEIGH_COUNTS: f32 = 20.0;

/// A measurement whose readings scatter more than this (standard deviation, counts) is
/// refused: something moved (the servo, a swinging weight). The sensors' own noise is ~1.3
/// counts (0.02 N at 0.015 N/count).
pub const MAX_SCATTER_COUNTS: f32 = 4.0;

/// [`MAX_SCATTER_COUNTS`] squared: the variance is compared, so no square root is linked.
const MAX_VARIANCE: f32 = MAX_SCATTER_COUNTS * MAX_SCATTER_COUNTS;

/// What is being measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Measuring {
    /// Both channels unloaded: their zeros.
    Zero,
    /// A known force, N, on one channel: its sensitivity.
    Weigh(Channel, f32),
}

/// A measurement in progress: sums of both channels until `end_us`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measure {
    /// What it is for.
    pub what: Measuring,
    sum: [u64; 2],
    sum_sq: [u64; 2],
    n: u32,
    end_us: u64,
}

impl Measure {
    /// Start at `now_us`.
    pub fn new(what: Measuring, now_us: u64) -> Self {
        Measure {
            what,
            sum: [0; 2],
            sum_sq: [0; 2],
            n: 0,
            end_us: now_us + MEASURE_MS as u64 * 1000,
        }
    }

    /// Add one sample (`None`: a failed conversion, skipped); once the time is up, the mean
    /// counts of both channels and their scatter, or why there are none.
    pub fn push(
        &mut self,
        now_us: u64,
        counts: Option<[u16; 2]>,
    ) -> Option<Result<Means, CommandError>> {
        if let Some(c) = counts {
            for (k, &x) in c.iter().enumerate() {
                self.sum[k] += x as u64;
                self.sum_sq[k] += x as u64 * x as u64;
            }
            self.n += 1;
        }
        if now_us < self.end_us {
            return None;
        }
        if self.n == 0 {
            return Some(Err(CommandError::NoLoad));
        }
        // In integers: n·Σx² − (Σx)² is exact (< 2⁶³ for a window of 10⁵ 12-bit samples).
        let n = self.n as u64;
        let stat = |k: usize| {
            let spread = (n * self.sum_sq[k]).saturating_sub(self.sum[k] * self.sum[k]);
            let var = spread as f32 / (n * n) as f32;
            (self.sum[k] as f32 / n as f32, var)
        };
        let [(m1, s1), (m2, s2)] = [stat(0), stat(1)];
        Some(Ok(Means {
            counts: [m1, m2],
            variance: [s1, s2],
        }))
    }
}

/// The result of a measurement: mean counts and their standard deviation, T1 then T2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Means {
    /// Mean counts.
    pub counts: [f32; 2],
    /// Variance of the readings, counts².
    pub variance: [f32; 2],
}

/// Put a finished measurement into the calibration; the reply's two values, or why not.
///
/// Zero: both zeros become the means (the cord must be slack: nothing hangs on either sensor).
/// Weigh: `n_per_count = force / (mean − zero)` of that channel, so the zero must be right
/// first.
pub fn apply(what: Measuring, m: Means, cal: &mut Calibration) -> Result<[f32; 2], CommandError> {
    let channels: &[usize] = match what {
        Measuring::Zero => &[0, 1],
        Measuring::Weigh(ch, _) => &[ch as usize],
    };
    if channels
        .iter()
        .any(|&k| m.variance[k].is_nan() || m.variance[k] > MAX_VARIANCE)
    {
        return Err(CommandError::Unsteady);
    }
    let means = m.counts;
    match what {
        Measuring::Zero => {
            cal.t1.zero_counts = means[0];
            cal.t2.zero_counts = means[1];
            Ok(means)
        }
        Measuring::Weigh(channel, force_n) => {
            let ch = match channel {
                Channel::T1 => &mut cal.t1,
                Channel::T2 => &mut cal.t2,
            };
            let mean = means[channel as usize];
            let delta = mean - ch.zero_counts;
            if delta.abs() < MIN_WEIGH_COUNTS {
                return Err(CommandError::NoLoad);
            }
            // A weight pulls (the rig refuses a force ≤ 0 before measuring): a reading that
            // fell is a reversed sensor, whose sensitivity would come out of the wrong sign.
            if delta < 0.0 {
                return Err(CommandError::Reversed);
            }
            let n_per_count = force_n / delta;
            let (lo, hi) = crate::calib::N_PER_COUNT_RANGE;
            if !(n_per_count >= lo && n_per_count <= hi) {
                return Err(CommandError::Invalid);
            }
            ch.n_per_count = n_per_count;
            Ok([n_per_count, mean])
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_measure_averages_over_its_window_and_skips_failed_conversions() {
        let mut m = Measure::new(Measuring::Zero, 1_000);
        let mut t = 1_000;
        let mut out = None;
        while out.is_none() {
            let counts = (t % 3_000 != 0).then_some([400, 402]);
            out = m.push(t, counts);
            t += 1_000;
        }
        assert_eq!(t, 1_000 + 501_000);
        let m = out.unwrap().unwrap();
        assert_eq!(m.counts, [400.0, 402.0]);
        assert_eq!(m.variance, [0.0, 0.0]);
    }

    fn steady(counts: [f32; 2]) -> Means {
        Means {
            counts,
            variance: [1.7, 1.7],
        }
    }

    #[test]
    fn zero_then_weigh_give_the_sensitivity_of_the_known_weight() {
        let mut cal = Calibration::default();
        let r = apply(Measuring::Zero, steady([412.0, 388.0]), &mut cal);
        assert_eq!(r, Ok([412.0, 388.0]));
        // 1 kg on T2: 9.80665 N over 800 counts above its zero.
        let w = Measuring::Weigh(Channel::T2, 9.80665);
        let r = apply(w, steady([413.0, 1188.0]), &mut cal);
        let npc = 9.80665 / 800.0;
        assert_eq!(r, Ok([npc, 1188.0]));
        assert_eq!(cal.t2.n_per_count, npc);
        assert_eq!(cal.t1.n_per_count, Calibration::default().t1.n_per_count);
        // A weight that did not arrive on T1 is refused, and nothing changes.
        let before = cal;
        let r = apply(
            Measuring::Weigh(Channel::T1, 9.8),
            steady([420.0, 1188.0]),
            &mut cal,
        );
        assert_eq!(r, Err(CommandError::NoLoad));
        // A reversed sensor: the weight lowered the reading.
        assert_eq!(
            apply(
                Measuring::Weigh(Channel::T1, 9.8),
                steady([200.0, 1188.0]),
                &mut cal
            ),
            Err(CommandError::Reversed)
        );
        // A swinging weight is refused too.
        let swinging = Means {
            counts: [420.0, 1188.0],
            variance: [1.7, 81.0],
        };
        assert_eq!(apply(w, swinging, &mut cal), Err(CommandError::Unsteady));
        assert_eq!(cal, before);
    }
}
