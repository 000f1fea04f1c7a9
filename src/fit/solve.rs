//! Least-squares fits driven by the `levenberg-marquardt` crate.
//!
//! * [`FitProblem`]: a [`ModelSpec`] on a set of runs as a `LeastSquaresProblem`: residuals
//!   are predicted − measured T2 (N) on the training rows, plus √λ·u_g for each group's random
//!   effect (penalised least squares: Σr² + λΣu²); the Jacobian is analytic in structure (see
//!   [`super::predict`]).
//! * [`fit_fixed`]: fixed effects only (random effects held at zero).
//! * [`fit_penalised`]: fixed effects and group effects at a given λ.
//! * [`fit_mixed`]: λ = σ²/σ_u² re-estimated (EM / Laplace updates, as for a linear mixed
//!   model with the Jacobian as design), optionally capped so that fixed + edf ≤ a budget.
//! * [`loco`]: leave-one-group-out: refit on the other groups, predict the held-out group with
//!   population values (u = 0).
//! * [`information_criteria`]: AIC/BIC on T2 residuals, n·ln(RSS/n) + 2p / p·ln n.

use super::obs::Observations;
use super::params::ModelSpec;
use super::predict::{evaluate, Evaluation};
use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::{storage::Owned, DMatrix, DVector, Dyn};
use serde::Serialize;

/// A spec on a training set, as the solver sees it.
pub struct FitProblem<'a> {
    spec: &'a ModelSpec,
    obs: &'a Observations,
    runs: Vec<usize>,
    rows: Vec<usize>,
    /// Groups with a random effect (those with training rows), in parameter order.
    re_groups: Vec<usize>,
    lambda: f64,
    theta: Vec<f64>,
    u: Vec<f64>,
    eval: Evaluation,
}

impl<'a> FitProblem<'a> {
    /// A problem on `runs`. With a random effect in `spec` and `lambda` given, the group
    /// effects are parameters (penalised by `lambda`); otherwise they stay at zero.
    pub fn new(
        spec: &'a ModelSpec,
        obs: &'a Observations,
        runs: &[usize],
        lambda: Option<f64>,
        theta: &[f64],
        u: &[f64],
    ) -> Self {
        let rows = obs.rows_of(runs);
        let mut re_groups: Vec<usize> = Vec::new();
        if spec.random.is_some() && lambda.is_some() {
            for &i in &rows {
                let g = obs.rows[i].group;
                if !re_groups.contains(&g) {
                    re_groups.push(g);
                }
            }
            re_groups.sort();
        }
        let mut uu = vec![0.0; obs.groups.len()];
        for &g in &re_groups {
            uu[g] = u.get(g).copied().unwrap_or(0.0);
        }
        let mut p = FitProblem {
            spec,
            obs,
            runs: runs.to_vec(),
            rows,
            re_groups,
            lambda: lambda.unwrap_or(0.0),
            theta: theta.to_vec(),
            u: uu,
            eval: Evaluation::default(),
        };
        p.eval = evaluate(spec, &p.theta, &p.u, obs, &p.runs, false);
        p
    }

    fn n_params(&self) -> usize {
        self.theta.len() + self.re_groups.len()
    }

    /// Current fixed-effect θ.
    pub fn theta(&self) -> &[f64] {
        &self.theta
    }

    /// Current group offsets (indexed by group).
    pub fn u(&self) -> &[f64] {
        &self.u
    }

    /// Residual sum of squares of T2 on the training rows (without the penalty).
    pub fn rss(&self) -> f64 {
        self.rows
            .iter()
            .map(|&i| (self.eval.t2_n[i] - self.obs.rows[i].t2_n).powi(2))
            .sum()
    }

    /// Σ_i (dT2_i/du_g)² per group (the information each group carries about its effect).
    pub fn group_information(&self) -> Vec<f64> {
        let Some(j) = self.spec.random else {
            return vec![0.0; self.obs.groups.len()];
        };
        let ev = evaluate(self.spec, &self.theta, &self.u, self.obs, &self.runs, true);
        let mut info = vec![0.0; self.obs.groups.len()];
        for &i in &self.rows {
            info[self.obs.rows[i].group] += ev.grad(i)[j].powi(2);
        }
        info
    }
}

impl LeastSquaresProblem<f64, Dyn, Dyn> for FitProblem<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, x: &DVector<f64>) {
        let nf = self.theta.len();
        self.theta.copy_from_slice(&x.as_slice()[..nf]);
        for (k, &g) in self.re_groups.iter().enumerate() {
            self.u[g] = x[nf + k];
        }
        self.eval = evaluate(self.spec, &self.theta, &self.u, self.obs, &self.runs, false);
    }

    fn params(&self) -> DVector<f64> {
        let mut v = self.theta.clone();
        v.extend(self.re_groups.iter().map(|&g| self.u[g]));
        DVector::from_vec(v)
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        let m = self.rows.len() + self.re_groups.len();
        let mut r = DVector::zeros(m);
        for (k, &i) in self.rows.iter().enumerate() {
            let v = self.eval.t2_n[i] - self.obs.rows[i].t2_n;
            r[k] = if v.is_finite() { v } else { 1e6 };
        }
        let s = self.lambda.sqrt();
        for (k, &g) in self.re_groups.iter().enumerate() {
            r[self.rows.len() + k] = s * self.u[g];
        }
        Some(r)
    }

    fn jacobian(&self) -> Option<DMatrix<f64>> {
        let ev = evaluate(self.spec, &self.theta, &self.u, self.obs, &self.runs, true);
        let nf = self.theta.len();
        let m = self.rows.len() + self.re_groups.len();
        let mut jac = DMatrix::zeros(m, self.n_params());
        for (k, &i) in self.rows.iter().enumerate() {
            let grad = ev.grad(i);
            for j in 0..nf {
                jac[(k, j)] = if grad[j].is_finite() { grad[j] } else { 0.0 };
            }
            if let Some(jr) = self.spec.random {
                let g = self.obs.rows[i].group;
                if let Some(pos) = self.re_groups.iter().position(|&x| x == g) {
                    jac[(k, nf + pos)] = jac[(k, jr)];
                }
            }
        }
        let s = self.lambda.sqrt();
        for k in 0..self.re_groups.len() {
            jac[(self.rows.len() + k, nf + k)] = s;
        }
        Some(jac)
    }
}

/// A fitted spec.
#[derive(Clone, Debug)]
pub struct Fit {
    /// What was fitted.
    pub spec: ModelSpec,
    /// Fixed-effect θ (internal coordinates).
    pub theta: Vec<f64>,
    /// Group offsets on the random-effect parameter (zero where none), indexed by group.
    pub u: Vec<f64>,
    /// Runs fitted.
    pub runs: Vec<usize>,
    /// Penalty λ = σ²/σ_u² (None for a fixed-effects fit).
    pub lambda: Option<f64>,
    /// Residual variance estimate σ², N².
    pub sigma2: f64,
    /// Standard deviation of the group effects (None without them).
    pub sigma_u: Option<f64>,
    /// Effective degrees of freedom of the group effects (Σ J_g/(J_g + λ)).
    pub edf_random: f64,
    /// Residual sum of squares of T2 on the fitted rows, N².
    pub rss: f64,
    /// Number of fitted rows.
    pub n: usize,
    /// In-sample predictions (with the group effects), NaN outside the fitted runs.
    pub t2_n: Vec<f64>,
    /// How the solver stopped.
    pub termination: String,
    /// Residual evaluations used.
    pub evaluations: usize,
}

impl Fit {
    /// The model of group `g` (with its effect), or the population model (`None`).
    pub fn model(&self, group: Option<usize>) -> capstan_friction::Model {
        let u = group.map_or(0.0, |g| self.u.get(g).copied().unwrap_or(0.0));
        self.spec.model(&self.theta, u)
    }

    /// Fitted values of the free parameters (population), by name.
    pub fn values(&self) -> Vec<(&'static str, f64)> {
        let m = self.model(None);
        self.spec
            .free
            .iter()
            .map(|f| (f.param.name(), f.param.get(&m)))
            .collect()
    }

    /// In-sample RMSE of T2, N.
    pub fn rmse(&self) -> f64 {
        (self.rss / self.n as f64).sqrt()
    }

    /// Number of fixed effects.
    pub fn n_fixed(&self) -> usize {
        self.spec.n_fixed()
    }

    /// Parameter count by the usual mixed-model convention: fixed effects + one variance
    /// component if there are random effects.
    pub fn n_params_mixed(&self) -> usize {
        self.n_fixed() + usize::from(self.lambda.is_some())
    }

    /// Parameter count with the random effects counted by their effective dof.
    pub fn n_params_edf(&self) -> f64 {
        self.n_fixed() as f64 + self.edf_random
    }

    /// Predictions for `runs` with (`with_random`) or without the group effects.
    pub fn predict(&self, obs: &Observations, runs: &[usize], with_random: bool) -> Vec<f64> {
        let zero = vec![0.0; obs.groups.len()];
        let u = if with_random { &self.u } else { &zero };
        evaluate(&self.spec, &self.theta, u, obs, runs, false).t2_n
    }

    /// AIC and BIC with `p` parameters.
    pub fn information_criteria(&self, p: f64) -> (f64, f64) {
        information_criteria(self.rss, self.n, p)
    }

    /// Standard errors of the fixed-effect *model values* from the Gauss-Newton covariance
    /// σ²(JᵀJ)⁻¹ (fixed effects only, group effects held at their values).
    pub fn standard_errors(&self, obs: &Observations) -> Vec<f64> {
        let ev = evaluate(&self.spec, &self.theta, &self.u, obs, &self.runs, true);
        let nf = self.theta.len();
        let rows = obs.rows_of(&self.runs);
        let mut jtj = DMatrix::<f64>::zeros(nf, nf);
        for &i in &rows {
            let g = ev.grad(i);
            for a in 0..nf {
                for b in 0..nf {
                    jtj[(a, b)] += g[a] * g[b];
                }
            }
        }
        let dv = self.spec.derivatives(&self.theta, 0.0);
        match jtj.try_inverse() {
            Some(inv) => (0..nf)
                .map(|a| (self.sigma2 * inv[(a, a)]).max(0.0).sqrt() * dv[a].abs())
                .collect(),
            None => vec![f64::NAN; nf],
        }
    }
}

/// AIC and BIC of T2 residuals: n·ln(RSS/n) + 2p and n·ln(RSS/n) + p·ln n.
pub fn information_criteria(rss: f64, n: usize, p: f64) -> (f64, f64) {
    let n_f = n as f64;
    let base = n_f * (rss / n_f).ln();
    (base + 2.0 * p, base + p * n_f.ln())
}

fn solver() -> LevenbergMarquardt<f64> {
    LevenbergMarquardt::new()
        .with_ftol(1e-9)
        .with_xtol(1e-8)
        .with_gtol(1e-10)
        .with_patience(200)
}

fn finish(
    spec: &ModelSpec,
    runs: &[usize],
    p: FitProblem<'_>,
    lambda: Option<f64>,
    report: levenberg_marquardt::MinimizationReport<f64>,
) -> Fit {
    let rss = p.rss();
    let n = p.rows.len();
    let dof = (n as f64 - spec.n_fixed() as f64).max(1.0);
    Fit {
        spec: spec.clone(),
        theta: p.theta.clone(),
        u: p.u.clone(),
        runs: runs.to_vec(),
        lambda,
        sigma2: rss / dof,
        sigma_u: lambda.map(|l| (rss / dof / l).sqrt()),
        edf_random: 0.0,
        rss,
        n,
        t2_n: p.eval.t2_n.clone(),
        termination: format!("{:?}", report.termination),
        evaluations: report.number_of_evaluations,
    }
}

/// Fixed effects only, from `start` (θ) or the spec's base values.
pub fn fit_fixed(
    spec: &ModelSpec,
    obs: &Observations,
    runs: &[usize],
    start: Option<&[f64]>,
) -> Fit {
    let theta = start.map_or_else(|| spec.start(), <[f64]>::to_vec);
    let u = vec![0.0; obs.groups.len()];
    let problem = FitProblem::new(spec, obs, runs, None, &theta, &u);
    let (p, report) = solver().minimize(problem);
    finish(spec, runs, p, None, report)
}

/// The best (lowest RSS) of fixed-effects fits from several starts.
pub fn fit_fixed_multistart(
    spec: &ModelSpec,
    obs: &Observations,
    runs: &[usize],
    starts: &[Vec<f64>],
) -> Fit {
    let mut best: Option<Fit> = None;
    for s in starts {
        let f = fit_fixed(spec, obs, runs, Some(s));
        if best.as_ref().is_none_or(|b| f.rss < b.rss) {
            best = Some(f);
        }
    }
    best.unwrap_or_else(|| fit_fixed(spec, obs, runs, None))
}

/// Penalised least squares at a given λ: Σ r² + λ Σ u_g².
pub fn fit_penalised(
    spec: &ModelSpec,
    obs: &Observations,
    runs: &[usize],
    lambda: f64,
    theta: &[f64],
    u: &[f64],
) -> Fit {
    let problem = FitProblem::new(spec, obs, runs, Some(lambda), theta, u);
    let (p, report) = solver().minimize(problem);
    finish(spec, runs, p, Some(lambda), report)
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
}

impl Default for MixedOptions {
    fn default() -> Self {
        MixedOptions {
            lambda0: 200.0,
            max_updates: 12,
            edf_cap: None,
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
    for _ in 0..opts.max_updates {
        let problem = FitProblem::new(spec, obs, runs, Some(lambda), &theta, &u);
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
    let problem = FitProblem::new(spec, obs, runs, Some(lambda), &theta, &u);
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
    let mut fit = finish(spec, runs, pr, Some(lambda), report);
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
        let target = cap - p;
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

/// Result of a leave-one-group-out run.
#[derive(Clone, Debug, Serialize)]
pub struct Loco {
    /// Held-out prediction of every row (its cord left out, population values), N.
    pub t2_n: Vec<f64>,
    /// Pooled RMSE over all rows, N.
    pub rmse: f64,
    /// Fitted values per fold (fold g = group g held out).
    pub fold_values: Vec<Vec<(&'static str, f64)>>,
}

impl Loco {
    /// Jackknife standard error of each fitted value over the folds.
    pub fn jackknife_se(&self) -> Vec<(&'static str, f64)> {
        let g = self.fold_values.len() as f64;
        if self.fold_values.is_empty() {
            return Vec::new();
        }
        (0..self.fold_values[0].len())
            .map(|k| {
                let vals: Vec<f64> = self.fold_values.iter().map(|f| f[k].1).collect();
                let mean = vals.iter().sum::<f64>() / g;
                let ss: f64 = vals.iter().map(|v| (v - mean).powi(2)).sum();
                (self.fold_values[0][k].0, ((g - 1.0) / g * ss).sqrt())
            })
            .collect()
    }
}

/// Leave each group out in turn: `refit(training_runs)` fits on the others, and the held-out
/// rows are predicted by the population model (u = 0). Folds run on up to `threads` threads.
pub fn loco<F>(obs: &Observations, threads: usize, refit: F) -> Loco
where
    F: Fn(&[usize]) -> Fit + Sync,
{
    let n_groups = obs.groups.len();
    type Fold = (Vec<f64>, Vec<(&'static str, f64)>);
    let mut results: Vec<Option<Fold>> = vec![None; n_groups];
    let threads = threads.clamp(1, n_groups.max(1));
    std::thread::scope(|s| {
        let chunks: Vec<Vec<usize>> = (0..threads)
            .map(|t| (t..n_groups).step_by(threads).collect())
            .collect();
        let handles: Vec<_> = chunks
            .into_iter()
            .map(|groups| {
                let refit = &refit;
                s.spawn(move || {
                    groups
                        .into_iter()
                        .map(|g| {
                            let train = obs.runs_without_group(g);
                            let fit = refit(&train);
                            let test: Vec<usize> = (0..obs.runs.len())
                                .filter(|&r| obs.rows[obs.runs[r][0]].group == g)
                                .collect();
                            (g, fit.predict(obs, &test, false), fit.values())
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        for h in handles {
            for (g, pred, vals) in h.join().expect("LOCO fold panicked") {
                results[g] = Some((pred, vals));
            }
        }
    });
    let mut t2 = vec![f64::NAN; obs.rows.len()];
    let mut fold_values = Vec::new();
    for r in results.into_iter().flatten() {
        for (i, row) in obs.rows.iter().enumerate() {
            if r.0[i].is_finite() && !t2[i].is_finite() {
                let _ = row;
                t2[i] = r.0[i];
            }
        }
        fold_values.push(r.1);
    }
    let se: f64 = obs
        .rows
        .iter()
        .zip(&t2)
        .map(|(r, p)| (p - r.t2_n).powi(2))
        .sum();
    Loco {
        rmse: (se / obs.rows.len() as f64).sqrt(),
        t2_n: t2,
        fold_values,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::thesis_dataset;
    use crate::fit::params::Param;
    use capstan_friction::Model;
    use levenberg_marquardt::differentiate_numerically;

    #[test]
    fn euler_eytelwein_global_mu_matches_the_reference() {
        let obs = Observations::from_dataset(&thesis_dataset());
        let spec = ModelSpec::new("ee", Model::euler_eytelwein(0.115)).free(Param::Mu);
        let fit = fit_fixed(&spec, &obs, &obs.all_runs(), None);
        let mu = fit.model(None).law.mu;
        assert!((mu - 0.1162).abs() < 5e-5, "{mu}");
        assert!((fit.rmse() - 1.718).abs() < 5e-4, "{}", fit.rmse());
    }

    #[test]
    fn problem_jacobian_matches_numerical_differences() {
        let obs = Observations::from_dataset(&thesis_dataset());
        let mut base = Model::euler_eytelwein(0.14);
        base.law.heat_per_ns = 0.0013;
        base.law.heat_tau_s = 7.0;
        base.sensors.t1_offset_n = 0.2;
        let spec = ModelSpec::new("a", base)
            .free(Param::Mu)
            .free(Param::HeatPerNs)
            .free(Param::HeatTauS)
            .free(Param::T1Offset)
            .free(Param::MuLogSlopePerRad)
            .random_effect_on(Param::Mu);
        let runs: Vec<usize> = (0..obs.runs.len()).step_by(7).collect();
        let u: Vec<f64> = (0..10).map(|g| 0.01 * g as f64 - 0.04).collect();
        let mut p = FitProblem::new(&spec, &obs, &runs, Some(300.0), &spec.start(), &u);
        let num = differentiate_numerically(&mut p).unwrap();
        let ana = p.jacobian().unwrap();
        let scale = ana.amax();
        let err = (&num - &ana).amax();
        assert!(
            err < 1e-5 * scale,
            "max |num − analytic| = {err} (scale {scale})"
        );
    }
}
