//! What the models get wrong: residual trends against every column, with test statistics.
//!
//! For each model, residual kind (T2 in N, ln(T2/T1)) and column: Spearman's rank correlation
//! (effect size, monotone trends), the least-squares slope per standard deviation of the
//! column with standard errors clustered by cord (G − 1 degrees of freedom: rows of one cord
//! are not independent), and η², the share of residual variance explained by the column's
//! levels (up to 12 levels; continuous columns in 10 quantile bins), with its one-way F test
//! (which treats rows as independent and so overstates significance; read it with η²). Each
//! model's slope tests are one family (both residuals, every column but the measured T2, which a
//! residual leans on by its own noise): their p-values are also given Holm-adjusted, as a reader
//! must read a dozen tests. With fewer than [`MIN_CLUSTERS`] cords no slope test is computed.

use super::{ln_amp, ln_amp_defined, Predictions};
use crate::fit::stats::{eta_squared, holm, mean, regress, spearman, variance};
use crate::fit::Observations;
use capstan_data::Dataset;
use serde::Serialize;

/// One residual trend.
#[derive(Clone, Debug, Serialize)]
pub struct Pattern {
    /// Model.
    pub model: String,
    /// `t2_n` (measured − predicted, N) or `ln_amp` (measured − predicted ln(T2/T1)).
    pub residual: &'static str,
    /// Column.
    pub column: String,
    /// Spearman's rank correlation of residual and column.
    pub spearman_rho: f64,
    /// Slope of the residual per SD of the column.
    pub slope_per_sd: f64,
    /// The column's SD (its unit): `slope_per_sd / column_sd` is the slope per unit of it.
    pub column_sd: f64,
    /// Its t statistic, SE clustered by cord.
    pub slope_t_cluster: f64,
    /// Two-sided p of that t (G − 1 df).
    pub slope_p_cluster: f64,
    /// That p adjusted by Holm's step-down procedure over the model's family of slope tests
    /// (both residuals, every column but the measured T2: NaN there): what a reader may quote
    /// as established.
    pub slope_p_holm: f64,
    /// Number of levels used for η².
    pub levels: usize,
    /// Share of residual variance explained by the column's levels.
    pub eta2: f64,
    /// One-way F.
    pub f: f64,
    /// p of F (rows treated as independent).
    pub f_p: f64,
}

fn levels(v: &[f64]) -> Vec<usize> {
    let mut distinct: Vec<f64> = v.to_vec();
    distinct.sort_by(f64::total_cmp);
    distinct.dedup();
    if distinct.len() <= 12 {
        return v
            .iter()
            .map(|x| distinct.iter().position(|d| d == x).unwrap_or(0))
            .collect();
    }
    let mut sorted = v.to_vec();
    sorted.sort_by(f64::total_cmp);
    let cuts: Vec<f64> = (1..10).map(|k| sorted[k * sorted.len() / 10]).collect();
    v.iter()
        .map(|x| cuts.iter().filter(|c| x >= c).count())
        .collect()
}

type Getter = fn(&capstan_data::Pair) -> Option<f64>;

/// The columns to test: every known column present plus the extra ones.
fn columns(ds: &Dataset, obs: &Observations) -> Vec<(String, Vec<f64>)> {
    let mut cols: Vec<(String, Vec<f64>)> = vec![
        ("t1_n".into(), obs.rows.iter().map(|r| r.t1_n).collect()),
        ("t2_n".into(), obs.rows.iter().map(|r| r.t2_n).collect()),
        (
            "wrap_deg".into(),
            obs.rows
                .iter()
                .map(|r| r.op.wrap_rad.to_degrees())
                .collect(),
        ),
    ];
    let opt: [(&str, Getter); 5] = [
        ("capstan_diameter_mm", |p| p.capstan_diameter_mm),
        ("drive_v", |p| p.drive_v),
        ("run", |p| p.run),
        ("step", |p| p.step),
        ("time_s", |p| p.time_s),
    ];
    for (name, f) in opt {
        if ds.has_column(name) {
            cols.push((
                name.into(),
                ds.pairs.iter().map(|p| f(p).unwrap_or(0.0)).collect(),
            ));
        }
    }
    for (k, name) in ds.extra_columns.iter().enumerate() {
        cols.push((name.clone(), ds.pairs.iter().map(|p| p.extra[k]).collect()));
    }
    // A column with one value carries no pattern.
    cols.retain(|(_, v)| v.iter().any(|x| *x != v[0]));
    cols
}

/// The fewest cords whose cord-clustered slope tests are computed: with fewer, the sandwich
/// over the cords is degenerate (two cords fit any column that is constant within a cord
/// exactly, t ≈ 10¹⁵). At 5 cords the family's Holm-adjusted claim fired in 6 of 100 thesis-like
/// campaigns with no trend planted (`science/validation/examples/residual_trends.rs`).
pub const MIN_CLUSTERS: usize = 5;

/// Whether a column's slope test belongs to the family that Holm's adjustment covers: not the
/// measured T2 itself, against which a residual (measured − model) always leans by its own
/// noise, so its slope is no trend of the model's.
fn in_family(column: &str) -> bool {
    column != "t2_n"
}

/// Residual patterns of the baseline and the extended model.
pub fn patterns(ds: &Dataset, obs: &Observations, pred: &Predictions) -> Vec<Pattern> {
    let cols = columns(ds, obs);
    let clusters: Vec<usize> = obs.group_of_rows();
    let mut out = Vec::new();
    for (model, p) in [("baseline", &pred.baseline), ("extended", &pred.extended)] {
        let first = out.len();
        for kind in ["t2_n", "ln_amp"] {
            let resid: Vec<f64> = obs
                .rows
                .iter()
                .zip(p.iter())
                .map(|(r, p)| match kind {
                    "t2_n" => r.t2_n - p,
                    _ => ln_amp(r.t2_n, r.t1_n) - ln_amp(*p, r.t1_n),
                })
                .collect();
            for (name, v) in &cols {
                let (m, sd) = (mean(v), variance(v).sqrt());
                let x: Vec<Vec<f64>> = v.iter().map(|a| vec![1.0, (a - m) / sd]).collect();
                let reg = regress(&x, &resid, None, Some(&clusters));
                // The slope stands on any number of cords; its cord-clustered test on enough.
                let test = reg.as_ref().filter(|_| obs.groups.len() >= MIN_CLUSTERS);
                let lv = levels(v);
                let (eta2, f, f_p) = eta_squared(&resid, &lv);
                out.push(Pattern {
                    model: model.into(),
                    residual: kind,
                    column: name.clone(),
                    spearman_rho: spearman(v, &resid),
                    slope_per_sd: reg.as_ref().map_or(f64::NAN, |r| r.coef[1]),
                    column_sd: sd,
                    slope_t_cluster: test.map_or(f64::NAN, |r| r.t[1]),
                    slope_p_cluster: test.map_or(f64::NAN, |r| r.p[1]),
                    slope_p_holm: f64::NAN,
                    levels: lv.iter().copied().max().map_or(0, |m| m + 1),
                    eta2,
                    f,
                    f_p,
                });
            }
        }
        let family: Vec<f64> = (out[first..].iter())
            .map(|p| match in_family(&p.column) {
                true => p.slope_p_cluster,
                false => f64::NAN,
            })
            .collect();
        for (p, h) in out[first..].iter_mut().zip(holm(&family)) {
            p.slope_p_holm = h;
        }
    }
    out
}

/// The ln-amplification residuals of one step, Euler-Eytelwein against the extended model:
/// where at low tension the extended model does better or worse, shown for every step.
#[derive(Clone, Debug, Serialize)]
pub struct StepResidual {
    /// The step.
    pub step: f64,
    /// Rows with both tensions above zero (the logarithm's rows).
    pub rows: usize,
    /// Mean T1 of those rows, N.
    pub mean_t1_n: f64,
    /// Mean residual of ln(T2/T1), Euler-Eytelwein (measured − model), over the rows where the
    /// model's T2 is above zero (the same for every ln statistic below).
    pub baseline_mean: f64,
    /// Mean residual of ln(T2/T1), extended model.
    pub extended_mean: f64,
    /// RMS residual of ln(T2/T1), Euler-Eytelwein.
    pub baseline_rms: f64,
    /// RMS residual of ln(T2/T1), extended model.
    pub extended_rms: f64,
    /// Rows where Euler-Eytelwein predicts T2 at or below zero (left out of its ln residuals).
    pub baseline_nonpositive: usize,
    /// Rows where the extended model predicts T2 at or below zero (left out of its ln residuals).
    pub extended_nonpositive: usize,
    /// The extended model's lowest predicted T2 at the step, N.
    pub extended_lowest_n: f64,
    /// The lowest measured T2 at the step, N.
    pub measured_lowest_n: f64,
}

/// The ln-amplification residuals by step (None without a `step` column).
pub fn ln_amp_by_step(obs: &Observations, pred: &Predictions) -> Option<Vec<StepResidual>> {
    let steps = crate::fit::stats::distinct(obs.rows.iter().filter_map(|r| r.step));
    if steps.is_empty() {
        return None;
    }
    Some(
        steps
            .into_iter()
            .map(|s| {
                let idx: Vec<usize> = (0..obs.len())
                    .filter(|&i| {
                        let r = &obs.rows[i];
                        r.step == Some(s) && r.t1_n > 0.0 && r.t2_n > 0.0
                    })
                    .collect();
                // Rows whose predicted T2 is at or below zero have no logarithm: counted, not
                // floored into a residual.
                let res = |p: &[f64]| -> (Vec<f64>, usize) {
                    let mut v = Vec::new();
                    let mut undefined = 0;
                    for &i in &idx {
                        let r = &obs.rows[i];
                        match ln_amp_defined(p[i], r.t1_n) {
                            Some(x) => v.push(ln_amp(r.t2_n, r.t1_n) - x),
                            None => undefined += 1,
                        }
                    }
                    (v, undefined)
                };
                let rms =
                    |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
                let ((b, b_undef), (e, e_undef)) = (res(&pred.baseline), res(&pred.extended));
                let lowest = |p: &[f64]| idx.iter().map(|&i| p[i]).fold(f64::INFINITY, f64::min);
                StepResidual {
                    step: s,
                    rows: idx.len(),
                    mean_t1_n: mean(&idx.iter().map(|&i| obs.rows[i].t1_n).collect::<Vec<_>>()),
                    baseline_mean: mean(&b),
                    extended_mean: mean(&e),
                    baseline_rms: rms(&b),
                    extended_rms: rms(&e),
                    baseline_nonpositive: b_undef,
                    extended_nonpositive: e_undef,
                    extended_lowest_n: lowest(&pred.extended),
                    measured_lowest_n: idx
                        .iter()
                        .map(|&i| obs.rows[i].t2_n)
                        .fold(f64::INFINITY, f64::min),
                }
            })
            .collect(),
    )
}
