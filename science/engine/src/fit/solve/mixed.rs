//! Penalised fits at a given λ and mixed fits with λ = σ²/σ_u² re-estimated.

use super::budget::Budget;
use super::problem::{solver, FitProblem};
use super::result::{finish, Fit};
use crate::fit::obs::Observations;
use crate::fit::params::ModelSpec;

/// Penalised least squares at a given λ: Σ r² + λ Σ u_g².
pub fn fit_penalised(
    spec: &ModelSpec,
    obs: &Observations,
    runs: &[usize],
    lambda: f64,
    theta: &[f64],
    u: &[f64],
) -> Fit {
    let rows = obs.rows_of(runs).len();
    let budget = Budget::for_fit(rows, spec.free.len() + obs.groups.len());
    let problem = FitProblem::new(spec, obs, runs, Some(lambda), theta, u, &budget);
    let (p, report) = solver().minimize(problem);
    finish(spec, runs, p, Some(lambda), report, &budget)
}

/// Options of [`fit_mixed`].
#[derive(Clone, Copy, Debug)]
pub struct MixedOptions {
    /// Start value of λ = σ²/σ_u².
    pub lambda0: f64,
    /// Maximum number of λ updates.
    pub max_updates: usize,
    /// If set, shrink harder so that fixed + edf of the group effects ≤ this.
    pub edf_cap: Option<f64>,
    /// If set, the most work units the fit may spend (below its size's budget, e.g. one fold
    /// of many).
    pub max_units: Option<u64>,
}

impl Default for MixedOptions {
    fn default() -> Self {
        MixedOptions {
            lambda0: 200.0,
            max_updates: 12,
            edf_cap: None,
            max_units: None,
        }
    }
}

/// Mixed model by penalised least squares with λ re-estimated (EM / Laplace):
/// edf_g = J_g/(J_g + λ), σ² = RSS/(n − p − Σedf), σ_u² = (Σu² + Σσ²/(J_g + λ))/G, λ = σ²/σ_u²,
/// where J_g = Σ_i∈g (∂T2_i/∂u_g)². The spec must carry a random effect.
pub fn fit_mixed(
    spec: &ModelSpec,
    obs: &Observations,
    runs: &[usize],
    start: Option<&[f64]>,
    opts: MixedOptions,
) -> Fit {
    let theta = start.map_or_else(|| spec.start(), <[f64]>::to_vec);
    let u = vec![0.0; obs.groups.len()];
    fit_mixed_from(spec, obs, runs, theta, u, opts)
}

/// [`fit_mixed`] warm-started from θ and group offsets `u` (e.g. a related fit's).
pub fn fit_mixed_from(
    spec: &ModelSpec,
    obs: &Observations,
    runs: &[usize],
    theta: Vec<f64>,
    u: Vec<f64>,
    opts: MixedOptions,
) -> Fit {
    let (mut theta, mut u) = (theta, u);
    let mut lambda = opts.lambda0;
    let p = spec.n_fixed() as f64;
    let mut evaluations = 0;
    let rows = obs.rows_of(runs).len();
    let params = spec.free.len() + obs.groups.len();
    let budget = match opts.max_units {
        Some(cap) => Budget::for_fit_within(rows, params, cap),
        None => Budget::for_fit(rows, params),
    };
    for _ in 0..opts.max_updates {
        if budget.spent() {
            break;
        }
        let problem = FitProblem::new(spec, obs, runs, Some(lambda), &theta, &u, &budget);
        let (pr, report) = solver().minimize(problem);
        evaluations += report.number_of_evaluations;
        theta = pr.theta.clone();
        u = pr.u.clone();
        let (new, _, _) = lambda_update(&pr, p, lambda, opts.edf_cap);
        let done = (new / lambda).ln().abs() < 1e-2;
        lambda = new;
        if done {
            break;
        }
    }
    let problem = FitProblem::new(spec, obs, runs, Some(lambda), &theta, &u, &budget);
    let (pr, report) = solver().minimize(problem);
    let info = pr.group_information();
    let edf: f64 = pr
        .re_groups
        .iter()
        .map(|&g| info[g] / (info[g] + lambda))
        .sum();
    let n = pr.rows.len() as f64;
    let rss = pr.rss();
    let sigma2 = rss / (n - p - edf).max(1.0);
    let mut fit = finish(spec, runs, pr, Some(lambda), report, &budget);
    fit.edf_random = edf;
    fit.sigma2 = sigma2;
    fit.sigma_u = Some((sigma2 / lambda).sqrt());
    fit.evaluations += evaluations;
    fit
}

/// One EM/Laplace update of λ; returns (λ, σ², Σedf).
fn lambda_update(pr: &FitProblem<'_>, p: f64, lambda: f64, cap: Option<f64>) -> (f64, f64, f64) {
    let info = pr.group_information();
    let js: Vec<f64> = pr.re_groups.iter().map(|&g| info[g]).collect();
    let edf: f64 = js.iter().map(|j| j / (j + lambda)).sum();
    let n = pr.rows.len() as f64;
    let sig2 = pr.rss() / (n - p - edf).max(1.0);
    let g = js.len().max(1) as f64;
    let tau2 = (pr.re_groups.iter().map(|&k| pr.u[k].powi(2)).sum::<f64>()
        + js.iter().map(|j| sig2 / (j + lambda)).sum::<f64>())
        / g;
    let mut new = (sig2 / tau2).clamp(1e-6, 1e12);
    if let Some(cap) = cap {
        let edf_of = |l: f64| js.iter().map(|j| j / (j + l)).sum::<f64>();
        // A hundredth below the budget: the last solve moves the sensitivities J_g a little,
        // and the fit must stay within it.
        let target = cap - p - 0.01;
        if edf_of(new) > target {
            // Bisection on ln λ for Σ J/(J+λ) = target.
            let (mut lo, mut hi) = (new.ln(), 1e12f64.ln());
            for _ in 0..100 {
                let mid = 0.5 * (lo + hi);
                if edf_of(mid.exp()) > target {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            new = hi.exp();
        }
    }
    (new, sig2, edf)
}
