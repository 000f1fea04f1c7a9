//! Descriptive tests on per-cord summaries (n = number of cords, so cord-to-cord variation is
//! the error term): straight lines of T2(T1) per cord and their intercept against slope, the
//! wrap pattern of the slopes, the low-tension loss by diameter, the run trend per cord, the
//! per-cord mu by diameter, and how much of the residual lives at the run level.

use super::CordLine;
use crate::analysis::metrics::ln_amp;
use crate::fit::obs::Row;
use crate::fit::solve::Fit;
use crate::fit::stats::{mean, one_sample_t, regress, welch, Regression};
use crate::fit::Observations;
use serde_json::{json, Value};

/// The per-cord summaries and their tests.
pub struct Summaries {
    /// Per-cord lines on the upper steps.
    pub cord_lines: Vec<CordLine>,
    /// (a, b, t of b) of c = a + b·s across cords.
    pub isl: (f64, f64, f64),
    /// The same with p and the implied offsets, for the JSON.
    pub isl_json: Value,
    /// ln(slope) against β across cords (a gain shows as exp(intercept) ≠ 1).
    pub gain_reg: Option<Regression>,
    /// (cord, diameter, mean ln-amp residual at T1 < 2 N) of the model without e1.
    pub low_tension_by_cord: Vec<(String, f64, f64)>,
    /// Those residuals on the smallest capstan.
    pub low_small: Vec<f64>,
    /// Those residuals on the other capstans.
    pub low_large: Vec<f64>,
    /// Welch test small against large: (t, df, p).
    pub low_test: Option<(f64, f64, f64)>,
    /// Per-cord slope of the run-mean ln residual (extended) on the run number.
    pub run_slopes: Vec<f64>,
    /// One-sample t of the run slopes: (mean, t, p).
    pub wear_t: Option<(f64, f64, f64)>,
    /// Per-cord Euler-Eytelwein mu on the smallest capstan.
    pub mu_small: Vec<f64>,
    /// Per-cord Euler-Eytelwein mu on the other capstans.
    pub mu_large: Vec<f64>,
    /// Welch test small against large: (t, df, p).
    pub mu_test: Option<(f64, f64, f64)>,
    /// Residual sum of squares (extended) of the run means, N².
    pub ss_run: f64,
    /// Residual sum of squares (extended), N².
    pub ss_tot: f64,
}

/// Compute the summaries. `no_e1` is the extended model without the T1-path loss.
pub fn compute(
    obs: &Observations,
    ext: &Fit,
    no_e1: Option<&Fit>,
    cord_mu: &[f64],
    diameters: &[f64],
) -> Summaries {
    let cord_lines = cord_lines(obs);
    let (isl, isl_json) = intercept_vs_slope(&cord_lines);
    let gain_reg = regress(
        &cord_lines
            .iter()
            .map(|c| vec![1.0, c.wrap_rad])
            .collect::<Vec<_>>(),
        &cord_lines.iter().map(|c| c.slope.ln()).collect::<Vec<_>>(),
        None,
        None,
    );
    // Low-tension loss by diameter under the model without e1 (bending predicts a larger loss
    // on the smaller capstan; a T1-path loss is the same on both).
    let mut low_tension_by_cord = Vec::new();
    if let Some(f) = no_e1 {
        for (g, grp) in obs.groups.iter().enumerate() {
            let r: Vec<f64> = obs
                .rows
                .iter()
                .enumerate()
                .filter(|(_, r)| r.group == g && r.t1_n < 2.0)
                .map(|(i, r)| ln_amp(r.t2_n, r.t1_n) - ln_amp(f.t2_n[i], r.t1_n))
                .collect();
            if !r.is_empty() {
                low_tension_by_cord.push((grp.label.clone(), grp.diameter_mm, mean(&r)));
            }
        }
    }
    let (low_small, low_large): (Vec<_>, Vec<_>) = low_tension_by_cord
        .iter()
        .partition(|c| c.1 == diameters[0]);
    let low_small: Vec<f64> = low_small.iter().map(|c| c.2).collect();
    let low_large: Vec<f64> = low_large.iter().map(|c| c.2).collect();
    let low_test =
        (low_small.len() >= 2 && low_large.len() >= 2).then(|| welch(&low_small, &low_large));
    // Wear at cord level: slope of the cord×run mean ln residual (extended, with cord effect)
    // on run.
    let mut run_slopes = Vec::new();
    for g in 0..obs.groups.len() {
        let (mut xs, mut ys) = (Vec::new(), Vec::new());
        for r in obs.runs_of_group(g) {
            let run = &obs.runs[r];
            let res: Vec<f64> = run
                .iter()
                .map(|&i| {
                    ln_amp(obs.rows[i].t2_n, obs.rows[i].t1_n)
                        - ln_amp(ext.t2_n[i], obs.rows[i].t1_n)
                })
                .collect();
            xs.push(vec![1.0, obs.rows[run[0]].op.run]);
            ys.push(mean(&res));
        }
        if xs.len() >= 3 {
            if let Some(r) = regress(&xs, &ys, None, None) {
                run_slopes.push(r.coef[1]);
            }
        }
    }
    let wear_t = (run_slopes.len() >= 3).then(|| one_sample_t(&run_slopes));
    // Diameter: per-cord Euler-Eytelwein mu, small against large capstan.
    let (mu_small, mu_large): (Vec<_>, Vec<_>) = obs
        .groups
        .iter()
        .zip(cord_mu)
        .partition(|(g, _)| g.diameter_mm == diameters[0]);
    let mu_small: Vec<f64> = mu_small.iter().map(|(_, m)| **m).collect();
    let mu_large: Vec<f64> = mu_large.iter().map(|(_, m)| **m).collect();
    let mu_test = (mu_small.len() >= 2 && mu_large.len() >= 2).then(|| welch(&mu_small, &mu_large));
    // Residual variance at the cord×run level (extended).
    let (mut ss_tot, mut ss_run) = (0.0, 0.0);
    for run in &obs.runs {
        let r: Vec<f64> = run
            .iter()
            .map(|&i| obs.rows[i].t2_n - ext.t2_n[i])
            .collect();
        let m = mean(&r);
        ss_run += m * m * r.len() as f64;
        ss_tot += r.iter().map(|x| x * x).sum::<f64>();
    }
    Summaries {
        cord_lines,
        isl,
        isl_json,
        gain_reg,
        low_tension_by_cord,
        low_small,
        low_large,
        low_test,
        run_slopes,
        wear_t,
        mu_small,
        mu_large,
        mu_test,
        ss_run,
        ss_tot,
    }
}

/// Per-cord lines on the upper steps (step ≥ 5, or T1 above the cord median without steps).
fn cord_lines(obs: &Observations) -> Vec<CordLine> {
    let mut out = Vec::new();
    for (g, grp) in obs.groups.iter().enumerate() {
        let rows: Vec<&Row> = obs.rows.iter().filter(|r| r.group == g).collect();
        let mut t1s: Vec<f64> = rows.iter().map(|r| r.t1_n).collect();
        t1s.sort_by(f64::total_cmp);
        let med = t1s[t1s.len() / 2];
        let sel: Vec<&&Row> = rows
            .iter()
            .filter(|r| r.step.map_or(r.t1_n >= med, |s| s >= 5.0))
            .collect();
        if sel.len() < 5 {
            continue;
        }
        let y: Vec<f64> = sel.iter().map(|r| r.t2_n).collect();
        let lin = regress(
            &sel.iter().map(|r| vec![1.0, r.t1_n]).collect::<Vec<_>>(),
            &y,
            None,
            None,
        );
        let quad = regress(
            &sel.iter()
                .map(|r| vec![1.0, r.t1_n, r.t1_n * r.t1_n])
                .collect::<Vec<_>>(),
            &y,
            None,
            None,
        );
        if let (Some(l), Some(q)) = (lin, quad) {
            out.push(CordLine {
                cord: grp.label.clone(),
                wrap_rad: grp.wrap_deg.to_radians(),
                intercept_n: l.coef[0],
                intercept_se: l.se[0],
                slope: l.coef[1],
                quadratic_t: q.t[2],
            });
        }
    }
    out
}

/// WLS c = a + b·s across cords: offsets predict c = e2 − e1·s, i.e. e1 = −b, e2 = a.
fn intercept_vs_slope(lines: &[CordLine]) -> ((f64, f64, f64), Value) {
    if lines.len() < 3 {
        return ((f64::NAN, f64::NAN, f64::NAN), Value::Null);
    }
    let x: Vec<Vec<f64>> = lines.iter().map(|c| vec![1.0, c.slope]).collect();
    let y: Vec<f64> = lines.iter().map(|c| c.intercept_n).collect();
    let w: Vec<f64> = lines
        .iter()
        .map(|c| 1.0 / c.intercept_se.powi(2).max(1e-12))
        .collect();
    match regress(&x, &y, Some(&w), None) {
        Some(r) => (
            (r.coef[0], r.coef[1], r.t[1]),
            json!({"a": r.coef[0], "b": r.coef[1], "t_b": r.t[1], "p_b": r.p[1], "implied_e1_n": -r.coef[1], "implied_e2_n": r.coef[0],
                   "intercepts_min_n": y.iter().cloned().fold(f64::INFINITY, f64::min), "intercepts_max_n": y.iter().cloned().fold(f64::NEG_INFINITY, f64::max)}),
        ),
        None => ((f64::NAN, f64::NAN, f64::NAN), Value::Null),
    }
}
