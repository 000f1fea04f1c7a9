//! The cords as units: every question about what varies between cords is answered against
//! the variation between cords, never against the runs' or the rows' scatter.
//!
//! A cord (one wrap on one capstan, re-hooked and re-zeroed when it is set up) is the unit of
//! diameter, wrap, material and of a new cord's prediction; its runs are repeated measurements
//! of it. So, from the final within-run fit (every run its own mu, the selected effects shared):
//!
//! * **Per-run and per-cord summaries** ([`Summaries`]): every parameter that may vary from cord
//!   to cord — mu, the T2 zero, and each selected within-run effect — estimated for each run and
//!   for each cord by one Gauss-Newton step from the shared fit (each run keeps its own mu), and
//!   the shape of each cord's residuals along T1 beyond those (two coefficients on asinh(T1/0.5 N)
//!   and its square, runs centred).
//! * **Random cord effects** ([`RandomEffect`]): does a parameter differ between cords more than
//!   between the runs of one cord? A one-way analysis of variance of the per-run estimates with
//!   the cord as the factor, F(G − 1, R − G) (the classical test of a random effect's variance,
//!   Searle, Casella & McCulloch 1992, §3.5), with the between-cord SD by the method of moments.
//! * **Between-cord patterns** ([`CordPattern`]): does a per-cord summary change with the wrap or
//!   the diameter? Each summary regressed on the covariate over the cords, t with G − 2 degrees
//!   of freedom; the family of summaries × covariates Bonferroni-adjusted. Fewer than
//!   [`MIN_CORDS`] cords: not tested (a pattern between cords is never judged against runs).
//!
//! The residuals with every cord's own summaries removed ([`CordLevel::z_after`]) are what the
//! lack-of-fit and the within-run directed tests then look at: what is left beyond cord-to-cord
//! scatter of the model's own parameters.

use super::design::Design;
use super::within::{sensitivities, WithinFit};
use super::Weights;
use crate::fit::stats::{f_p_upper, regress};
use capstan_physics::EffectKind;
use nalgebra::{DMatrix, DVector};
use serde::Serialize;

/// Cords as units from this many cords (a one-covariate regression then has 2 degrees of
/// freedom left).
pub const MIN_CORDS: usize = 4;

/// The random-effect test of mu.
pub const ANOVA: &str =
    "one-way analysis of variance of the runs' mu, cords as the factor: F(cords − 1, runs − cords)";
/// The random-effect test of the other parameters.
pub const SCORE_FLIPS: &str = "score test of a per-cord departure (each cord's summed score²/information), p from 1,999 sign flips of whole runs";

/// A random cord effect: does the parameter differ between cords more than between runs?
#[derive(Clone, Debug, Serialize)]
pub struct RandomEffect {
    /// `mu`, `t2_offset` (the T2 zero) or a selected within-run effect's name.
    pub parameter: &'static str,
    /// How it was tested.
    pub method: &'static str,
    /// mu: F of the one-way analysis of variance of the runs' mu, cords as the factor. The
    /// other parameters: the cords' score statistic over its mean under sign flips of whole
    /// runs (1: no more agreement inside cords than chance).
    pub f: f64,
    /// Cords − 1.
    pub df1: f64,
    /// Runs − cords.
    pub df2: f64,
    /// Upper-tail p.
    pub p: f64,
    /// SD between cords beyond what the runs' scatter explains (method of moments), in the
    /// parameter's catalogue unit (mu: % of mu).
    pub sd_between: f64,
    /// The unit of `sd_between`.
    pub unit: &'static str,
    /// p below the rule's level: the data support a cord-to-cord scatter of this parameter.
    pub supported: bool,
}

/// A per-cord summary against a covariate that varies between cords (cords as units).
#[derive(Clone, Debug, Serialize)]
pub struct CordPattern {
    /// `wrap` or `diameter`.
    pub covariate: &'static str,
    /// The summary: a parameter's per-cord value (`t2_offset`, an effect's name) or a shape
    /// coefficient of the cords' residuals (`shape_t1`, `shape_t1_squared`).
    pub summary: &'static str,
    /// Slope of the summary per unit of the covariate (deg or mm).
    pub slope: f64,
    /// Its t statistic.
    pub t: f64,
    /// Cords − 2.
    pub df: f64,
    /// Two-sided p.
    pub p: f64,
    /// p times the family's size (summaries × covariates), at most 1 (Bonferroni).
    pub p_family: f64,
    /// Share of the summary's between-cord variance the covariate explains.
    pub r2: f64,
    /// For a shape summary: the share of the residuals' run-centred sum of squares (beyond
    /// every cord's own parameters) the pattern accounts for — its size in the data. NaN for a
    /// parameter's summary.
    pub share: f64,
}

/// The cord-level view of a fit.
#[derive(Clone, Debug, Serialize)]
pub struct CordLevel {
    /// Cords.
    pub cords: usize,
    /// Runs.
    pub runs: usize,
    /// Each parameter's random-cord-effect test.
    pub random_effects: Vec<RandomEffect>,
    /// Each summary against wrap and diameter (empty with fewer than [`MIN_CORDS`] cords).
    pub patterns: Vec<CordPattern>,
    /// Each cord's summaries, in catalogue units: (parameter, value per cord).
    pub per_cord: Vec<(&'static str, Vec<f64>)>,
    /// Every run's mu with its cord's own parameters.
    #[serde(skip)]
    pub runs_mu: Vec<f64>,
    /// Standardised residuals (r·√w) after every cord's own parameters.
    #[serde(skip)]
    pub z_after: Vec<f64>,
    /// Parameters each cord was given (beyond every run's mu).
    #[serde(skip)]
    pub per_cord_parameters: usize,
    /// The map from the runs' residuals to those after every cord's own parameters.
    #[serde(skip)]
    pub projection: Projection,
}

/// One parameter that may vary between cords: its name, unit, each row's sensitivity, and its
/// catalogue value at the fit with the value per unit of the sensitivity's coordinate.
struct Column {
    name: &'static str,
    unit: &'static str,
    col: Vec<f64>,
    value: f64,
    per_unit: f64,
}

/// The parameters besides mu: the selected within-run effects, and the T2 zero when it is not
/// among them (the rig re-zeroes its sensors for every cord).
fn columns(d: &Design, fit: &WithinFit, w: &Weights) -> Vec<Column> {
    let (n, k) = (d.n(), fit.k());
    let (_, b) = sensitivities(d, fit, w);
    let mut out: Vec<Column> = (0..k)
        .map(|j| {
            let kind = fit.maps[j].kind;
            Column {
                name: kind.name(),
                unit: kind.entry().unit,
                col: (0..n).map(|i| b[i * k + j]).collect(),
                value: fit.value(j),
                per_unit: fit.maps[j].derivative(fit.theta[j]),
            }
        })
        .collect();
    if !fit.maps.iter().any(|m| m.kind == EffectKind::T2Offset) {
        out.push(Column {
            name: EffectKind::T2Offset.name(),
            unit: "N",
            col: vec![1.0; n],
            value: 0.0,
            per_unit: 1.0,
        });
    }
    out
}

/// Every cord's own parameters by one Gauss-Newton step from the shared fit, each run keeping
/// its own mu, as a linear map of the runs' residuals: per row the residual and the
/// sensitivities with the run's mu step removed (r̃, c̃), per run its score Σ w·c̃·r̃, per cord
/// the inverse of its information (None where not identified).
#[derive(Clone, Debug)]
pub struct Projection {
    rt: Vec<f64>,
    ct: Vec<Vec<f64>>,
    sw: Vec<f64>,
    score: Vec<Vec<f64>>,
    info_diag: Vec<Vec<f64>>,
    inv: Vec<Option<DMatrix<f64>>>,
    m: usize,
    /// Per run: its mu's step for the residual, and for each parameter (the projection's
    /// coefficients on ∂f/∂mu).
    mu_step: Vec<(f64, Vec<f64>)>,
}

/// A fit's columns at its estimate: ∂f/∂mu per row, ∂f/∂(each other parameter) per row, the
/// residuals and the weights.
type Columns<'a> = (&'a [f64], &'a [&'a [f64]], &'a [f64], &'a [f64]);

impl Projection {
    fn new(d: &Design, (a, cols, r, w): Columns<'_>) -> Projection {
        let (n, m) = (d.n(), cols.len());
        let (mut rt, mut ct) = (vec![0.0; n], vec![vec![0.0; m]; n]);
        let mut score = Vec::with_capacity(d.units.len());
        let mut info_diag = Vec::with_capacity(d.units.len());
        let mut info = vec![DMatrix::<f64>::zeros(m, m); d.cords.len()];
        let mut mu_step = Vec::with_capacity(d.units.len());
        for (u, rows) in d.units.iter().enumerate() {
            let aa: f64 = rows.iter().map(|&i| w[i] * a[i] * a[i]).sum();
            let proj = |v: &dyn Fn(usize) -> f64| -> f64 {
                if aa > 0.0 {
                    rows.iter().map(|&i| w[i] * a[i] * v(i)).sum::<f64>() / aa
                } else {
                    0.0
                }
            };
            let cr = proj(&|i| r[i]);
            let cc: Vec<f64> = cols.iter().map(|c| proj(&|i| c[i])).collect();
            let (mut su, mut iu) = (vec![0.0; m], vec![0.0; m]);
            let g = d.unit_cord[u];
            for &i in rows {
                rt[i] = r[i] - a[i] * cr;
                for j in 0..m {
                    ct[i][j] = cols[j][i] - a[i] * cc[j];
                    su[j] += w[i] * ct[i][j] * rt[i];
                    iu[j] += w[i] * ct[i][j] * ct[i][j];
                    for l in 0..m {
                        info[g][(j, l)] += w[i] * ct[i][j] * ct[i][l];
                    }
                }
            }
            score.push(su);
            info_diag.push(iu);
            mu_step.push((cr, cc));
        }
        let inv = info.into_iter().map(invert).collect();
        Projection {
            rt,
            ct,
            sw: w.iter().map(|x| x.sqrt()).collect(),
            score,
            info_diag,
            inv,
            m,
            mu_step,
        }
    }

    /// Every run's mu after its cord's own step (a run's mu moves with its cord's parameters:
    /// δmu = the residual's projection − the parameters' projections · the step), `mu` the
    /// shared fit's.
    fn runs_mu(&self, d: &Design, mu: &[f64], steps: &[Vec<f64>]) -> Vec<f64> {
        (0..d.units.len())
            .map(|u| {
                let (cr, cc) = &self.mu_step[u];
                let st = &steps[d.unit_cord[u]];
                let m: f64 = cc.iter().zip(st).map(|(c, s)| c * s).sum();
                if m.is_finite() {
                    mu[u] + cr - m
                } else {
                    mu[u]
                }
            })
            .collect()
    }

    /// Every cord's step for the runs' residuals times `signs` (NaN where not identified).
    fn steps(&self, d: &Design, signs: &[f64]) -> Vec<Vec<f64>> {
        let mut sc = vec![vec![0.0; self.m]; d.cords.len()];
        for (u, &g) in d.unit_cord.iter().enumerate() {
            for (acc, s) in sc[g].iter_mut().zip(&self.score[u]) {
                *acc += signs[u] * s;
            }
        }
        sc.into_iter()
            .zip(&self.inv)
            .map(|(s, inv)| match inv {
                Some(inv) => (inv * DVector::from_vec(s)).iter().copied().collect(),
                None => vec![f64::NAN; self.m],
            })
            .collect()
    }

    /// The standardised residuals (r·√w) after every cord's own step, the runs' residuals
    /// times `signs`, into `out`.
    pub fn after(&self, d: &Design, signs: &[f64], out: &mut [f64]) {
        let steps = self.steps(d, signs);
        for (u, rows) in d.units.iter().enumerate() {
            let st = &steps[d.unit_cord[u]];
            for &i in rows {
                let fit: f64 = self.ct[i].iter().zip(st).map(|(c, s)| c * s).sum();
                let fit = if fit.is_finite() { fit } else { 0.0 };
                out[i] = self.sw[i] * (signs[u] * self.rt[i] - fit);
            }
        }
    }
}

/// a > b, false when either is NaN.
fn above(a: f64, b: f64) -> bool {
    a.partial_cmp(&b) == Some(std::cmp::Ordering::Greater)
}

/// The inverse of a cord's information, None when it is (nearly) singular.
fn invert(xtx: DMatrix<f64>) -> Option<DMatrix<f64>> {
    let m = xtx.nrows();
    let scale = (0..m).map(|j| xtx[(j, j)]).fold(0.0, f64::max);
    let min = (0..m).map(|j| xtx[(j, j)]).fold(f64::INFINITY, f64::min);
    if m == 0 || !(scale > 0.0 && min > 1e-12 * scale) {
        return None;
    }
    let sv = xtx.clone().svd(false, false).singular_values;
    if !above(sv.min(), 1e-10 * sv.max()) {
        return None;
    }
    xtx.try_inverse()
}

/// The solution of a small symmetric system, None when it is (nearly) singular.
fn solve(xtx: DMatrix<f64>, xty: DVector<f64>) -> Option<Vec<f64>> {
    let m = xty.len();
    if m == 0 {
        return Some(Vec::new());
    }
    let scale = (0..m).map(|j| xtx[(j, j)]).fold(0.0, f64::max);
    let min = (0..m).map(|j| xtx[(j, j)]).fold(f64::INFINITY, f64::min);
    if !(scale > 0.0 && min > 1e-12 * scale) {
        return None;
    }
    let svd = xtx.clone().svd(false, false);
    let (smax, smin) = (svd.singular_values.max(), svd.singular_values.min());
    if !above(smin, 1e-10 * smax) {
        return None;
    }
    let x = xtx.lu().solve(&xty)?;
    x.iter()
        .all(|v| v.is_finite())
        .then(|| x.iter().copied().collect())
}

/// The one-way analysis of variance of `y` (NaN dropped) with groups `g` (0..groups):
/// (F, df1, df2, between-group variance component by the method of moments).
pub fn one_way(y: &[f64], g: &[usize], groups: usize) -> Option<(f64, f64, f64, f64)> {
    let (mut sum, mut cnt) = (vec![0.0; groups], vec![0usize; groups]);
    for (v, &c) in y.iter().zip(g) {
        if v.is_finite() {
            sum[c] += v;
            cnt[c] += 1;
        }
    }
    let used: Vec<usize> = (0..groups).filter(|&c| cnt[c] > 0).collect();
    let n: usize = cnt.iter().sum();
    let k = used.len();
    if k < 2 || n <= k {
        return None;
    }
    let grand = sum.iter().sum::<f64>() / n as f64;
    let mean: Vec<f64> = (0..groups).map(|c| sum[c] / cnt[c].max(1) as f64).collect();
    let ss_b: f64 = used
        .iter()
        .map(|&c| cnt[c] as f64 * (mean[c] - grand).powi(2))
        .sum();
    let ss_w: f64 = y
        .iter()
        .zip(g)
        .filter(|(v, _)| v.is_finite())
        .map(|(v, &c)| (v - mean[c]).powi(2))
        .sum();
    let (df1, df2) = ((k - 1) as f64, (n - k) as f64);
    let (ms_b, ms_w) = (ss_b / df1, ss_w / df2);
    let n0 =
        (n as f64 - used.iter().map(|&c| (cnt[c] * cnt[c]) as f64).sum::<f64>() / n as f64) / df1;
    let var_b = ((ms_b - ms_w) / n0).max(0.0);
    let f = if ms_w > 0.0 { ms_b / ms_w } else { f64::NAN };
    f.is_finite().then_some((f, df1, df2, var_b))
}

/// The cord-level view of `fit`; `alpha` is the level at which a random effect is supported.
pub fn cord_level(d: &Design, fit: &WithinFit, w: &Weights, alpha: f64) -> CordLevel {
    let n = d.n();
    let (a, _) = sensitivities(d, fit, w);
    let cols = columns(d, fit, w);
    let col_refs: Vec<&[f64]> = cols.iter().map(|c| c.col.as_slice()).collect();
    let r: Vec<f64> = (0..n).map(|i| d.t2[i] - fit.fitted[i]).collect();
    let ww = &w.w;
    let ncords = d.cords.len();
    let projection = Projection::new(d, (&a, &col_refs, &r, ww));
    let ones = vec![1.0; d.units.len()];
    let per_cord_delta = projection.steps(d, &ones);
    let mut z_after = vec![0.0; n];
    projection.after(d, &ones, &mut z_after);
    let mut random_effects = Vec::new();
    let mu_bar = fit.mu.iter().sum::<f64>() / fit.mu.len().max(1) as f64;
    if let Some((f, df1, df2, var_b)) = one_way(&fit.mu, &d.unit_cord, ncords) {
        random_effects.push(RandomEffect {
            parameter: "mu",
            method: ANOVA,
            f,
            df1,
            df2,
            p: f_p_upper(f, df1, df2),
            sd_between: 100.0 * var_b.sqrt() / mu_bar,
            unit: "% of mu",
            supported: false,
        });
    }
    for (j, c) in cols.iter().enumerate() {
        if let Some((f, p, var_b)) = projection.flip_test(d, j) {
            random_effects.push(RandomEffect {
                parameter: c.name,
                method: SCORE_FLIPS,
                f,
                df1: (ncords - 1) as f64,
                df2: (d.units.len() - ncords) as f64,
                p,
                sd_between: var_b.sqrt() * c.per_unit.abs(),
                unit: c.unit,
                supported: false,
            });
        }
    }
    for e in &mut random_effects {
        e.supported = e.p < alpha;
    }
    let shape = shape_coefficients(d, &z_after);
    let mut per_cord: Vec<(&'static str, Vec<f64>)> = cols
        .iter()
        .enumerate()
        .map(|(j, c)| {
            let v = per_cord_delta
                .iter()
                .map(|dl| c.value + dl[j] * c.per_unit)
                .collect();
            (c.name, v)
        })
        .collect();
    per_cord.push(("shape_t1", shape.iter().map(|s| s[0]).collect()));
    per_cord.push(("shape_t1_squared", shape.iter().map(|s| s[1]).collect()));
    let mut patterns = patterns(d, &per_cord);
    for p in patterns.iter_mut() {
        p.share = shape_share(d, p, &z_after);
    }
    CordLevel {
        cords: ncords,
        runs: d.units.len(),
        random_effects,
        patterns,
        per_cord,
        z_after,
        per_cord_parameters: cols.len(),
        runs_mu: projection.runs_mu(d, &fit.mu, &per_cord_delta),
        projection,
    }
}

/// How many units each question of `d` has, in words (the structure line's tail): the cords
/// for what varies between cords, the runs for the shape within runs.
pub fn units_statement(d: &Design) -> String {
    let (g, r) = (d.cords.len(), d.units.len());
    let plural = |n: usize, one: &str| format!("{n} {one}{}", if n == 1 { "" } else { "s" });
    let between = if g >= MIN_CORDS {
        format!(
            "{} for what varies between cords (diameter, wrap, a T2 gain, the random cord effects, a new cord's prediction)",
            plural(g, "cord")
        )
    } else {
        format!(
            "{} for what varies between cords (a new cord's prediction; patterns with wrap or diameter need {MIN_CORDS})",
            plural(g, "cord")
        )
    };
    format!(
        "units: {between}; {} for the shape within runs",
        plural(r, "run")
    )
}

/// The shape basis along T1: asinh(T1/0.5 N) and its square (defined at or below zero).
pub fn t1_basis(d: &Design) -> Vec<Vec<f64>> {
    let s: Vec<f64> = d.t1.iter().map(|t| (t / 0.5).asinh()).collect();
    vec![s.clone(), s.iter().map(|x| x * x).collect()]
}

/// Each cord's coefficients of `z` on the run-centred columns `x` (NaN where not identified).
pub fn per_cord_coefficients(d: &Design, x: &[Vec<f64>], z: &[f64]) -> Vec<Vec<f64>> {
    let q = x.len();
    (0..d.cords.len())
        .map(|c| {
            let mut xtx = DMatrix::<f64>::zeros(q, q);
            let mut xty = DVector::<f64>::zeros(q);
            for (u, rows) in d.units.iter().enumerate() {
                if d.unit_cord[u] != c || rows.is_empty() {
                    continue;
                }
                let m = rows.len() as f64;
                let zm = rows.iter().map(|&i| z[i]).sum::<f64>() / m;
                let xm: Vec<f64> = (0..q)
                    .map(|a| rows.iter().map(|&i| x[a][i]).sum::<f64>() / m)
                    .collect();
                for &i in rows {
                    for a in 0..q {
                        let xa = x[a][i] - xm[a];
                        xty[a] += xa * (z[i] - zm);
                        for b in 0..q {
                            xtx[(a, b)] += xa * (x[b][i] - xm[b]);
                        }
                    }
                }
            }
            solve(xtx, xty).unwrap_or_else(|| vec![f64::NAN; q])
        })
        .collect()
}

fn shape_coefficients(d: &Design, z: &[f64]) -> Vec<Vec<f64>> {
    per_cord_coefficients(d, &t1_basis(d), z)
}

/// Every per-cord summary against wrap and diameter, cords as units (none with fewer than
/// [`MIN_CORDS`] cords or a covariate with one value).
fn patterns(d: &Design, per_cord: &[(&'static str, Vec<f64>)]) -> Vec<CordPattern> {
    let g = d.cords.len();
    if g < MIN_CORDS {
        return Vec::new();
    }
    let covariates: Vec<(&'static str, Vec<f64>)> = [
        (
            "wrap",
            d.cords.iter().map(|c| c.wrap_deg).collect::<Vec<_>>(),
        ),
        ("diameter", d.cords.iter().map(|c| c.diameter_mm).collect()),
    ]
    .into_iter()
    .filter(|(_, x)| crate::fit::stats::distinct(x.iter().copied()).len() >= 2)
    .collect();
    let mut out = Vec::new();
    for (cov, x) in &covariates {
        for (name, y) in per_cord {
            let keep: Vec<usize> = (0..g).filter(|&c| y[c].is_finite()).collect();
            if keep.len() < MIN_CORDS {
                continue;
            }
            let xs: Vec<Vec<f64>> = keep.iter().map(|&c| vec![1.0, x[c]]).collect();
            let ys: Vec<f64> = keep.iter().map(|&c| y[c]).collect();
            let Some(r) = regress(&xs, &ys, None, None) else {
                continue;
            };
            if !(r.t[1].is_finite() && r.p[1].is_finite()) {
                continue;
            }
            out.push(CordPattern {
                covariate: cov,
                summary: name,
                slope: r.coef[1],
                t: r.t[1],
                df: r.df,
                p: r.p[1],
                p_family: 1.0,
                r2: r.r2,
                share: f64::NAN,
            });
        }
    }
    let m = out.len() as f64;
    for p in &mut out {
        p.p_family = (p.p * m).min(1.0);
    }
    out
}

/// The share of the run-centred residuals `z`'s sum of squares a shape pattern accounts for:
/// each cord's coefficient moved by the slope times its covariate's departure from the cords'
/// mean, on the run-centred basis column. NaN for a parameter's pattern.
fn shape_share(d: &Design, p: &CordPattern, z: &[f64]) -> f64 {
    let col = match p.summary {
        "shape_t1" => 0,
        "shape_t1_squared" => 1,
        _ => return f64::NAN,
    };
    let basis = &t1_basis(d)[col];
    let x: Vec<f64> = d
        .cords
        .iter()
        .map(|c| match p.covariate {
            "wrap" => c.wrap_deg,
            _ => c.diameter_mm,
        })
        .collect();
    let x_bar = x.iter().sum::<f64>() / x.len().max(1) as f64;
    let (mut explained, mut total) = (0.0, 0.0);
    for (u, rows) in d.units.iter().enumerate() {
        if rows.is_empty() {
            continue;
        }
        let m = rows.len() as f64;
        let bm = rows.iter().map(|&i| basis[i]).sum::<f64>() / m;
        let zm = rows.iter().map(|&i| z[i]).sum::<f64>() / m;
        let shift = p.slope * (x[d.unit_cord[u]] - x_bar);
        for &i in rows {
            explained += (shift * (basis[i] - bm)).powi(2);
            total += (z[i] - zm).powi(2);
        }
    }
    if total > 0.0 {
        explained / total
    } else {
        f64::NAN
    }
}

/// Hotelling's one-sample T² that the mean of the rows of `c` (units × q, NaN rows dropped)
/// is zero: (F, q, units − q), None with too few units.
pub fn hotelling(c: &[Vec<f64>]) -> Option<(f64, f64, f64)> {
    let rows: Vec<&Vec<f64>> = c
        .iter()
        .filter(|v| v.iter().all(|x| x.is_finite()))
        .collect();
    let q = rows.first()?.len();
    let g = rows.len();
    if q == 0 || g < q + 2 {
        return None;
    }
    let gf = g as f64;
    let mean = DVector::from_fn(q, |a, _| rows.iter().map(|v| v[a]).sum::<f64>() / gf);
    let mut s = DMatrix::<f64>::zeros(q, q);
    for v in &rows {
        let dv = DVector::from_fn(q, |a, _| v[a] - mean[a]);
        s += &dv * dv.transpose();
    }
    s /= gf - 1.0;
    let t2 = gf * (mean.transpose() * s.try_inverse()? * &mean)[(0, 0)];
    let qf = q as f64;
    let f = (gf - qf) / (qf * (gf - 1.0)) * t2;
    f.is_finite().then_some((f, qf, gf - qf))
}

/// Sign-flip replications of the random-effect score tests.
const FLIPS: usize = 1999;

impl Projection {
    /// Σ over cords of (the cord's score)²/(its information) for parameter `j`, each run's
    /// score times `sign(run)`; and the mean over cords of the per-cord step².
    fn statistic(&self, d: &Design, j: usize, sign: &dyn Fn(usize) -> f64) -> (f64, f64) {
        let g = d.cords.len();
        let (mut sc, mut inf) = (vec![0.0; g], vec![0.0; g]);
        for (u, &c) in d.unit_cord.iter().enumerate() {
            sc[c] += sign(u) * self.score[u][j];
            inf[c] += self.info_diag[u][j];
        }
        let (mut t, mut step2, mut used) = (0.0, 0.0, 0usize);
        for c in 0..g {
            if inf[c] > 0.0 {
                t += sc[c] * sc[c] / inf[c];
                step2 += (sc[c] / inf[c]).powi(2);
                used += 1;
            }
        }
        (t, step2 / used.max(1) as f64)
    }

    /// The random-cord-effect test of parameter `j`: do the runs of a cord push it the same way
    /// more than sign flips of whole runs make them (the runs' residuals keep their own
    /// correlation; a cord-level departure is what a flip destroys)? Returns (the statistic
    /// over its flips' mean, p, the between-cord variance of the per-cord step beyond the
    /// flips' in the θ coordinate). None with fewer than two cords or no cord of two runs.
    fn flip_test(&self, d: &Design, j: usize) -> Option<(f64, f64, f64)> {
        let g = d.cords.len();
        if g < 2 || d.units.len() <= g {
            return None;
        }
        let (observed, step2) = self.statistic(d, j, &|_| 1.0);
        let mut rng = capstan_rng::Rng::new(0x00c0_4d5e);
        let mut signs = vec![1.0; d.units.len()];
        let (mut above, mut total, mut total_step2) = (0usize, 0.0, 0.0);
        for _ in 0..FLIPS {
            for x in signs.iter_mut() {
                *x = if rng.next_u64() >> 63 == 0 { 1.0 } else { -1.0 };
            }
            let (t, s2) = self.statistic(d, j, &|u| signs[u]);
            total += t;
            total_step2 += s2;
            if t >= observed {
                above += 1;
            }
        }
        let null_mean = total / FLIPS as f64;
        let ratio = observed / null_mean;
        let p = (above + 1) as f64 / (FLIPS + 1) as f64;
        let var_b = (step2 - total_step2 / FLIPS as f64).max(0.0);
        (ratio.is_finite() && null_mean > 0.0).then_some((ratio, p, var_b))
    }
}
