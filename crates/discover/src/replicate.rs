//! The replicate-run gate: does a within-run term explain what the replicate runs *share*?
//!
//! The screen's statistic ([`crate::screen::within_evidence`]) credits a term with every
//! row's covariance between its column and the residuals, including the covariance *between
//! replicate runs of the same step*. At the thesis rig's noise that part is not empty: the slow
//! wander of mu inside a run moves a run's loads and its residuals together, so a load-shaped
//! term (`heat_per_wrap`, `t1_lowforce`, …) can fit the run-to-run wander and pass the screen's
//! bar with a catalogue-only truth (note-26: 2–3 false proposals in 12). Physics that is really
//! there is shared by every replicate run of a cell (cord × step).
//!
//! So a term must also earn its evidence on the replicate cells' means: its column is replaced
//! by its cell mean x̄_c, and the score U = Σ_runs u_r, u_r = Σ_{rows of run r} √w·e·x̄_c(i)·√w,
//! is judged against the sign-flip null of whole runs (the null of the engine's lack-of-fit
//! test: under it each run's residuals are symmetric noise, wander included), through its
//! exact variance Σ u_r²: z² = U²/Σ u_r² → χ²₁, ΔBIC = −z² + ln n, held to the same bar as the
//! screen. A run-clustered statistic: wander that is run-specific cancels in U and inflates
//! Σ u_r², whatever its correlation along the run.

use crate::columns::Base;

/// The replicate-run evidence of one within-run term.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Replicate {
    /// The score over its sign-flip standard deviation.
    pub z: f64,
    /// ΔBIC = −z² + ln n.
    pub delta_bic: f64,
    /// θ fitted to the replicate cells' means (what the runs share).
    pub theta_shared: f64,
    /// Replicate cells used (with at least two runs).
    pub cells: usize,
}

/// The replicate evidence of projected column `xt` against projected residuals `e`; None
/// without replicate cells (each step seen by one run only).
pub fn replicate_evidence(base: &Base, xt: &[f64], e: &[f64]) -> Option<Replicate> {
    let d = base.d;
    let n_cells = d.cell.iter().flatten().map(|&c| c + 1).max().unwrap_or(0);
    let mut cnt = vec![0usize; n_cells];
    let mut sum_x = vec![0.0; n_cells];
    for (i, c) in d.cell.iter().enumerate() {
        if let Some(c) = *c {
            cnt[c] += 1;
            sum_x[c] += base.w[i].sqrt() * xt[i];
        }
    }
    let used = cnt.iter().filter(|&&c| c >= 2).count();
    if used < 4 {
        return None;
    }
    let xbar: Vec<f64> = (0..n_cells)
        .map(|c| {
            if cnt[c] >= 2 {
                sum_x[c] / cnt[c] as f64
            } else {
                0.0
            }
        })
        .collect();
    let (mut u_sum, mut u_sq, mut xx) = (0.0, 0.0, 0.0);
    for rows in &d.units {
        let mut u = 0.0;
        for &i in rows {
            if let Some(c) = d.cell[i] {
                u += base.w[i].sqrt() * e[i] * xbar[c];
                xx += xbar[c] * xbar[c];
            }
        }
        u_sum += u;
        u_sq += u * u;
    }
    if !(u_sq > 0.0 && xx > 0.0) {
        return None;
    }
    let z = u_sum / u_sq.sqrt();
    let n = d.n() as f64;
    let out = Replicate {
        z,
        delta_bic: -z * z + n.ln(),
        theta_shared: u_sum / xx,
        cells: used,
    };
    [out.z, out.delta_bic, out.theta_shared]
        .iter()
        .all(|v| v.is_finite())
        .then_some(out)
}
