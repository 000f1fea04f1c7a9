//! The extended fit in detail: values with Gauss-Newton and jackknife (leave-one-cord-out)
//! standard errors, the cord offsets and their variance, the steady-state heating effect, and
//! the strict-budget variant.

use super::fits::Fits;
use super::metrics::named;
use crate::fit::stats::jackknife_se;
use crate::fit::Observations;
use serde::Serialize;

/// The extended fit in detail.
#[derive(Clone, Debug, Serialize)]
pub struct ExtendedDetail {
    /// Fitted population values.
    pub values: Vec<(String, f64)>,
    /// Gauss-Newton standard errors of the values.
    pub standard_errors: Vec<(String, f64)>,
    /// Jackknife standard errors over the leave-one-cord-out refits.
    pub jackknife_se: Vec<(String, f64)>,
    /// Per-cord log-mu offsets (BLUPs).
    pub cord_log_mu: Vec<(String, f64)>,
    /// SD of the cord log-mu offsets.
    pub sigma_u: f64,
    /// λ = σ²/σ_u².
    pub lambda: f64,
    /// Effective dof of the cord offsets.
    pub edf_random: f64,
    /// RMSE of T2 with population values only (cord offsets 0), N.
    pub rmse_population_t2_n: f64,
    /// Steady-state mu factor at a friction load T2 − T1 = 40 N: exp(−h·τ·40).
    pub mu_factor_at_40n_load: f64,
    /// h·τ, 1/N: steady-state ln-mu loss per newton of friction load.
    pub heat_per_n_steady: f64,
    /// How the extended fit stopped.
    pub termination: String,
    /// The strict-count variant: cord effects shrunk so that fixed + edf ≤ 12.
    pub strict12: StrictVariant,
}

/// The extended model with its cord effects shrunk to a strict budget.
#[derive(Clone, Debug, Serialize)]
pub struct StrictVariant {
    /// Fixed + edf of the cord effects.
    pub n_params_strict: f64,
    /// In-sample RMSE of T2, N.
    pub rmse_t2_n: f64,
    /// λ used.
    pub lambda: f64,
}

/// Jackknife SE of h·τ over the folds (the product is what the data fix when τ is short).
fn heat_product_jackknife(f: &Fits) -> f64 {
    let prods: Vec<f64> = f
        .extended_loco
        .fold_values
        .iter()
        .map(|fold| {
            let get = |k: &str| fold.iter().find(|x| x.0 == k).map_or(f64::NAN, |x| x.1);
            get("heat_per_ns") * get("heat_tau_s")
        })
        .collect();
    jackknife_se(&prods)
}

/// The extended fit of `f` in detail.
pub fn detail(obs: &Observations, f: &Fits) -> ExtendedDetail {
    let ext = &f.extended;
    let se = ext.standard_errors(obs);
    let m_pop = ext.model(None);
    let h_tau = m_pop.law.heat_per_ns * m_pop.law.heat_tau_s;
    let mut jackknife = named(f.extended_loco.jackknife_se());
    jackknife.push(("heat_per_ns*heat_tau_s".into(), heat_product_jackknife(f)));
    ExtendedDetail {
        values: named(ext.values()),
        standard_errors: ext
            .spec
            .free
            .iter()
            .zip(se)
            .map(|(p, s)| (p.param.name().to_string(), s))
            .collect(),
        jackknife_se: jackknife,
        cord_log_mu: obs
            .groups
            .iter()
            .zip(&ext.u)
            .map(|(g, u)| (g.label.clone(), *u))
            .collect(),
        sigma_u: ext.sigma_u.unwrap_or(f64::NAN),
        lambda: ext.lambda.unwrap_or(f64::NAN),
        edf_random: ext.edf_random,
        rmse_population_t2_n: obs.rmse_t2(&f.pred.extended_population),
        mu_factor_at_40n_load: (-h_tau * 40.0).exp(),
        heat_per_n_steady: h_tau,
        termination: ext.termination.clone(),
        strict12: StrictVariant {
            n_params_strict: f.strict.n_params_edf(),
            rmse_t2_n: f.strict.rmse(),
            lambda: f.strict.lambda.unwrap_or(f64::NAN),
        },
    }
}
