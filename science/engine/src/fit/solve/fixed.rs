//! Fixed-effects fits (random effects held at zero).

use super::budget::Budget;
use super::problem::{solver, FitProblem};
use super::result::{finish, Fit};
use crate::fit::obs::Observations;
use crate::fit::params::ModelSpec;

/// Fixed effects only, from `start` (θ) or the spec's base values, within the budget its size
/// gives ([`Budget::for_fit`]).
pub fn fit_fixed(
    spec: &ModelSpec,
    obs: &Observations,
    runs: &[usize],
    start: Option<&[f64]>,
) -> Fit {
    let rows = runs.iter().map(|&r| obs.runs[r].len()).sum();
    fit_fixed_with(
        spec,
        obs,
        runs,
        start,
        &Budget::for_fit(rows, spec.free.len()),
    )
}

/// [`fit_fixed`] within `budget`.
pub fn fit_fixed_with(
    spec: &ModelSpec,
    obs: &Observations,
    runs: &[usize],
    start: Option<&[f64]>,
    budget: &Budget,
) -> Fit {
    let theta = start.map_or_else(|| spec.start(), <[f64]>::to_vec);
    let u = vec![0.0; obs.groups.len()];
    let problem = FitProblem::new(spec, obs, runs, None, &theta, &u, budget);
    let (p, report) = solver().minimize(problem);
    finish(spec, runs, p, None, report, budget)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::params::Param;
    use capstan_data::thesis_dataset;
    use capstan_physics::Model;

    #[test]
    fn euler_eytelwein_global_mu_matches_the_reference() {
        let obs = Observations::from_dataset(&thesis_dataset());
        let spec = ModelSpec::new("ee", Model::euler_eytelwein(0.115)).free(Param::Mu);
        let fit = fit_fixed(&spec, &obs, &obs.all_runs(), None);
        let mu = fit.model(None).law.mu;
        assert!((mu - 0.1162).abs() < 5e-5, "{mu}");
        assert!((fit.rmse() - 1.718).abs() < 5e-4, "{}", fit.rmse());
    }
}
