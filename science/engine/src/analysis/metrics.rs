//! The gain table: per model its parameter count, RMSE of T2 and of ln(T2/T1), leave-one-cord-out
//! RMSE, AIC/BIC (mixed and strict counts) and per-cord R² of amplification; and the thesis's
//! per-angle R², recomputed.

use super::fits::Fits;
use super::thesis;
use super::uncertainty::{self, CordErrors, WithInterval};
use crate::fit::solve::information_criteria;
use crate::fit::stats::{median, r_squared};
use crate::fit::Observations;
use serde::Serialize;

/// Parameter counts, spelled out.
#[derive(Clone, Debug, Serialize)]
pub struct ParamCount {
    /// Fixed (population) values.
    pub fixed: usize,
    /// Variance components (1 with per-cord random effects).
    pub variance_components: usize,
    /// Effective degrees of freedom of the per-cord effects (0 without them).
    pub edf_random: f64,
    /// Values set per group without shrinkage (per-cord mu, Table 3's per-angle numbers).
    pub per_group_values: usize,
    /// Which count `n_params` uses.
    pub rule: &'static str,
}

/// R² of amplification of one cord.
#[derive(Clone, Debug, Serialize)]
pub struct CordR2 {
    /// Cord label.
    pub cord: String,
    /// 1 − SS_res/SS_tot on T2/T1 over the cord's rows.
    pub r2: f64,
}

/// One row of the gain table.
#[derive(Clone, Debug, Serialize)]
pub struct ModelMetrics {
    /// `baseline`, `baseline_per_cord`, `thesis`, `extended`, ...
    pub name: String,
    /// What it is.
    pub description: String,
    /// Number of fitted values under `n_params_detail.rule`.
    pub n_params: f64,
    /// The count spelled out.
    pub n_params_detail: ParamCount,
    /// Strict count: fixed + effective dof of the random effects (+ per-group values).
    pub n_params_strict: f64,
    /// In-sample RMSE of T2, N.
    pub rmse_t2_n: f64,
    /// In-sample RMSE of ln(T2/T1), over the rows where the predicted T2 is above zero ...
    pub rmse_ln_amp: f64,
    /// ... and the rows left out of it: a predicted T2 at or below zero (no logarithm).
    pub ln_amp_undefined_rows: usize,
    /// Leave-one-cord-out RMSE of T2, N (None if the model cannot be refitted).
    pub loco_rmse_t2_n: Option<f64>,
    /// In-sample RMSE of T2 with its 95 % cord-bootstrap interval and cord-jackknife SE.
    pub rmse_t2_uncertainty: WithInterval,
    /// Leave-one-cord-out RMSE of T2 with its uncertainty.
    pub loco_rmse_t2_uncertainty: Option<WithInterval>,
    /// AIC with `n_params`.
    pub aic: f64,
    /// BIC with `n_params`.
    pub bic: f64,
    /// AIC with the strict count.
    pub aic_strict: f64,
    /// BIC with the strict count.
    pub bic_strict: f64,
    /// Per-cord R² of amplification.
    pub per_cord_r2_amp: Vec<CordR2>,
    /// Median of `per_cord_r2_amp`.
    pub per_cord_r2_amp_median: f64,
    /// Fitted values (population), by name.
    pub values: Vec<(String, f64)>,
}

/// The thesis's per-angle R² of amplification, recomputed.
#[derive(Clone, Debug, Serialize)]
pub struct AngleR2 {
    /// Wrap angle, deg.
    pub wrap_deg: f64,
    /// R² (pooled over diameters).
    pub r2: f64,
    /// Rows.
    pub rows: usize,
}

/// ln(max(T2, 1 mN)/T1): the log amplification used for log metrics.
pub fn ln_amp(t2_n: f64, t1_n: f64) -> f64 {
    (t2_n.max(1e-3) / t1_n).ln()
}

/// ln(T2/T1) where both tensions are above zero (None where the logarithm is not defined: a
/// model can predict a T2 at or below zero, which no floor would make a residual of).
pub fn ln_amp_defined(t2_n: f64, t1_n: f64) -> Option<f64> {
    (t2_n > 0.0 && t1_n > 0.0 && t2_n.is_finite() && t1_n.is_finite()).then(|| (t2_n / t1_n).ln())
}

/// RMSE of ln(T2/T1), predicted against measured, over the rows where both are defined, and
/// the rows with a finite prediction where the predicted T2 is at or below zero (left out).
pub fn rmse_ln_amp(obs: &Observations, pred: &[f64]) -> (f64, usize) {
    let (mut s, mut n, mut undefined) = (0.0, 0usize, 0usize);
    for (r, p) in obs.rows.iter().zip(pred) {
        let m = ln_amp_defined(r.t2_n, r.t1_n);
        match (ln_amp_defined(*p, r.t1_n), m) {
            (Some(x), Some(y)) => {
                s += (x - y).powi(2);
                n += 1;
            }
            (None, Some(_)) if p.is_finite() => undefined += 1,
            _ => {}
        }
    }
    ((s / n as f64).sqrt(), undefined)
}

/// Per-cord R² of amplification.
pub fn per_cord_r2(obs: &Observations, pred: &[f64]) -> Vec<CordR2> {
    obs.groups
        .iter()
        .enumerate()
        .map(|(g, grp)| {
            let idx = obs.rows_of_group(g);
            let m: Vec<f64> = idx
                .iter()
                .map(|&i| obs.rows[i].t2_n / obs.rows[i].t1_n)
                .collect();
            let p: Vec<f64> = idx.iter().map(|&i| pred[i] / obs.rows[i].t1_n).collect();
            CordR2 {
                cord: grp.label.clone(),
                r2: r_squared(&m, &p),
            }
        })
        .collect()
}

/// How a model enters the gain table.
struct Entry<'a> {
    name: &'a str,
    description: &'a str,
    pred: &'a [f64],
    loco: Option<&'a [f64]>,
    count: ParamCount,
    n_params: f64,
    n_strict: f64,
    values: Vec<(String, f64)>,
}

fn metrics(obs: &Observations, e: Entry<'_>) -> ModelMetrics {
    let rss: f64 = obs
        .rows
        .iter()
        .zip(e.pred)
        .map(|(r, p)| (p - r.t2_n).powi(2))
        .sum();
    let (aic, bic) = information_criteria(rss, obs.len(), e.n_params);
    let (aic_s, bic_s) = information_criteria(rss, obs.len(), e.n_strict);
    let per_cord = per_cord_r2(obs, e.pred);
    let (rmse_ln, ln_undefined) = rmse_ln_amp(obs, e.pred);
    let mut r2s: Vec<f64> = per_cord.iter().map(|c| c.r2).collect();
    let seed = e
        .name
        .bytes()
        .fold(0u64, |a, b| a.wrapping_mul(31).wrapping_add(b as u64));
    // Leaving one cord out needs two: with one (or no held-out prediction at all) there is no
    // held-out RMSE, not one of 0 N.
    let loco = e
        .loco
        .filter(|p| obs.groups.len() >= 2 && p.iter().any(|x| x.is_finite()))
        .map(|p| uncertainty::rmse(&CordErrors::of(obs, p), seed ^ 1));
    ModelMetrics {
        name: e.name.into(),
        description: e.description.into(),
        n_params: e.n_params,
        n_params_detail: e.count,
        n_params_strict: e.n_strict,
        rmse_t2_n: obs.rmse_t2(e.pred),
        rmse_ln_amp: rmse_ln,
        ln_amp_undefined_rows: ln_undefined,
        loco_rmse_t2_n: loco.as_ref().map(|l| l.value),
        rmse_t2_uncertainty: uncertainty::rmse(&CordErrors::of(obs, e.pred), seed),
        loco_rmse_t2_uncertainty: loco,
        aic,
        bic,
        aic_strict: aic_s,
        bic_strict: bic_s,
        per_cord_r2_amp: per_cord,
        per_cord_r2_amp_median: median(&mut r2s),
        values: e.values,
    }
}

/// Fitted values with owned names.
pub fn named(values: Vec<(&'static str, f64)>) -> Vec<(String, f64)> {
    values
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect()
}

fn count(fixed: usize, per_group_values: usize, rule: &'static str) -> ParamCount {
    ParamCount {
        fixed,
        variance_components: 0,
        edf_random: 0.0,
        per_group_values,
        rule,
    }
}

/// The gain table: baseline, baseline per cord, thesis (if Table 3 covers the wraps), extended;
/// `causes` describes the extended model's named causes.
pub fn gain_table(obs: &Observations, f: &Fits, causes: &str) -> Vec<ModelMetrics> {
    let pred = &f.pred;
    let n_groups = obs.groups.len();
    let mut table = vec![
        metrics(
            obs,
            Entry {
                name: "baseline",
                description: "Euler-Eytelwein T2 = T1·exp(mu·β), one global mu (least squares on T2)",
                pred: &pred.baseline,
                loco: Some(&pred.baseline_loco),
                count: count(1, 0, "fixed values"),
                n_params: 1.0,
                n_strict: 1.0,
                values: named(f.baseline.values()),
            },
        ),
        metrics(
            obs,
            Entry {
                name: "baseline_per_cord",
                description: "Euler-Eytelwein with one mu per cord (a new cord is predicted with the mean log-mu of the others)",
                pred: &pred.baseline_per_cord,
                loco: Some(&pred.baseline_per_cord_loco),
                count: count(0, n_groups, "one value per cord"),
                n_params: n_groups as f64,
                n_strict: n_groups as f64,
                values: obs
                    .groups
                    .iter()
                    .zip(&f.cord_mu)
                    .map(|(g, m)| (format!("mu {}", g.label), *m))
                    .collect(),
            },
        ),
    ];
    if f.thesis_ok {
        table.push(metrics(
            obs,
            Entry {
                name: "thesis",
                description: "Thesis Table 3: amp(T1) = −Nd·exp(−ld·T1) + N0·exp(−l·T1) + SS per angle (published constants, set by eye; not refittable per cord)",
                pred: &pred.thesis,
                loco: None,
                count: count(0, thesis::TABLE3_N_VALUES, "5 published numbers per angle"),
                n_params: thesis::TABLE3_N_VALUES as f64,
                n_strict: thesis::TABLE3_N_VALUES as f64,
                values: Vec::new(),
            },
        ));
    }
    let ext = &f.extended;
    let description = format!(
        "Euler-Eytelwein with the named causes ({causes}) and a per-cord random log-mu (mixed model; the cord effects shrunk so that fixed values + their effective degrees of freedom ≤ {})",
        super::fits::STRICT_BUDGET
    );
    table.push(metrics(
        obs,
        Entry {
            name: "extended",
            description: &description,
            pred: &pred.extended,
            loco: Some(&pred.extended_loco),
            count: ParamCount {
                fixed: ext.n_fixed(),
                variance_components: 1,
                edf_random: ext.edf_random,
                per_group_values: 0,
                rule: "fixed values + the effective degrees of freedom of the cord effects",
            },
            n_params: ext.n_params_edf(),
            n_strict: ext.n_params_edf(),
            values: named(ext.values()),
        },
    ));
    table
}

/// The thesis's per-angle R² of amplification on these data.
pub fn thesis_per_angle(obs: &Observations) -> Vec<AngleR2> {
    let wraps: Vec<f64> = obs
        .rows
        .iter()
        .map(|r| r.op.wrap_rad.to_degrees())
        .collect();
    let t1s: Vec<f64> = obs.rows.iter().map(|r| r.t1_n).collect();
    let t2s: Vec<f64> = obs.rows.iter().map(|r| r.t2_n).collect();
    thesis::per_angle_r2(&wraps, &t1s, &t2s)
        .into_iter()
        .map(|(w, r2, rows)| AngleR2 {
            wrap_deg: w,
            r2,
            rows,
        })
        .collect()
}
