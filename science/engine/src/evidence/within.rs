//! Within-run fits: every run has its own mu, and a set of effects shares its parameters θ
//! across runs.
//!
//! T2ᵢ = Model(mu_r(i), θ).predict(T1ᵢ, opᵢ) — its shape in tension read at the row's shape
//! point where it has one ([`super::design::shape_t1`]) — weighted least squares in T2 (N) with the
//! weights of the noise's variance function ([`Weights`]). Giving every run its own mu
//! conditions out everything that varies between runs and cords (their scatter of mu, their
//! tare, wear, diameter and speed dependence, a gain error): what is left to θ is the shape of
//! T2 against T1, time and wrap inside runs — the within estimator of a mixed model whose run
//! effects are far larger than the noise.
//!
//! The problem is solved by Levenberg-Marquardt on (θ, mu₁…mu_R) through its arrow-head
//! structure: each residual depends on θ and on its own run's mu only, so the normal equations
//! reduce (Schur complement) to a k×k system for δθ plus R scalar ones. Predictions come from
//! `fit::predict::predict_run` (the shared `capstan_physics::Model`, with the contact's load
//! memory carried along each run); sensitivities come from the law's closed-form partials
//! through the chain rule (`within/sens.rs`), checked against forward differences.
//!
//! Uncertainty: the model-based covariance σ²S⁻¹ (S the Schur complement of the information)
//! and the cluster-robust covariance with runs as clusters, built from each run's profile
//! score (its mu projected out) in the jackknife form (CR3: each run's score through the
//! information without that run, (G − 1)/G): valid whatever the correlation of residuals
//! inside a run (its tare, the wander of its mu, serial correlation), and not fooled by a few
//! runs that carry most of the information.

use super::candidates::{run_model, ThetaMap};
use super::design::Design;
use crate::fit::predict::{predict_run, Hint, RunRows};
use nalgebra::{DMatrix, DVector};

mod normal;
mod sens;
mod weights;

use normal::{bounded_step, normal, schur, Normal};

pub use weights::Weights;

/// The lowest mu a run is given: a cord that transmits no friction (T2 = T1) fits here.
const MU_FLOOR: f64 = 1e-4;

/// Which block of θ each run uses: one block (every run shares θ), or one block per stratum
/// of runs (e.g. per wrap) for the constancy check of the adequacy test. Block s is
/// θ[s·k .. (s + 1)·k] with its maps; run u uses block `of_unit[u]`.
#[derive(Clone, Debug)]
pub struct Strata {
    /// Parameters per block.
    pub k: usize,
    /// The block of every run.
    pub of_unit: Vec<usize>,
}

impl Strata {
    /// Every run shares the `k` parameters.
    pub fn shared(d: &Design, k: usize) -> Strata {
        Strata {
            k,
            of_unit: vec![0; d.units.len()],
        }
    }

    /// The θ (and maps) range of run `u`.
    fn block(&self, u: usize) -> std::ops::Range<usize> {
        let s = self.of_unit[u];
        s * self.k..(s + 1) * self.k
    }
}

/// A fitted within-run model.
#[derive(Clone, Debug)]
pub struct WithinFit {
    /// The effects and their θ maps, in θ order (block after block with strata).
    pub maps: Vec<ThetaMap>,
    /// Which block of θ each run uses.
    pub strata: Strata,
    /// θ (internal coordinates).
    pub theta: Vec<f64>,
    /// Every run's mu.
    pub mu: Vec<f64>,
    /// Fitted T2 per row, N.
    pub fitted: Vec<f64>,
    /// Weighted residual sum of squares.
    pub wrss: f64,
    /// Unweighted residual sum of squares, N².
    pub rss: f64,
    /// Model-based covariance of θ, σ²S⁻¹ (row-major k×k; NaN where S is singular).
    pub cov_model: Vec<f64>,
    /// Cluster-robust covariance of θ (runs as clusters, CR1).
    pub cov_robust: Vec<f64>,
}

impl WithinFit {
    /// Number of shared parameters.
    pub fn k(&self) -> usize {
        self.maps.len()
    }

    /// Catalogue value of parameter `j`.
    pub fn value(&self, j: usize) -> f64 {
        self.maps[j].value(self.theta[j])
    }

    /// Overdispersion of parameter `j`: robust over model-based variance (at least 1).
    pub fn c_hat(&self, j: usize) -> f64 {
        let k = self.k();
        let r = self.cov_robust[j * k + j] / self.cov_model[j * k + j];
        if r.is_finite() {
            r.max(1.0)
        } else {
            1.0
        }
    }

    /// Cluster-robust standard error of the catalogue value of parameter `j`.
    pub fn se_robust(&self, j: usize) -> f64 {
        let k = self.k();
        self.cov_robust[j * k + j].max(0.0).sqrt() * self.maps[j].derivative(self.theta[j]).abs()
    }

    /// Residuals, N.
    pub fn residuals(&self, d: &Design) -> Vec<f64> {
        (0..d.n()).map(|i| d.t2[i] - self.fitted[i]).collect()
    }
}

/// The rows of run `u` for the predictor.
fn run_rows(d: &Design, u: usize) -> RunRows<'_> {
    RunRows {
        t1_n: &d.t1,
        t1_shape_n: Some(&d.t1_shape),
        op: &d.op,
        timing: &d.timing,
        rows: &d.units[u],
    }
}

/// Predict every row for run mu `mu` and shared `theta` (from predictions `hint` for nearby
/// values, if given); returns (WRSS, RSS).
fn predict(
    d: &Design,
    (maps, strata): (&[ThetaMap], &Strata),
    (mu, theta): (&[f64], &[f64]),
    w: &Weights,
    hint: Option<Hint<'_>>,
    (out, slopes): (&mut [f64], &mut [f64]),
) -> (f64, f64) {
    for (u, &mu_u) in mu.iter().enumerate().take(d.units.len()) {
        let b = strata.block(u);
        let m = run_model(&maps[b.clone()], mu_u, &theta[b]);
        predict_run(&m, run_rows(d, u), d.timed, hint, out, Some(&mut *slopes));
    }
    let (mut wrss, mut rss) = (0.0, 0.0);
    for ((o, t2), wi) in out.iter().zip(&d.t2).zip(&w.w) {
        let r = o - t2;
        rss += r * r;
        wrss += wi * r * r;
    }
    if wrss.is_finite() {
        (wrss, rss)
    } else {
        (f64::INFINITY, f64::INFINITY)
    }
}

/// Sensitivities of every row: a = ∂f/∂mu (own run), b = ∂f/∂θ (row-major n×k).
struct Sens {
    a: Vec<f64>,
    b: Vec<f64>,
    scratch: Vec<f64>,
}

impl Sens {
    fn new(n: usize, k: usize) -> Sens {
        Sens {
            a: vec![0.0; n],
            b: vec![0.0; n * k],
            scratch: vec![0.0; n],
        }
    }
}

/// Sensitivities at (mu, θ) around the predictions `f0`: analytic ([`sens`]) for the effects
/// it knows, else forward differences.
fn jacobian(
    d: &Design,
    (maps, strata): (&[ThetaMap], &Strata),
    (mu, theta): (&[f64], &[f64]),
    (f0, slope0): (&[f64], &[f64]),
    s: &mut Sens,
) {
    match sens::roles(maps) {
        Some(roles) => sens::jacobian(d, (maps, strata), (mu, theta), f0, &roles, s),
        None => jacobian_by_differences(d, (maps, strata), (mu, theta), (f0, slope0), s),
    }
}

/// Forward differences at (mu, θ) around the predictions `f0` (with the step equation's
/// slopes `slope0` there, for the heating's solve).
fn jacobian_by_differences(
    d: &Design,
    (maps, strata): (&[ThetaMap], &Strata),
    (mu, theta): (&[f64], &[f64]),
    (f0, slope0): (&[f64], &[f64]),
    s: &mut Sens,
) {
    let k = maps.len();
    let Sens { a, b, scratch } = s;
    let hint = Some(Hint {
        t2: f0,
        slope: Some(slope0),
    });
    let h: Vec<f64> = mu.iter().map(|m| 1e-6 * m.abs().max(1e-3)).collect();
    for (u, rows) in d.units.iter().enumerate() {
        let blk = strata.block(u);
        let m = run_model(&maps[blk.clone()], mu[u] + h[u], &theta[blk]);
        predict_run(&m, run_rows(d, u), d.timed, hint, scratch, None);
        for &i in rows {
            a[i] = (scratch[i] - f0[i]) / h[u];
        }
    }
    b.iter_mut().for_each(|x| *x = 0.0);
    for j in 0..k {
        let step = maps[j].step();
        let hb = if theta[j] + step > maps[j].hi {
            -step
        } else {
            step
        };
        let mut th = theta.to_vec();
        th[j] += hb;
        // Only the runs whose block holds θ_j move.
        for (u, rows) in d.units.iter().enumerate() {
            let blk = strata.block(u);
            if !blk.contains(&j) {
                continue;
            }
            let m = run_model(&maps[blk.clone()], mu[u], &th[blk]);
            predict_run(&m, run_rows(d, u), d.timed, hint, scratch, None);
            for &i in rows {
                b[i * k + j] = (scratch[i] - f0[i]) / hb;
            }
        }
    }
}

/// Fit the effects of `maps` from θ₀ and run mu₀, every run sharing θ.
pub fn fit(d: &Design, maps: &[ThetaMap], theta0: &[f64], mu0: &[f64], w: &Weights) -> WithinFit {
    fit_strata(d, (maps, &Strata::shared(d, maps.len())), theta0, mu0, w)
}

/// The fit's current point, its predictions and slopes, and the trial point's buffers.
struct Iterate {
    theta: Vec<f64>,
    mu: Vec<f64>,
    f: Vec<f64>,
    slopes: Vec<f64>,
    trial: Vec<f64>,
    trial_slopes: Vec<f64>,
    lin: Vec<f64>,
    wrss: f64,
    rss: f64,
    lambda: f64,
}

/// Fit with θ in blocks by strata of runs (see [`Strata`]).
pub fn fit_strata(
    d: &Design,
    (maps, strata): (&[ThetaMap], &Strata),
    theta0: &[f64],
    mu0: &[f64],
    w: &Weights,
) -> WithinFit {
    let (n, k, nu) = (d.n(), maps.len(), d.units.len());
    let mut it = Iterate {
        theta: (theta0.iter().zip(maps))
            .map(|(t, m)| t.clamp(m.lo, m.hi))
            .collect(),
        mu: mu0.to_vec(),
        f: vec![0.0; n],
        slopes: vec![f64::NAN; n],
        trial: vec![0.0; n],
        trial_slopes: vec![f64::NAN; n],
        lin: vec![0.0; n],
        wrss: 0.0,
        rss: 0.0,
        lambda: 1e-3,
    };
    let mut sens = Sens::new(n, k);
    (it.wrss, it.rss) = predict(
        d,
        (maps, strata),
        (&it.mu, &it.theta),
        w,
        None,
        (&mut it.f, &mut it.slopes),
    );
    for _iter in 0..80 {
        jacobian(
            d,
            (maps, strata),
            (&it.mu, &it.theta),
            (&it.f, &it.slopes),
            &mut sens,
        );
        let resid: Vec<f64> = (0..n).map(|i| it.f[i] - d.t2[i]).collect();
        let nm = normal(d, k, w, &resid, &sens.a, &sens.b);
        // A run whose mu sits on its floor and would go lower is held there (a projected
        // step): left free, its clamped update would not be the step the system solved for,
        // and the fit would crawl (a cord worn to no friction, say).
        let held: Vec<bool> = (0..nu)
            .map(|u| it.mu[u] <= MU_FLOOR && nm.g[u] > 0.0)
            .collect();
        if !damped_step(d, (maps, strata), w, (&sens, &nm, &held), &mut it) {
            break;
        }
    }
    let (cov_model, cov_robust) = covariances(
        d,
        (maps, strata),
        (&it.mu, &it.theta),
        (&it.f, &it.slopes),
        w,
        it.wrss,
    );
    WithinFit {
        maps: maps.to_vec(),
        strata: strata.clone(),
        theta: it.theta,
        mu: it.mu,
        fitted: it.f,
        wrss: it.wrss,
        rss: it.rss,
        cov_model,
        cov_robust,
    }
}

/// The trial point of a step with damping `lambda`: θ by the projected Newton step within its
/// bounds, each run's mu by back-substitution (held runs stay, mu no lower than its floor);
/// returns (θ, mu, the change of θ).
fn proposal(
    nm: &Normal,
    (theta, mu): (&[f64], &[f64]),
    maps: &[ThetaMap],
    lambda: f64,
    held: &[bool],
) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let k = maps.len();
    let (s, rhs) = schur(nm, k, lambda, held);
    let dtheta = bounded_step(s, rhs, theta, maps);
    let new_theta: Vec<f64> = (0..k)
        .map(|j| (theta[j] + dtheta[j]).clamp(maps[j].lo, maps[j].hi))
        .collect();
    let dt: Vec<f64> = (0..k).map(|j| new_theta[j] - theta[j]).collect();
    let new_mu: Vec<f64> = (0..mu.len())
        .map(|u| {
            if held[u] {
                return mu[u];
            }
            let c = &nm.c[u * k..(u + 1) * k];
            let cd: f64 = c.iter().zip(&dt).map(|(c, t)| c * t).sum();
            (mu[u] + (-nm.g[u] - cd) / (nm.d[u] * (1.0 + lambda))).max(MU_FLOOR)
        })
        .collect();
    (new_theta, new_mu, dt)
}

/// One Levenberg-Marquardt step: raise the damping until a trial point lowers the weighted
/// RSS (then take it and relax the damping) or the damping runs away. True when the step
/// improved the fit by more than a relative 1e-8 (the fit goes on).
fn damped_step(
    d: &Design,
    (maps, strata): (&[ThetaMap], &Strata),
    w: &Weights,
    (sens, nm, held): (&Sens, &Normal, &[bool]),
    it: &mut Iterate,
) -> bool {
    for _ in 0..30 {
        let (new_theta, new_mu, dt) = proposal(nm, (&it.theta, &it.mu), maps, it.lambda, held);
        // The trial's step equations start from the linearised predictions, with the
        // slopes of the current point: close enough that one evaluation often settles them.
        linearised(d, sens, (&it.f, &it.mu, &new_mu, &dt), &mut it.lin);
        let hint = Hint {
            t2: &it.lin,
            slope: Some(&it.slopes),
        };
        let (new_wrss, new_rss) = predict(
            d,
            (maps, strata),
            (&new_mu, &new_theta),
            w,
            Some(hint),
            (&mut it.trial, &mut it.trial_slopes),
        );
        if new_wrss < it.wrss {
            let rel = (it.wrss - new_wrss) / it.wrss.max(1e-300);
            it.theta = new_theta;
            it.mu = new_mu;
            it.wrss = new_wrss;
            it.rss = new_rss;
            std::mem::swap(&mut it.f, &mut it.trial);
            std::mem::swap(&mut it.slopes, &mut it.trial_slopes);
            it.lambda = (it.lambda / 4.0).max(1e-9);
            return rel > 1e-8;
        }
        it.lambda *= 5.0;
        if it.lambda > 1e12 {
            break;
        }
    }
    false
}

/// f + a·δmu + b·δθ: the predictions to first order after a step.
fn linearised(
    d: &Design,
    s: &Sens,
    (f, mu, new_mu, dt): (&[f64], &[f64], &[f64], &[f64]),
    out: &mut [f64],
) {
    let k = dt.len();
    for (u, rows) in d.units.iter().enumerate() {
        let dmu = new_mu[u] - mu[u];
        for &i in rows {
            let b = &s.b[i * k..(i + 1) * k];
            out[i] = f[i] + s.a[i] * dmu + b.iter().zip(dt).map(|(b, t)| b * t).sum::<f64>();
        }
    }
}

/// Model-based and cluster-robust covariances of θ at the solution.
fn covariances(
    d: &Design,
    (maps, strata): (&[ThetaMap], &Strata),
    (mu, theta): (&[f64], &[f64]),
    (f, slopes): (&[f64], &[f64]),
    w: &Weights,
    wrss: f64,
) -> (Vec<f64>, Vec<f64>) {
    let n = d.n();
    let k = maps.len();
    let nan = vec![f64::NAN; k * k];
    if k == 0 {
        return (Vec::new(), Vec::new());
    }
    let mut sens = Sens::new(n, k);
    jacobian(d, (maps, strata), (mu, theta), (f, slopes), &mut sens);
    let (a, b) = (&sens.a, &sens.b);
    let resid: Vec<f64> = (0..n).map(|i| f[i] - d.t2[i]).collect();
    let nm = normal(d, k, w, &resid, a, b);
    let (s, _) = schur(&nm, k, 0.0, &vec![false; d.units.len()]);
    let Some(s_inv) = s.clone().try_inverse() else {
        return (nan.clone(), nan);
    };
    let g = d.units.len() as f64;
    let dof = (n as f64 - g - k as f64).max(1.0);
    let sigma2 = wrss / dof;
    // Each run's profile score s_g (its mu projected out) and its share A_g of the information.
    // The jackknife form (CR3, the one-step leave-one-run-out estimate) inflates the score of
    // a run that carries much of the information (a high wrap tells more about a T1 offset
    // than a low one): the plain sandwich (CR1) understates the variance then.
    let mut robust = DMatrix::<f64>::zeros(k, k);
    for (u, rows) in d.units.iter().enumerate() {
        let c = &nm.c[u * k..(u + 1) * k];
        let mut score = DVector::<f64>::zeros(k);
        let mut info = DMatrix::<f64>::zeros(k, k);
        for &i in rows {
            let bt: Vec<f64> = (0..k)
                .map(|j| b[i * k + j] - a[i] * c[j] / nm.d[u])
                .collect();
            for j in 0..k {
                score[j] += w.w[i] * bt[j] * resid[i];
                for l in 0..k {
                    info[(j, l)] += w.w[i] * bt[j] * bt[l];
                }
            }
        }
        let m = (&s - info).try_inverse().unwrap_or_else(|| s_inv.clone());
        let ms = &m * score;
        robust += &ms * ms.transpose();
    }
    let robust = robust * ((g - 1.0) / g).max(0.0);
    let model = &s_inv * sigma2;
    let flat = |m: DMatrix<f64>| (0..k * k).map(|x| m[(x / k, x % k)]).collect();
    (flat(model), flat(robust))
}

/// The sensitivities of every row at a fit: ∂f/∂mu of its own run, and ∂f/∂θ (row-major
/// n×k), as the fit's own solver computes them (what the cord-level summaries linearise on).
pub fn sensitivities(d: &Design, fit: &WithinFit, w: &Weights) -> (Vec<f64>, Vec<f64>) {
    let (n, k) = (d.n(), fit.k());
    let maps = (fit.maps.as_slice(), &fit.strata);
    let (mut f, mut slopes) = (vec![0.0; n], vec![f64::NAN; n]);
    predict(
        d,
        maps,
        (&fit.mu, &fit.theta),
        w,
        None,
        (&mut f, &mut slopes),
    );
    let mut sens = Sens::new(n, k);
    jacobian(d, maps, (&fit.mu, &fit.theta), (&f, &slopes), &mut sens);
    (sens.a, sens.b)
}

/// Start values of every run's mu: the median of ln(T2/T1)/β over its rows with both
/// tensions above zero (the only rows a logarithm takes).
pub fn start_mu(d: &Design) -> Vec<f64> {
    d.units
        .iter()
        .map(|rows| {
            let mut v: Vec<f64> = rows
                .iter()
                .filter(|&&i| d.t1[i] > 0.0 && d.t2[i] > 0.0)
                .map(|&i| (d.t2[i] / d.t1[i]).ln() / d.op[i].wrap_rad)
                .filter(|x| x.is_finite())
                .collect();
            v.sort_by(f64::total_cmp);
            let m = if v.is_empty() { 0.1 } else { v[v.len() / 2] };
            m.clamp(0.005, 2.0)
        })
        .collect()
}

/// The best of fits from several starts of the last parameter (the others at `theta0`).
pub fn fit_multistart(
    d: &Design,
    maps: &[ThetaMap],
    theta0: &[f64],
    mu0: &[f64],
    w: &Weights,
) -> WithinFit {
    let k = maps.len();
    let starts = if k == 0 {
        vec![theta0.to_vec()]
    } else {
        maps[k - 1]
            .starts()
            .into_iter()
            .map(|s| {
                let mut t = theta0.to_vec();
                t[k - 1] = s;
                t
            })
            .collect()
    };
    let mut best: Option<WithinFit> = None;
    for t in starts {
        let f = fit(d, maps, &t, mu0, w);
        if best.as_ref().is_none_or(|b| f.wrss < b.wrss) {
            best = Some(f);
        }
    }
    best.expect("at least one start")
}
