//! What any test of the cords' mu could reach on the planted truths of [`crate::cord_cases`]:
//! the power of an oracle that sees every cord's mean mu with only the planted scatter of mu
//! (cord to cord, and the runs' scatter averaged over the cord's runs) — no T2 zero, no
//! heating, no noise of a fit — and tests the planted change by a t test over the cords with
//! the change's own shape as the covariate (the most powerful test of that shape). An engine
//! that must also estimate each cord's mu from its pairs, beside its T2 zero and heating, and
//! that must not know the shape in advance, can do no better; if this bound is under 80 % at a
//! level, no rule for the between-cord questions reaches 80 % at that level on that design.
//!
//! The shapes, over a cord's wrap β and diameter D (ln of the cord's mu over the base mu):
//! * [`Truth::Diameter`]: ±c/2 on the two capstans (c the planted fraction);
//! * [`Truth::WrapTurn`]: ln((2π + (1 + r)(β − 2π))/β) beyond one turn, 0 up to it — linear
//!   in r·(β − 2π)/β. The engine's wrap-dependent term on mu (a T2 gain, mu + ln g/β) has 1/β
//!   as its covariate: its oracle power is reported too.

use crate::cord_cases::{CordCase, Truth, THESIS_SCATTER};
use capstan_engine::fit::stats::regress;
use capstan_sim::plant::rng::{derive_seed, Rng};
use serde::Serialize;
use std::f64::consts::PI;

/// The oracle's power on one truth and design.
#[derive(Clone, Debug, Serialize)]
pub struct Bound {
    /// The planted truth.
    #[serde(serialize_with = "truth_name")]
    pub truth: Truth,
    /// Cords in a set.
    pub cords: usize,
    /// The test's two-sided level.
    pub alpha: f64,
    /// Share of sets in which the t test of the planted shape rejects.
    pub power_planted_shape: f64,
    /// Share in which the t test of the engine's covariate (diameter; 1/β for the wrap)
    /// rejects.
    pub power_engine_covariate: f64,
    /// Sets drawn.
    pub sets: usize,
}

fn truth_name<S: serde::Serializer>(t: &Truth, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(t.name())
}

/// ln of a cord's mu over the base mu under the planted `change` of `truth`.
fn planted(truth: Truth, change: f64, diameter_first: bool, wrap_deg: f64) -> f64 {
    let b = wrap_deg.to_radians();
    let turn = 2.0 * PI;
    match truth {
        Truth::Diameter => (1.0 + change / 2.0 * if diameter_first { -1.0 } else { 1.0 }).ln(),
        Truth::WrapTurn if b > turn => ((turn + (1.0 + change) * (b - turn)) / b).ln(),
        _ => 0.0,
    }
}

/// The oracle's covariates of a cord: (the planted shape, the engine's).
fn covariates(truth: Truth, diameter_first: bool, wrap_deg: f64) -> (f64, f64) {
    let b = wrap_deg.to_radians();
    match truth {
        Truth::WrapTurn => (((b - 2.0 * PI) / b).max(0.0), 1.0 / b),
        _ => {
            let x = f64::from(u8::from(!diameter_first));
            (x, x)
        }
    }
}

/// The oracle's power on `sets` thesis-design sets of `truth` with `replicates` new cords per
/// (diameter, wrap) and the planted scatter of mu, at the two-sided level `alpha`; the changes
/// drawn as [`CordCase::many`] draws them from `seed`.
pub fn oracle(truth: Truth, replicates: u32, alpha: f64, sets: usize, seed: u64) -> Bound {
    let s = THESIS_SCATTER;
    let (sd_cord, sd_runs) = (s.mu_pct / 100.0, s.run_pct / 100.0);
    let mut hits = (0usize, 0usize);
    let mut cords = 0;
    for (i, case) in CordCase::many(truth, seed, sets).into_iter().enumerate() {
        let mut rng = Rng::new(derive_seed(seed, &[0x0b0d, i as u64]));
        let sd = (sd_cord.powi(2) + sd_runs.powi(2) / f64::from(case.runs)).sqrt();
        let (mut y, mut x_shape, mut x_engine) = (Vec::new(), Vec::new(), Vec::new());
        for _ in 0..replicates {
            for (k, _) in case.diameters_mm.iter().enumerate() {
                for &w in &case.wraps_deg {
                    let first = k == 0;
                    y.push(planted(truth, case.change, first, w) + sd * rng.normal());
                    let (a, b) = covariates(truth, first, w);
                    x_shape.push(vec![1.0, a]);
                    x_engine.push(vec![1.0, b]);
                }
            }
        }
        cords = y.len();
        let rejects = |x: &[Vec<f64>]| regress(x, &y, None, None).is_some_and(|r| r.p[1] < alpha);
        hits.0 += usize::from(rejects(&x_shape));
        hits.1 += usize::from(rejects(&x_engine));
    }
    Bound {
        truth,
        cords,
        alpha,
        power_planted_shape: hits.0 as f64 / sets.max(1) as f64,
        power_engine_covariate: hits.1 as f64 / sets.max(1) as f64,
        sets,
    }
}

impl Bound {
    /// The bound in one line.
    pub fn line(&self) -> String {
        format!(
            "oracle bound, {} at {} cords, two-sided {}: the planted shape's t test {:.0} %, the engine's covariate's {:.0} % ({} sets)",
            self.truth.name(),
            self.cords,
            self.alpha,
            100.0 * self.power_planted_shape,
            100.0 * self.power_engine_covariate,
            self.sets
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bound_has_its_size_under_the_null_and_grows_with_the_cords() {
        // No change planted: the t test rejects at its level (5 % ± 1.5 % over 2,000 sets).
        let null = oracle(Truth::Null, 1, 0.05, 2000, 3);
        assert!(
            (0.035..=0.065).contains(&null.power_planted_shape),
            "{null:?}"
        );
        // Three cords per cell find a diameter change more often than one.
        let one = oracle(Truth::Diameter, 1, 0.004, 1000, 3);
        let three = oracle(Truth::Diameter, 3, 0.004, 1000, 3);
        assert_eq!((one.cords, three.cords), (10, 30));
        assert!(three.power_planted_shape > one.power_planted_shape + 0.1);
    }

    #[test]
    fn a_change_beyond_one_turn_is_linear_in_one_over_the_wrap() {
        // mu·(2π + (1 + r)(β − 2π))/β = mu·(1 + r − 2πr/β) beyond one turn.
        let r = 0.2;
        for w in [450.0, 630.0, 720.0] {
            let b: f64 = f64::to_radians(w);
            let want = (1.0 + r - 2.0 * PI * r / b).ln();
            assert!((planted(Truth::WrapTurn, r, true, w) - want).abs() < 1e-12);
        }
        assert_eq!(planted(Truth::WrapTurn, r, true, 360.0), 0.0);
    }
}
