//! The replicate-run gate: does a within-run term explain what the replicate runs *share*?
//!
//! The screen's statistic ([`crate::screen::within_evidence`]) credits a term with every
//! row's covariance between its column and the residuals. At the thesis rig's noise part of
//! that covariance is not physics: the slow wander of mu inside a run moves the run's residuals
//! *and* its measured T1 (the lever settles where the capstan's amplification puts it), so a
//! column built from the run's own T1 or load co-varies with the run's own wander, with a mean
//! that is not zero (an errors-in-variables bias, not noise: a run-clustered variance does not
//! remove it). A load-shaped term (`heat_per_wrap`, `t1_lowforce`, …) then fits the wander and
//! passed the screen's bar on catalogue-only sets (note-26: 2–3 in 12). Physics that is really
//! there is shared by every replicate run of a cell (cord × step).
//!
//! So the gate replaces the term's column, row by row, by its mean over the **other** runs of
//! the row's replicate cell, x̃ (the run's own wander cannot enter it), and scores each run,
//! u_r = Σ_{rows of r} √w·e·x̃. Under the null of the engine's lack-of-fit test (each run's
//! residuals symmetric noise, wander included, independent between runs) every u_r has mean
//! zero, whatever the number of runs or the wander's memory. The gate is the one-sample
//! Student t of the u_r over the R runs that have replicated rows (t_{R−1}), **one-sided in
//! the direction of the screen's θ̂**: the shared part must carry the term with its sign. The
//! search's bar has already paid for choosing the term among every model tried; the gate is one
//! test of the chosen term, at its own level [`crate::Options::replicate_alpha`], set on the
//! calibration seed (docs/README-discover.md).
//!
//! The s32 rule ([`ReplicateRule::SearchBar`]) is kept for the calibration's comparison: the
//! cell means with the run's own row in, the uncentred sign-flip variance z² = U²/Σu_r², and
//! ΔBIC = −z² + ln n held to the search's whole bar. Since z² = R·t²/(t² + R − 1) < R, that
//! bar (z² > 21 with 78 models and 720 rows) cannot be passed at all with 21 runs or fewer, and
//! needs t² > 71 with 30.

use crate::columns::Base;
use statrs::distribution::{ContinuousCDF, StudentsT};

/// How the replicate gate decides.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ReplicateRule {
    /// The one-sided t of the runs' shared scores at `Options::replicate_alpha` (since s41).
    Share,
    /// s32-s35: ΔBIC on the cell means (own run in, uncentred variance) against the search's bar.
    SearchBar,
}

/// The replicate-run evidence of one within-run term.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Replicate {
    /// Student t of the runs' shared scores (the other runs' cell means of the column).
    pub t: f64,
    /// Its degrees of freedom: runs with replicated rows − 1.
    pub df: f64,
    /// One-sided p of t in the direction of the screen's θ̂ (t_{df}).
    pub p: f64,
    /// θ fitted to what the replicate runs share.
    pub theta_shared: f64,
    /// θ_shared over the screen's θ̂: the share of the term the replicate runs carry.
    pub share: f64,
    /// Replicate cells used (seen by at least two runs).
    pub cells: usize,
    /// s32's statistic: the score over its uncentred sign-flip SD, cell means with the run's own
    /// row in.
    pub z: f64,
    /// s32's ΔBIC = −z² + ln n.
    pub delta_bic: f64,
    /// Whether the term passes the gate (at the search's first bar for the s32 rule).
    pub passed: bool,
}

/// The gate's settings at one step: its rule, its level (Share) and the search's bar
/// (SearchBar).
#[derive(Clone, Copy, Debug)]
pub struct Gate {
    /// How it decides.
    pub rule: ReplicateRule,
    /// Level of the one-sided test (Share).
    pub alpha: f64,
    /// The search's bar (SearchBar).
    pub bar: f64,
}

impl Gate {
    /// Does a term with replicate evidence `r` pass (no evidence: the gate cannot be applied,
    /// so it does not stop the term; the answer says so)?
    pub fn lets_through(&self, r: Option<&Replicate>) -> bool {
        r.is_none_or(|r| r.passes(self.rule, self.alpha, self.bar))
    }

    /// The same gate at another bar.
    pub fn at(self, bar: f64) -> Gate {
        Gate { bar, ..self }
    }
}

impl Replicate {
    /// Does the term pass the gate under `rule` at level `alpha` (Share) or `bar` (SearchBar)?
    pub fn passes(&self, rule: ReplicateRule, alpha: f64, bar: f64) -> bool {
        match rule {
            ReplicateRule::Share => self.p < alpha,
            ReplicateRule::SearchBar => self.delta_bic < bar,
        }
    }
}

/// Per replicate cell: the sum of √w·x and the rows, over all runs and per run.
struct Cells {
    sum: Vec<f64>,
    cnt: Vec<f64>,
    /// Distinct runs seen per cell.
    runs: Vec<usize>,
}

impl Cells {
    fn new(base: &Base, xt: &[f64]) -> Cells {
        let d = base.d;
        let n = d.cell.iter().flatten().map(|&c| c + 1).max().unwrap_or(0);
        let (mut sum, mut cnt, mut runs) = (vec![0.0; n], vec![0.0; n], vec![0usize; n]);
        let mut last = vec![usize::MAX; n];
        for (u, rows) in d.units.iter().enumerate() {
            for &i in rows {
                if let Some(c) = d.cell[i] {
                    sum[c] += base.w[i].sqrt() * xt[i];
                    cnt[c] += 1.0;
                    if last[c] != u {
                        last[c] = u;
                        runs[c] += 1;
                    }
                }
            }
        }
        Cells { sum, cnt, runs }
    }
}

/// The replicate evidence of projected column `xt` against projected residuals `e`, for a term
/// whose screen estimate is `theta`; judged at `alpha` (Share) or `bar` (SearchBar). None
/// without replicate cells (fewer than 4 cells seen by two runs) or fewer than 3 runs with
/// replicated rows.
pub fn replicate_evidence(
    base: &Base,
    xt: &[f64],
    e: &[f64],
    theta: f64,
    gate: Gate,
) -> Option<Replicate> {
    let d = base.d;
    let cells = Cells::new(base, xt);
    let used = cells.runs.iter().filter(|&&r| r >= 2).count();
    if used < 4 {
        return None;
    }
    let (mut u, mut u_own) = (Vec::new(), Vec::new());
    let (mut xx, mut xx_own) = (0.0, 0.0);
    for rows in &d.units {
        // The run's own part of each of its cells (a run may see a cell more than once).
        let mut own: std::collections::HashMap<usize, (f64, f64)> = Default::default();
        for &i in rows {
            if let Some(c) = d.cell[i] {
                let o = own.entry(c).or_default();
                o.0 += base.w[i].sqrt() * xt[i];
                o.1 += 1.0;
            }
        }
        let (mut ur, mut ur_own, mut any) = (0.0, 0.0, false);
        for &i in rows {
            let Some(c) = d.cell[i].filter(|&c| cells.runs[c] >= 2) else {
                continue;
            };
            let (s_own, n_own) = own[&c];
            let x_other = (cells.sum[c] - s_own) / (cells.cnt[c] - n_own);
            let x_all = cells.sum[c] / cells.cnt[c];
            let we = base.w[i].sqrt() * e[i];
            ur += we * x_other;
            ur_own += we * x_all;
            xx += x_other * x_other;
            xx_own += x_all * x_all;
            any = true;
        }
        if any {
            u.push(ur);
            u_own.push(ur_own);
        }
    }
    let r = u.len() as f64;
    if r < 3.0 || !(xx > 0.0 && xx_own > 0.0) {
        return None;
    }
    let mean = u.iter().sum::<f64>() / r;
    let var = u.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (r - 1.0);
    let t = mean / (var / r).sqrt();
    let df = r - 1.0;
    let dir = if theta < 0.0 { -1.0 } else { 1.0 };
    let p = StudentsT::new(0.0, 1.0, df).ok()?.sf(dir * t);
    let u_sum: f64 = u.iter().sum();
    let theta_shared = u_sum / xx;
    let own_sum: f64 = u_own.iter().sum();
    let z = own_sum / u_own.iter().map(|v| v * v).sum::<f64>().sqrt();
    let mut out = Replicate {
        t,
        df,
        p,
        theta_shared,
        share: theta_shared / theta,
        cells: used,
        z,
        delta_bic: -z * z + (d.n() as f64).ln(),
        passed: false,
    };
    out.passed = out.passes(gate.rule, gate.alpha, gate.bar);
    [out.t, out.p, out.theta_shared, out.z, out.delta_bic]
        .iter()
        .all(|v| v.is_finite())
        .then_some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use capstan_rng::Rng;

    /// The thesis design's rows, runs and cells (60 runs, 6 a cord), linearised.
    fn thesis() -> capstan_engine::evidence::Assessment {
        let data = capstan_data::thesis_dataset();
        capstan_engine::evidence::assess(&data, &Default::default())
    }

    /// A column g (load-shaped) whose value in each run carries that run's wander s_r, and
    /// residuals that carry the same wander: the screen's covariance is biased, the runs share
    /// nothing.
    fn wander(base: &Base, rng: &mut Rng, shared: f64) -> (Vec<f64>, Vec<f64>) {
        let d = base.d;
        let (mut x, mut e) = (vec![0.0; d.n()], vec![0.0; d.n()]);
        for rows in &d.units {
            let s = rng.normal();
            for &i in rows {
                let g = d.t1[i] / 10.0;
                x[i] = g * (1.0 + 0.3 * s);
                e[i] = (0.2 * s + shared) * g + 0.05 * rng.normal();
            }
        }
        (x, e)
    }

    #[test]
    fn the_gate_has_its_size_under_run_wander_and_its_power_on_shared_physics() {
        let a = thesis();
        let base = Base::new(&a.design, &a.fit, &a.weights.w);
        let gate = Gate {
            rule: ReplicateRule::Share,
            alpha: 0.05,
            bar: -14.7,
        };
        let mut rng = Rng::new(41);
        let (mut rejected, mut mean_t, mut s32_mean_z, draws) = (0, 0.0, 0.0, 400);
        for _ in 0..draws {
            let (x, e) = wander(&base, &mut rng, 0.0);
            let r = replicate_evidence(&base, &x, &e, 1.0, gate).expect("cells");
            rejected += usize::from(r.passed);
            mean_t += r.t / draws as f64;
            s32_mean_z += r.z / draws as f64;
        }
        // One-sided 5 %: 20 of 400 expected; binomial 99.9 % upper end ≈ 36.
        assert!(rejected <= 36, "{rejected} of {draws}");
        // The other runs' cell means: the score is centred (its mean over 400 draws has SD
        // ≈ 0.05); with the run's own row in (s32), its wander biases it upwards.
        assert!(mean_t.abs() < 0.15, "{mean_t}");
        assert!(s32_mean_z > 0.2, "{s32_mean_z}");
        // Physics the runs share (three quarters of the wander's SD), the same wander on top.
        let mut found = 0;
        for _ in 0..100 {
            let (x, e) = wander(&base, &mut rng, 0.15);
            // The screen's θ̂ would be about the shared 0.15: the runs carry all of it.
            let r = replicate_evidence(&base, &x, &e, 0.15, gate).expect("cells");
            found += usize::from(r.p < 0.01 && (r.share - 1.0).abs() < 0.5);
        }
        assert!(found >= 95, "{found} of 100");
    }

    #[test]
    fn without_replicate_cells_there_is_no_gate() {
        let a = thesis();
        let base = Base::new(&a.design, &a.fit, &a.weights.w);
        let mut d = a.design.clone();
        d.cell = vec![None; d.n()];
        let base = Base { d: &d, ..base };
        let x = vec![1.0; d.n()];
        let gate = Gate {
            rule: ReplicateRule::Share,
            alpha: 0.01,
            bar: -14.7,
        };
        assert!(replicate_evidence(&base, &x, &x, 1.0, gate).is_none());
        assert!(gate.lets_through(None));
    }
}
