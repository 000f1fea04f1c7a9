//! Uncertainty of the gain: the RMSEs of every model, in-sample and leave-one-cord-out, with
//! 95 % intervals from a cluster bootstrap that resamples whole cords (never rows: a cord's
//! rows share its mu and its runs' noise; Field & Welsh 2007), their cord-jackknife standard
//! errors, and the held-out error of every cord.

use crate::fit::stats::jackknife_se;
use crate::fit::Observations;
use capstan_rng::Rng;
use serde::Serialize;

/// Cluster-bootstrap resamples.
pub const RESAMPLES: usize = 2000;

/// A 95 % interval.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Interval {
    /// 2.5 % point.
    pub lo: f64,
    /// 97.5 % point.
    pub hi: f64,
}

/// Per cord: the sum of squared errors and the rows of a prediction. A row without a finite
/// prediction is counted in `missing`, never as an error of 0.
#[derive(Clone, Debug)]
pub struct CordErrors {
    /// Σ (prediction − T2)² per cord, N².
    pub ss: Vec<f64>,
    /// Rows with a prediction per cord.
    pub n: Vec<usize>,
    /// Rows without one (not finite) per cord: a cord with any is not a held-out success.
    pub missing: Vec<usize>,
}

impl CordErrors {
    /// The errors of `pred` against the measured T2, cord by cord.
    pub fn of(obs: &Observations, pred: &[f64]) -> CordErrors {
        let g = obs.groups.len();
        let (mut ss, mut n, mut missing) = (vec![0.0; g], vec![0usize; g], vec![0usize; g]);
        for (r, p) in obs.rows.iter().zip(pred) {
            if p.is_finite() {
                ss[r.group] += (p - r.t2_n).powi(2);
                n[r.group] += 1;
            } else {
                missing[r.group] += 1;
            }
        }
        CordErrors { ss, n, missing }
    }

    /// These errors with the cords `out` left out (no rows, no error): what a statistic over
    /// the cords that have a prediction sees.
    pub fn without(&self, out: &[usize]) -> CordErrors {
        let mut e = self.clone();
        for &c in out {
            e.ss[c] = 0.0;
            e.n[c] = 0;
        }
        e
    }

    /// RMSE over the cords `pick` (with repetition), N.
    fn rmse_of(&self, pick: impl Iterator<Item = usize>) -> f64 {
        let (mut s, mut m) = (0.0, 0usize);
        for c in pick {
            s += self.ss[c];
            m += self.n[c];
        }
        (s / m.max(1) as f64).sqrt()
    }

    /// RMSE over all cords, N.
    pub fn rmse(&self) -> f64 {
        self.rmse_of(0..self.ss.len())
    }

    /// RMSE of cord `c` alone, N.
    pub fn cord_rmse(&self, c: usize) -> f64 {
        // A cord with any row left unpredicted (a failed fold) has no held-out error: NaN,
        // never the 0 its empty sum would give.
        if self.missing[c] > 0 || self.n[c] == 0 {
            return f64::NAN;
        }
        (self.ss[c] / self.n[c] as f64).sqrt()
    }
}

/// A figure with its uncertainty.
#[derive(Clone, Debug, Serialize)]
pub struct WithInterval {
    /// The figure.
    pub value: f64,
    /// 95 % cluster-bootstrap interval (cords resampled).
    pub ci95: Interval,
    /// Cord-jackknife standard error.
    pub jackknife_se: f64,
}

fn percentile(v: &mut [f64], q: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        return f64::NAN;
    }
    let pos = q * (v.len() - 1) as f64;
    let (i, f) = (pos.floor() as usize, pos - pos.floor());
    if i + 1 < v.len() {
        v[i] * (1.0 - f) + v[i + 1] * f
    } else {
        v[i]
    }
}

/// A statistic of cord-level errors with its bootstrap interval and jackknife SE.
/// `stat(weights)` gets each cord's multiplicity in the resample.
fn with_interval(g: usize, seed: u64, stat: impl Fn(&[usize]) -> f64) -> WithInterval {
    let all = vec![1usize; g];
    let value = stat(&all);
    let mut rng = Rng::new(seed);
    let mut boot: Vec<f64> = (0..RESAMPLES)
        .map(|_| {
            let mut w = vec![0usize; g];
            for _ in 0..g {
                w[(rng.uniform() * g as f64) as usize % g] += 1;
            }
            stat(&w)
        })
        .filter(|v| v.is_finite())
        .collect();
    let jack: Vec<f64> = (0..g)
        .map(|c| {
            let mut w = all.clone();
            w[c] = 0;
            stat(&w)
        })
        .collect();
    WithInterval {
        value,
        ci95: Interval {
            lo: percentile(&mut boot, 0.025),
            hi: percentile(&mut boot, 0.975),
        },
        jackknife_se: if g >= 2 {
            jackknife_se(&jack)
        } else {
            f64::NAN
        },
    }
}

fn weighted(e: &CordErrors, w: &[usize]) -> f64 {
    e.rmse_of(
        w.iter()
            .enumerate()
            .flat_map(|(c, &k)| std::iter::repeat_n(c, k)),
    )
}

/// The RMSE of `e` with its uncertainty.
pub fn rmse(e: &CordErrors, seed: u64) -> WithInterval {
    with_interval(e.ss.len(), seed, |w| weighted(e, w))
}

/// The ratio of two RMSEs (`num` over `den`, same cords) with its uncertainty: the gain.
pub fn ratio(num: &CordErrors, den: &CordErrors, seed: u64) -> WithInterval {
    with_interval(num.ss.len(), seed, |w| weighted(num, w) / weighted(den, w))
}

/// One cord's held-out errors.
#[derive(Clone, Debug, Serialize)]
pub struct HeldOut {
    /// Cord label.
    pub cord: String,
    /// Rows.
    pub rows: usize,
    /// RMSE of T2 of each model predicting this cord from the others, N (model name, RMSE).
    pub rmse_t2_n: Vec<(String, f64)>,
    /// The extended model predicts this cord better than Euler-Eytelwein.
    pub extended_better: bool,
}

/// Every cord's held-out RMSE under each model's leave-one-cord-out predictions.
pub fn held_out(obs: &Observations, models: &[(&str, &CordErrors)]) -> Vec<HeldOut> {
    let get = |name: &str, c: usize| {
        models
            .iter()
            .find(|m| m.0 == name)
            .map_or(f64::NAN, |m| m.1.cord_rmse(c))
    };
    obs.groups
        .iter()
        .enumerate()
        .map(|(c, g)| HeldOut {
            cord: g.label.clone(),
            rows: models.first().map_or(0, |m| m.1.n[c]),
            rmse_t2_n: models
                .iter()
                .map(|(name, e)| (name.to_string(), e.cord_rmse(c)))
                .collect(),
            // NaN (a failed fold on either side) compares false: never a held-out success.
            extended_better: get("extended", c) < get("baseline", c),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bootstrap_and_jackknife_of_a_known_case() {
        // Ten cords with squared errors 1..10 (one row each): RMSE √5.5.
        let e = CordErrors {
            ss: (1..=10).map(f64::from).collect(),
            n: vec![1; 10],
            missing: vec![0; 10],
        };
        let r = rmse(&e, 7);
        assert!((r.value - 5.5f64.sqrt()).abs() < 1e-12);
        assert!(r.ci95.lo < r.value && r.value < r.ci95.hi, "{r:?}");
        // The jackknife SE of a mean of squares, through the square root (delta method).
        let var_mean = crate::fit::stats::variance(&e.ss) / 10.0;
        let delta = var_mean.sqrt() / (2.0 * 5.5f64.sqrt());
        assert!(
            (r.jackknife_se / delta - 1.0).abs() < 0.05,
            "{r:?} vs {delta}"
        );
        // A ratio of a model with itself is exactly 1, with no spread.
        let q = ratio(&e, &e, 7);
        assert!((q.value - 1.0).abs() < 1e-12 && q.ci95.hi - q.ci95.lo < 1e-12);
    }
}
