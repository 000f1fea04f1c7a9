//! The fits behind the gain table: Euler-Eytelwein (one mu, one mu per cord), the thesis's
//! Table 3 (published, not fitted), the extended mixed model (the named causes, its cord
//! effects shrunk so that fixed values + their effective degrees of freedom stay within the
//! budget), and every model's leave-one-cord-out predictions.

use super::{models, thesis};
use crate::fit::par::par_map;
use crate::fit::predict::evaluate;
use crate::fit::solve::{
    fit_fixed, fit_fixed_with, fit_mixed, fit_mixed_from, loco, loco_over, Budget, Fit, Loco,
    MixedOptions,
};
use crate::fit::stats::mean;
use crate::fit::Observations;
use std::time::Instant;

/// The parameter budget of the extended model, counted strictly: fixed values + the effective
/// degrees of freedom of the cord effects.
pub const STRICT_BUDGET: f64 = 12.0;

/// Work units a one-mu fit of a family (the per-cord baseline, the baseline's
/// leave-one-cord-out refits) may spend per row: ~20 evaluations with their Jacobians, where
/// the thesis's need ~1.
pub const ONE_MU_UNITS_PER_ROW: u64 = 60;
/// Work units a leave-one-cord-out refit of the extended model may spend per training row:
/// 2.6 times what the thesis's ten refits use (~97 a row, warm-started from the in-sample
/// fit). With at most 12 folds ([`crate::fit::solve::loco::MAX_FOLDS`]) the refits of a
/// 1,000-row data set stay within 3 M units (~1.3 s on two cores) whatever they meet.
pub const LOCO_UNITS_PER_ROW: u64 = 250;

/// Per-row predictions of every model (N), NaN where a model has no prediction.
#[derive(Clone, Debug, Default)]
pub struct Predictions {
    /// Euler-Eytelwein, one global mu.
    pub baseline: Vec<f64>,
    /// Euler-Eytelwein, one mu per cord.
    pub baseline_per_cord: Vec<f64>,
    /// Thesis Table 3, amp(T1)·T1 per angle.
    pub thesis: Vec<f64>,
    /// Extended model with the cord effects (in-sample).
    pub extended: Vec<f64>,
    /// Extended model, population values (cord effect 0).
    pub extended_population: Vec<f64>,
    /// Baseline, leave-one-cord-out.
    pub baseline_loco: Vec<f64>,
    /// Baseline per cord, leave-one-cord-out (mean log-mu of the other cords).
    pub baseline_per_cord_loco: Vec<f64>,
    /// Extended, leave-one-cord-out (population values of a fit on the other cords).
    pub extended_loco: Vec<f64>,
    /// The population-averaged model (the named causes, one mu, least squares in T2): the
    /// smallest and the largest wrap left out in turn (a fit on the other wraps): what
    /// extrapolating in wrap costs. NaN on the other wraps, and everywhere with fewer than
    /// three wraps.
    pub extended_edge_wrap: Vec<f64>,
    /// The population-averaged model, in-sample.
    pub population: Vec<f64>,
    /// Load memory H of the extended model at each window centre, N s.
    pub extended_load_memory_ns: Vec<f64>,
}

/// Every model fitted, with its in-sample and leave-one-cord-out predictions.
#[derive(Clone, Debug)]
pub struct Fits {
    /// Euler-Eytelwein with one mu.
    pub baseline: Fit,
    /// Euler-Eytelwein mu of each cord.
    pub cord_mu: Vec<f64>,
    /// The extended mixed model, its cord effects shrunk to [`STRICT_BUDGET`] if they would
    /// exceed it.
    pub extended: Fit,
    /// Baseline, leave-one-cord-out.
    pub baseline_loco: Loco,
    /// Extended, leave-one-cord-out.
    pub extended_loco: Loco,
    /// The population-averaged model with the named causes (what a new cord is predicted
    /// with, and `capstan predict` uses).
    pub population: Fit,
    /// Its refits without each cord (the same causes): the cord jackknife of its values.
    pub population_loco: Loco,
    /// RMSE of T2 of the per-cord baseline on a new cord, N.
    pub per_cord_loco_rmse: f64,
    /// Table 3 covers every wrap of the data.
    pub thesis_ok: bool,
    /// Per-row predictions.
    pub pred: Predictions,
    /// Wall time of the in-sample fits, s.
    pub fits_s: f64,
    /// Wall time of the leave-one-cord-out refits, s.
    pub loco_s: f64,
    /// Fits that did not converge, in words (the analysis went on without them, or, for the
    /// in-sample fits, with their last iterate).
    pub notes: Vec<String>,
}

/// Fit every model of the gain table to `obs`; `ext_spec` is the extended model
/// ([`models::extended`]).
pub fn fit_all(
    obs: &Observations,
    (ext_spec, pop_spec): (&crate::fit::ModelSpec, &crate::fit::ModelSpec),
    threads: usize,
) -> Fits {
    let all = obs.all_runs();
    let t0 = Instant::now();
    let base_spec = models::baseline();
    let baseline = fit_fixed(&base_spec, obs, &all, None);
    let per_cord_fits = per_cord(obs, threads);
    let mut per_cord_pred = vec![f64::NAN; obs.len()];
    for f in &per_cord_fits {
        for i in obs.rows_of(&f.runs) {
            per_cord_pred[i] = f.t2_n[i];
        }
    }
    let cord_mu: Vec<f64> = per_cord_fits.iter().map(|f| f.model(None).law.mu).collect();
    let thesis_pred = thesis_predictions(obs);
    let thesis_ok = thesis_pred.iter().all(|p| p.is_finite());
    // The extended model (mixed: per-cord random log-mu), within the budget.
    let extended = fit_mixed(ext_spec, obs, &all, None, extended_budget());
    let ext_pop = extended.predict(obs, &all, false);
    let ext_eval = evaluate(
        &extended.spec,
        &extended.theta,
        &extended.u,
        obs,
        &all,
        false,
    );
    let population = population_fit(obs, pop_spec, &extended.theta, &all);
    let fits_s = t0.elapsed().as_secs_f64();

    // Leave one cord out.
    let t1 = Instant::now();
    let baseline_loco = loco(obs, threads, |train| {
        let rows = obs.rows_of(train).len() as u64;
        let budget = Budget::for_fit_within(rows as usize, 1, ONE_MU_UNITS_PER_ROW * rows);
        fit_fixed_with(&base_spec, obs, train, None, &budget)
    });
    let extended_loco = extended_refits(obs, ext_spec, &extended, threads, None);
    let population_loco = population_refits(obs, pop_spec, &population, threads, None);
    let edge_wrap = edge_wrap_folds(obs);
    let extended_edge_wrap = if edge_wrap.is_empty() {
        vec![f64::NAN; obs.len()]
    } else {
        population_refits(obs, pop_spec, &population, threads, Some(&edge_wrap)).t2_n
    };
    let per_cord_loco = per_cord_on_new_cords(obs, &cord_mu);
    let per_cord_loco_rmse = obs.rmse_t2(&per_cord_loco);
    let loco_s = t1.elapsed().as_secs_f64();

    let notes = notes(
        obs,
        &baseline,
        &extended,
        &per_cord_fits,
        [&baseline_loco, &extended_loco],
    );
    let pred = Predictions {
        baseline: baseline.t2_n.clone(),
        baseline_per_cord: per_cord_pred,
        thesis: thesis_pred,
        extended: extended.t2_n.clone(),
        extended_population: ext_pop,
        baseline_loco: baseline_loco.t2_n.clone(),
        baseline_per_cord_loco: per_cord_loco,
        extended_loco: extended_loco.t2_n.clone(),
        extended_edge_wrap,
        population: population.t2_n.clone(),
        extended_load_memory_ns: ext_eval.load_memory_ns,
    };
    Fits {
        baseline,
        cord_mu,
        extended,
        baseline_loco,
        extended_loco,
        population,
        population_loco,
        per_cord_loco_rmse,
        thesis_ok,
        pred,
        fits_s,
        loco_s,
        notes,
    }
}

/// Euler-Eytelwein fitted to each cord alone (one mu per cord), each within its budget.
fn per_cord(obs: &Observations, threads: usize) -> Vec<Fit> {
    let base_spec = models::baseline();
    let groups: Vec<usize> = (0..obs.groups.len()).collect();
    par_map(&groups, threads, |&g| {
        let runs = obs.runs_of_group(g);
        let rows = obs.rows_of(&runs).len();
        let budget = Budget::for_fit_within(rows, 1, ONE_MU_UNITS_PER_ROW * rows as u64);
        fit_fixed_with(&base_spec, obs, &runs, None, &budget)
    })
}

/// The thesis's Table 3 at every row (amp(T1)·T1 at its angle), NaN where it has none.
fn thesis_predictions(obs: &Observations) -> Vec<f64> {
    obs.rows
        .iter()
        .map(|r| {
            thesis::thesis_amp(r.op.wrap_rad.to_degrees().round(), r.t1_n)
                .map_or(f64::NAN, |a| a * r.t1_n)
        })
        .collect()
}

/// The extended model's options: its cord effects shrunk to [`STRICT_BUDGET`].
fn extended_budget() -> MixedOptions {
    MixedOptions {
        edf_cap: Some(STRICT_BUDGET),
        ..MixedOptions::default()
    }
}

/// The extended model refitted without each cord, warm-started from the in-sample fit.
/// Refits from an in-sample fit that did not converge would not either: they are not run,
/// and no cord gets a held-out prediction of the extended model.
fn extended_refits(
    obs: &Observations,
    ext_spec: &crate::fit::ModelSpec,
    extended: &Fit,
    threads: usize,
    folds: Option<&[Vec<usize>]>,
) -> Loco {
    if !extended.converged {
        return Loco::skipped(obs);
    }
    let (th, u0) = (extended.theta.clone(), extended.u.clone());
    let l0 = extended.lambda.unwrap_or(200.0);
    let budget = extended_budget();
    let refit = |train: &[usize]| {
        let opts = MixedOptions {
            lambda0: l0,
            max_units: Some(LOCO_UNITS_PER_ROW * obs.rows_of(train).len() as u64),
            ..budget
        };
        fit_mixed_from(ext_spec, obs, train, th.clone(), u0.clone(), opts)
    };
    match folds {
        None => loco(obs, threads, refit),
        Some(f) => loco_over(obs, threads, f, refit),
    }
}

/// The population-averaged model fitted to `runs`, from the mixed fit's values `theta0` (the
/// same free parameters) when they are finite.
fn population_fit(
    obs: &Observations,
    spec: &crate::fit::ModelSpec,
    theta0: &[f64],
    runs: &[usize],
) -> Fit {
    let start =
        (theta0.len() == spec.free.len() && theta0.iter().all(|t| t.is_finite())).then_some(theta0);
    let rows = obs.rows_of(runs).len();
    let budget = Budget::for_fit_within(rows, spec.free.len(), LOCO_UNITS_PER_ROW * rows as u64);
    fit_fixed_with(spec, obs, runs, start, &budget)
}

/// The population-averaged model refitted without each cord (or each fold of `folds`),
/// warm-started from the fit on all the data; none when that did not converge.
fn population_refits(
    obs: &Observations,
    spec: &crate::fit::ModelSpec,
    population: &Fit,
    threads: usize,
    folds: Option<&[Vec<usize>]>,
) -> Loco {
    if !population.converged {
        return Loco::skipped(obs);
    }
    let refit = |train: &[usize]| population_fit(obs, spec, &population.theta, train);
    match folds {
        None => loco(obs, threads, refit),
        Some(f) => loco_over(obs, threads, f, refit),
    }
}

/// Two folds: the cords of the smallest wrap, and those of the largest (none with fewer than
/// three wraps: the rest would not span a wrap to extrapolate from).
fn edge_wrap_folds(obs: &Observations) -> Vec<Vec<usize>> {
    let wraps = crate::fit::stats::distinct(obs.groups.iter().map(|g| g.wrap_deg));
    let (Some(lo), Some(hi)) = (wraps.first(), wraps.last()) else {
        return Vec::new();
    };
    if wraps.len() < 3 {
        return Vec::new();
    }
    let of = |w: f64| -> Vec<usize> {
        (0..obs.groups.len())
            .filter(|&g| obs.groups[g].wrap_deg == w)
            .collect()
    };
    vec![of(*lo), of(*hi)]
}

/// The per-cord baseline on a new cord: each cord predicted by the mean log-mu of the others.
fn per_cord_on_new_cords(obs: &Observations, cord_mu: &[f64]) -> Vec<f64> {
    let mut per_cord_loco = vec![f64::NAN; obs.len()];
    for g in 0..obs.groups.len() {
        let others: Vec<f64> = (0..obs.groups.len())
            .filter(|&k| k != g)
            .map(|k| cord_mu[k].ln())
            .collect();
        let m = capstan_physics::Model::euler_eytelwein(mean(&others).exp());
        for i in obs.rows_of_group(g) {
            let r = &obs.rows[i];
            per_cord_loco[i] = m.predict_t2_n(r.t1_n, &r.op);
        }
    }
    per_cord_loco
}

/// The fits that did not converge, in words, one line per family.
fn notes(
    obs: &Observations,
    baseline: &Fit,
    extended: &Fit,
    per_cord: &[Fit],
    locos: [&Loco; 2],
) -> Vec<String> {
    let mut notes = Vec::new();
    for (what, f) in [
        ("Euler-Eytelwein (one mu)", baseline),
        ("the extended model", extended),
    ] {
        if let Some(why) = &f.stopped {
            notes.push(format!("{what}: {why}; its last iterate is reported"));
        }
    }
    let cords = |list: Vec<(usize, &String)>| -> Option<String> {
        let (_, why) = list.first()?;
        let why = why.trim_start_matches("did not converge: ");
        let names: Vec<&str> = list
            .iter()
            .take(3)
            .map(|(g, _)| obs.groups[*g].label.as_str())
            .collect();
        let more = if list.len() > 3 { ", ..." } else { "" };
        Some(format!(
            "{} of {} cords ({}{more}; the first: {why})",
            list.len(),
            obs.groups.len(),
            names.join(", ")
        ))
    };
    let stopped: Vec<(usize, &String)> = per_cord
        .iter()
        .enumerate()
        .filter_map(|(g, f)| f.stopped.as_ref().map(|w| (g, w)))
        .collect();
    if let Some(s) = cords(stopped) {
        notes.push(format!(
            "Euler-Eytelwein with one mu per cord: the fit did not converge on {s}"
        ));
    }
    if obs.groups.len() < 2 {
        // Nothing to refit without the only cord: not a failure to converge.
        notes.push(
            "leave one cord out needs two cords or more: with one there is no held-out prediction"
                .to_string(),
        );
        return notes;
    }
    // The held-out predictions of the extended model are the whole procedure's (population
    // fits, `heldout`); its mixed refits only give its values' cord-jackknife SE.
    for (what, l, consequence) in [
        (
            "Euler-Eytelwein",
            locos[0],
            "those cords have no held-out prediction",
        ),
        (
            "the extended (mixed) model",
            locos[1],
            "its values' cord-jackknife SE leaves those folds out (the held-out predictions are the whole procedure's, not these refits)",
        ),
    ] {
        let list: Vec<(usize, &String)> = l.did_not_converge.iter().map(|(g, w)| (*g, w)).collect();
        if let Some(s) = cords(list) {
            notes.push(format!(
                "{what}, leave one cord out: the refit did not converge without {s}: {consequence}"
            ));
        }
    }
    notes
}
