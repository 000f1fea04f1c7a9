//! Screening the library given the catalogue fit: every term as one extra parameter,
//! linearised from the fit, with the engine's evidence (quasi-likelihood ratio over the
//! parameter's run-clustered overdispersion, F(1, G − 1) → χ²₁, ΔBIC = −χ² + ln n) for terms
//! that act within runs, and the engine's between-level test (the runs' ln mu regressed on the
//! term, t → χ²₁, ΔBIC = −χ² + ln N with N the cords or runs) for mu terms that are constant
//! inside every run (every run's own mu absorbs them within runs).

use crate::columns::Base;
use crate::library::{Form, Sign, Term};
use capstan_engine::fit::stats::{chi2_of_f, chi2_of_t, regress};
use nalgebra::{DMatrix, DVector};

/// Where a term's evidence comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Level {
    /// Within runs (its shape).
    WithinRun,
    /// Between cords or runs (the runs' mu).
    Between,
}

/// One term's screen.
#[derive(Clone, Debug)]
pub struct Screen {
    /// Index into the library.
    pub term: usize,
    /// Level of its evidence.
    pub level: Level,
    /// θ̂ (first order).
    pub theta: f64,
    /// Its cluster-robust standard error.
    pub se: f64,
    /// ΔBIC given the catalogue (and any term already proposed), before the search penalty.
    pub delta_bic: f64,
    /// Overdispersion ĉ (within; 1 between).
    pub c_hat: f64,
    /// θ̂ has the term's physical sign.
    pub sign_ok: bool,
    /// Share of its column (each run's mu projected out) the model's columns explain:
    /// 1 − 1/VIF (within-run terms; 0 between).
    pub r2_model: f64,
    /// Its evidence in what the replicate runs share (within-run terms with replicate cells).
    pub replicate: Option<crate::replicate::Replicate>,
}

/// Projection of columns off every run's mu and the model's shared columns (weighted).
pub struct Projector {
    /// The model's shared columns, each already projected off the runs' mu.
    pub shared: Vec<Vec<f64>>,
    inv: DMatrix<f64>,
}

/// `v` with every run's mu column projected out (weighted).
pub fn off_run_mu(base: &Base, v: &[f64]) -> Vec<f64> {
    let mut out = v.to_vec();
    for rows in &base.d.units {
        let (mut aa, mut av) = (0.0, 0.0);
        for &i in rows {
            aa += base.w[i] * base.a[i] * base.a[i];
            av += base.w[i] * base.a[i] * v[i];
        }
        if aa > 0.0 {
            let c = av / aa;
            for &i in rows {
                out[i] -= c * base.a[i];
            }
        }
    }
    out
}

fn dot_w(w: &[f64], x: &[f64], y: &[f64]) -> f64 {
    w.iter().zip(x).zip(y).map(|((w, x), y)| w * x * y).sum()
}

impl Projector {
    /// The projector for shared columns `cols` (raw; projected off the runs' mu here).
    pub fn new(base: &Base, cols: &[Vec<f64>]) -> Projector {
        let shared: Vec<Vec<f64>> = cols.iter().map(|c| off_run_mu(base, c)).collect();
        let k = shared.len();
        let g = DMatrix::from_fn(k, k, |i, j| dot_w(&base.w, &shared[i], &shared[j]));
        let inv = g
            .clone()
            .try_inverse()
            .unwrap_or_else(|| DMatrix::zeros(k, k));
        Projector { shared, inv }
    }

    /// `v` projected off every run's mu and the shared columns.
    pub fn project(&self, base: &Base, v: &[f64]) -> Vec<f64> {
        let mut out = off_run_mu(base, v);
        let k = self.shared.len();
        if k == 0 {
            return out;
        }
        let rhs = DVector::from_fn(k, |j, _| dot_w(&base.w, &self.shared[j], &out));
        let c = &self.inv * rhs;
        for (j, col) in self.shared.iter().enumerate() {
            for (o, x) in out.iter_mut().zip(col) {
                *o -= c[j] * x;
            }
        }
        out
    }
}

/// Within-run evidence of a projected column `x` against projected residuals `e`, with `k`
/// shared parameters already in.
pub fn within_evidence(
    base: &Base,
    x: &[f64],
    e: &[f64],
    k: usize,
) -> Option<(f64, f64, f64, f64)> {
    let d = base.d;
    let n = d.n() as f64;
    let w = &base.w;
    let sxx = dot_w(w, x, x);
    let sxe = dot_w(w, x, e);
    let wrss0 = dot_w(w, e, e);
    if !(sxx > 0.0 && wrss0 > 0.0) {
        return None;
    }
    let theta = sxe / sxx;
    let wrss1 = (wrss0 - sxe * sxe / sxx).max(1e-300);
    let lr = (n * (wrss0 / wrss1).ln()).max(0.0);
    let g = d.units.len() as f64;
    let dof = (n - g - k as f64 - 1.0).max(1.0);
    let var_model = wrss1 / dof / sxx;
    // CR3: each run's score through the information without that run.
    let mut var_rob = 0.0;
    for rows in &d.units {
        let (mut s, mut sr) = (0.0, 0.0);
        for &i in rows {
            s += w[i] * x[i] * (e[i] - theta * x[i]);
            sr += w[i] * x[i] * x[i];
        }
        let info = (sxx - sr).max(1e-12 * sxx);
        var_rob += (s / info).powi(2);
    }
    var_rob *= (g - 1.0) / g;
    // Fewer than 3 runs: no run-clustered error worth the name (from 2 clusters it claims more
    // than it knows; the screen shows none). ĉ still uses what there is (1 at one run).
    let se = if g >= 3.0 { var_rob.sqrt() } else { f64::NAN };
    let c_hat = (var_rob / var_model).max(1.0);
    let c_hat = if c_hat.is_finite() { c_hat } else { 1.0 };
    let chi2 = chi2_of_f(lr / c_hat, 1.0, (g - 1.0).max(1.0));
    Some((theta, se, -chi2 + n.ln(), c_hat))
}

/// The term's g per run, if it acts on mu and is constant inside every run.
pub fn run_level_g(base: &Base, t: &Term) -> Option<Vec<f64>> {
    let Form::Mu(g) = t.form else { return None };
    let mut out = Vec::with_capacity(base.d.units.len());
    for rows in &base.d.units {
        let first = g(&base.rows[*rows.first()?]);
        if rows
            .iter()
            .any(|&i| (g(&base.rows[i]) - first).abs() > 1e-12 * (1.0 + first.abs()))
        {
            return None;
        }
        out.push(first);
    }
    Some(out)
}

/// The runs of a data set for the between-level test: each run's cord and ln mu.
#[derive(Clone, Debug)]
pub struct Runs {
    /// Cord of each run (0..cords).
    pub cord: Vec<usize>,
    /// Number of cords.
    pub cords: usize,
    /// ln mu of each run.
    pub ln_mu: Vec<f64>,
}

/// Between-level evidence: the runs' ln mu against g (with `covs`, the selected catalogue
/// between covariates, one value per run). Cord-level g: the cords' means, t with G − p df,
/// N = G; run-level g: cord intercepts, t with R − G − p df, N = R. Returns (θ̂, SE, ΔBIC).
pub fn between_evidence(runs: &Runs, g: &[f64], covs: &[Vec<f64>]) -> Option<(f64, f64, f64)> {
    let cord_level = is_cord_level(runs, g);
    let spread = g.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
        - g.iter().cloned().fold(f64::INFINITY, f64::min);
    if spread.is_nan() || spread <= 1e-12 {
        return None;
    }
    let problem = if cord_level {
        Between::on_cord_means(runs, g, covs)
    } else {
        Between::within_cords(runs, g, covs)
    };
    problem.evidence()
}

/// Is g one value per cord (the same for every run of a cord)?
fn is_cord_level(runs: &Runs, g: &[f64]) -> bool {
    let mut first = vec![f64::NAN; runs.cords];
    let mut cord_level = true;
    for (&c, &gu) in runs.cord.iter().zip(g) {
        if first[c].is_nan() {
            first[c] = gu;
        } else if (gu - first[c]).abs() > 1e-12 * (1.0 + gu.abs()) {
            cord_level = false;
        }
    }
    cord_level
}

/// A between-level regression of ln mu on the covariates and g (last column).
struct Between {
    x: Vec<Vec<f64>>,
    y: Vec<f64>,
    /// Observations at the level tested (N of the BIC).
    n_level: usize,
    /// Parameters absorbed beyond x's columns (the cord intercepts).
    extra: usize,
}

impl Between {
    /// Cord-level g: the cords' means of ln mu on an intercept, the covariates and g.
    fn on_cord_means(runs: &Runs, g: &[f64], covs: &[Vec<f64>]) -> Between {
        let (nc, y) = (runs.cords, &runs.ln_mu);
        let mut sx = vec![vec![0.0; covs.len() + 2]; nc];
        let mut sy = vec![0.0; nc];
        let mut cnt = vec![0.0; nc];
        for u in 0..runs.cord.len() {
            let c = runs.cord[u];
            cnt[c] += 1.0;
            sy[c] += y[u];
            sx[c][0] += 1.0;
            for (j, cv) in covs.iter().enumerate() {
                sx[c][j + 1] += cv[u];
            }
            sx[c][covs.len() + 1] += g[u];
        }
        let keep: Vec<usize> = (0..nc).filter(|&c| cnt[c] > 0.0).collect();
        let x: Vec<Vec<f64>> = keep
            .iter()
            .map(|&c| sx[c].iter().map(|v| v / cnt[c]).collect())
            .collect();
        let y: Vec<f64> = keep.iter().map(|&c| sy[c] / cnt[c]).collect();
        let n_level = keep.len();
        Between {
            x,
            y,
            n_level,
            extra: 0,
        }
    }

    /// Run-level g: ln mu, the covariates and g taken off their cords' means (cord intercepts).
    fn within_cords(runs: &Runs, g: &[f64], covs: &[Vec<f64>]) -> Between {
        let (nc, nr) = (runs.cords, runs.cord.len());
        let demean = |v: &[f64]| -> Vec<f64> {
            let mut s = vec![0.0; nc];
            let mut c = vec![0.0; nc];
            for u in 0..v.len() {
                s[runs.cord[u]] += v[u];
                c[runs.cord[u]] += 1.0;
            }
            (0..v.len())
                .map(|u| v[u] - s[runs.cord[u]] / c[runs.cord[u]])
                .collect()
        };
        let gd = demean(g);
        let cd: Vec<Vec<f64>> = covs.iter().map(|c| demean(c)).collect();
        let x: Vec<Vec<f64>> = (0..nr)
            .map(|u| {
                let mut r: Vec<f64> = cd.iter().map(|c| c[u]).collect();
                r.push(gd[u]);
                r
            })
            .collect();
        let used = runs
            .cord
            .iter()
            .collect::<std::collections::BTreeSet<_>>()
            .len();
        Between {
            x,
            y: demean(&runs.ln_mu),
            n_level: nr,
            extra: used,
        }
    }

    /// g's slope: (θ̂, SE, ΔBIC), t with n_level − p − extra df; None if too few observations
    /// or not finite.
    fn evidence(&self) -> Option<(f64, f64, f64)> {
        let p = self.x.first()?.len();
        if self.n_level < p + self.extra + 2 {
            return None;
        }
        let reg = regress(&self.x, &self.y, None, None)?;
        let j = p - 1;
        let df = (self.n_level - p - self.extra) as f64;
        let se = reg.se[j] * (reg.df / df).sqrt();
        let chi2 = chi2_of_t(reg.coef[j] / se, df);
        [reg.coef[j], se, chi2]
            .iter()
            .all(|v| v.is_finite())
            .then(|| (reg.coef[j], se, -chi2 + (self.n_level as f64).ln()))
    }
}

/// Does θ̂ keep the term's physical sign?
pub fn sign_ok(t: &Term, theta: f64) -> bool {
    match t.sign {
        Sign::Free => true,
        Sign::NonNegative => theta >= 0.0,
    }
}
