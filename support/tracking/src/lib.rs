//! How well a force-controlled capstan rig tracks its T2 target (issue 43), from a time series
//! of the target and the measured T2 (the firmware's raw log: `t_s`, `t2_target_n`, `t2_n`).
//!
//! * [`steps`]: every step of the target (a jump followed by a hold): the steady-state error,
//!   the overshoot, the rise time (10-90 %) and the settling time;
//! * [`sine`]: every segment of a stepped sine sweep: the closed loop's gain and phase at its
//!   frequency, by least squares on whole cycles; the −3 dB bandwidth and the phase there.
//!
//! Pure functions of the samples: no file, no clock. The definitions are in each module and
//! in `docs/README-force.md`.
#![deny(missing_docs)]

pub mod sine;
pub mod steps;

pub use sine::{bandwidth, bode, Bandwidth, BodePoint};
pub use steps::{steps, SteadyWindow, StepResponse};

/// A target and the measured T2, sampled in time (the raw log's rows).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Trace {
    /// Time, s, rising.
    pub t_s: Vec<f64>,
    /// The T2 target, N (0: none).
    pub target_n: Vec<f64>,
    /// The measured T2, N.
    pub measured_n: Vec<f64>,
}

impl Trace {
    /// Samples.
    pub fn len(&self) -> usize {
        self.t_s.len()
    }

    /// No samples.
    pub fn is_empty(&self) -> bool {
        self.t_s.is_empty()
    }

    /// Add a sample (a NaN measurement is skipped: a failed conversion).
    pub fn push(&mut self, t_s: f64, target_n: f64, measured_n: f64) {
        if t_s.is_finite() && target_n.is_finite() && measured_n.is_finite() {
            self.t_s.push(t_s);
            self.target_n.push(target_n);
            self.measured_n.push(measured_n);
        }
    }

    /// The median sample interval, s (0 with fewer than two samples).
    pub fn interval_s(&self) -> f64 {
        let mut d: Vec<f64> = self.t_s.windows(2).map(|w| w[1] - w[0]).collect();
        if d.is_empty() {
            return 0.0;
        }
        d.sort_by(f64::total_cmp);
        d[d.len() / 2]
    }

    /// The measured T2 smoothed by a centred moving mean over `span_s` (the transient's shape
    /// without the sensor's white noise).
    pub fn smoothed(&self, span_s: f64) -> Vec<f64> {
        let dt = self.interval_s();
        let half = if dt > 0.0 {
            ((span_s / dt) / 2.0).floor() as usize
        } else {
            0
        };
        let n = self.len();
        let mut prefix = Vec::with_capacity(n + 1);
        prefix.push(0.0);
        for &y in &self.measured_n {
            prefix.push(prefix.last().copied().unwrap_or(0.0) + y);
        }
        (0..n)
            .map(|i| {
                let (a, b) = (i.saturating_sub(half), (i + half + 1).min(n));
                (prefix[b] - prefix[a]) / (b - a) as f64
            })
            .collect()
    }
}

fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        f64::NAN
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

fn sd(v: &[f64]) -> f64 {
    if v.len() < 2 {
        return 0.0;
    }
    let m = mean(v);
    (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
}
