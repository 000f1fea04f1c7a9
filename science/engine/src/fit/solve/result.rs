//! A fitted spec ([`Fit`]): values, counts, predictions, standard errors, and the
//! information criteria of its T2 residuals.

use super::budget::Budget;
use super::problem::FitProblem;
use crate::fit::obs::Observations;
use crate::fit::params::ModelSpec;
use crate::fit::predict::evaluate;
use nalgebra::DMatrix;

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
    /// The solver stopped on its tolerances (or at machine precision).
    pub converged: bool,
    /// Why it did not converge, if it did not ("did not converge: ...").
    pub stopped: Option<String>,
    /// Work units spent ([`super::budget`]).
    pub work_units: u64,
}

impl Fit {
    /// The model of group `g` (with its effect), or the population model (`None`).
    pub fn model(&self, group: Option<usize>) -> capstan_physics::Model {
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

/// A [`Fit`] from a solved problem (σ² with the fixed effects' degrees of freedom).
pub(super) fn finish(
    spec: &ModelSpec,
    runs: &[usize],
    p: FitProblem<'_>,
    lambda: Option<f64>,
    report: levenberg_marquardt::MinimizationReport<f64>,
    budget: &Budget,
) -> Fit {
    use levenberg_marquardt::TerminationReason as T;
    let stopped = match report.termination {
        T::Converged { .. }
        | T::Orthogonal
        | T::ResidualsZero
        | T::NoParameters
        | T::NoImprovementPossible(_) => None,
        T::User(_) => Some(format!(
            "did not converge: its work budget ({} units for {} rows) ran out after {} \
             evaluations",
            budget.limit(),
            p.rows.len(),
            report.number_of_evaluations
        )),
        T::LostPatience => Some(format!(
            "did not converge: its iteration budget ran out after {} evaluations",
            report.number_of_evaluations
        )),
        T::Numerical(what) => Some(format!(
            "did not converge: a numerical failure ({what} not finite: the model runs off to \
             infinity on these data)"
        )),
        ref other => Some(format!("did not converge: {other:?}")),
    };
    if std::env::var_os("CAPSTAN_FIT_LOG").is_some() {
        crate::trace::line(format_args!(
            "fit {}: {} rows, {} params, {} evaluations, {} of {} units, {:?}",
            spec.name,
            p.rows.len(),
            p.theta.len() + p.re_groups.len(),
            report.number_of_evaluations,
            budget.used(),
            budget.limit(),
            report.termination
        ));
    }
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
        converged: stopped.is_none(),
        stopped,
        work_units: budget.used(),
    }
}
