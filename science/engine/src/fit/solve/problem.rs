//! A [`ModelSpec`] on a set of runs as a `levenberg_marquardt::LeastSquaresProblem`:
//! residuals are predicted − measured T2 (N) on the training rows, plus √λ·u_g for each group's
//! random effect (penalised least squares: Σr² + λΣu²).

use super::budget::Budget;
use crate::fit::obs::Observations;
use crate::fit::params::ModelSpec;
use crate::fit::predict::{evaluate, Evaluation};
use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::{storage::Owned, DMatrix, DVector, Dyn};

/// A spec on a training set, as the solver sees it.
pub struct FitProblem<'a> {
    spec: &'a ModelSpec,
    obs: &'a Observations,
    runs: Vec<usize>,
    /// Training rows.
    pub(super) rows: Vec<usize>,
    /// Groups with a random effect (those with training rows), in parameter order.
    pub(super) re_groups: Vec<usize>,
    lambda: f64,
    /// Fixed-effect θ.
    pub(super) theta: Vec<f64>,
    /// Group offsets, indexed by group.
    pub(super) u: Vec<f64>,
    /// Predictions at the current parameters.
    pub(super) eval: Evaluation,
    /// What the fit may still spend.
    budget: &'a Budget,
}

impl<'a> FitProblem<'a> {
    /// A problem on `runs`. With a random effect in `spec` and `lambda` given, the group
    /// effects are parameters (penalised by `lambda`); otherwise they stay at zero. The solver
    /// stops (the Jacobian is refused) once `budget` is spent.
    pub fn new(
        spec: &'a ModelSpec,
        obs: &'a Observations,
        runs: &[usize],
        lambda: Option<f64>,
        theta: &[f64],
        u: &[f64],
        budget: &'a Budget,
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
            budget,
        };
        p.eval = evaluate(spec, &p.theta, &p.u, obs, &p.runs, false);
        budget.charge(p.rows.len() as u64);
        p
    }

    /// The work a Jacobian costs here.
    fn jacobian_cost(&self) -> u64 {
        let free = self.theta.len() * if self.spec.tie.is_some() { 2 } else { 1 };
        let m = self.rows.len() + self.re_groups.len();
        Budget::jacobian_cost(self.rows.len(), free, m, self.n_params())
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
        self.budget.charge(self.jacobian_cost());
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
        self.budget.charge(self.rows.len() as u64);
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
        // The solver asks for a Jacobian at the last accepted parameters: refusing it there
        // ends the fit at its best point so far.
        if self.budget.spent() {
            return None;
        }
        self.budget.charge(self.jacobian_cost());
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

/// The Levenberg-Marquardt solver every fit uses (tolerances and patience).
pub(super) fn solver() -> LevenbergMarquardt<f64> {
    LevenbergMarquardt::new()
        .with_ftol(1e-9)
        .with_xtol(1e-8)
        .with_gtol(1e-10)
        .with_patience(200)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::params::Param;
    use capstan_data::thesis_dataset;
    use capstan_physics::Model;
    use levenberg_marquardt::differentiate_numerically;

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
        let budget = Budget::new(u64::MAX);
        let mut p = FitProblem::new(&spec, &obs, &runs, Some(300.0), &spec.start(), &u, &budget);
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
