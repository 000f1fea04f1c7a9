//! The extended fit in detail: its values with cluster-robust uncertainties (the cord
//! jackknife over the leave-one-cord-out refits, and the evidence engine's run-clustered SEs of
//! the named causes), the cord offsets and their variance, and the parameter count.

use super::fits::Fits;
use super::metrics::named;
use crate::evidence::Assessment;
use crate::fit::Observations;
use serde::Serialize;

/// One fitted value with its uncertainties.
#[derive(Clone, Debug, Serialize)]
pub struct Value {
    /// Name (`capstan_physics` parameter).
    pub name: String,
    /// Population value.
    pub value: f64,
    /// Cord-jackknife SE over the leave-one-cord-out refits (cords as clusters); NaN when not
    /// identified.
    pub jackknife_se: f64,
    /// The evidence engine's SE of the cause this value belongs to (runs as clusters, every
    /// run's own mu); NaN for the population mu.
    pub run_clustered_se: f64,
    /// Why an SE is NaN (empty otherwise).
    pub note: String,
}

/// The extended fit in detail.
#[derive(Clone, Debug, Serialize)]
pub struct ExtendedDetail {
    /// Fitted values with their uncertainties.
    pub values: Vec<Value>,
    /// Per-cord log-mu offsets (BLUPs).
    pub cord_log_mu: Vec<(String, f64)>,
    /// SD of the cord log-mu offsets.
    pub sigma_u: f64,
    /// λ = σ²/σ_u².
    pub lambda: f64,
    /// Fixed values.
    pub n_fixed: usize,
    /// Effective degrees of freedom of the cord offsets.
    pub edf_random: f64,
    /// The count: fixed values + edf of the cord offsets.
    pub effective_dof: f64,
    /// RMSE of T2 with population values only (cord offsets 0), N.
    pub rmse_population_t2_n: f64,
    /// How the extended fit stopped.
    pub termination: String,
}

/// The extended fit of `f` in detail.
pub fn detail(obs: &Observations, f: &Fits, a: &Assessment) -> ExtendedDetail {
    let ext = &f.extended;
    let jk = f.extended_loco.jackknife_se();
    let values = named(ext.values())
        .into_iter()
        .map(|(name, value)| {
            let j = jk.iter().find(|x| x.0 == name).map_or(f64::NAN, |x| x.1);
            let cause = a.selected_evidence().into_iter().find(|e| {
                crate::fit::Param::from_effect(e.kind).map(|p| p.name()) == Some(name.as_str())
            });
            // The catalogue value per model scalar (heating's value is h·τ; the model's is h).
            let run_se = cause.map_or(f64::NAN, |e| {
                e.parameter_se / e.kind.entry().population.value_per_scalar
            });
            let note = if !(j.is_finite() && j > 0.0) {
                "not identified: the cord-jackknife variance is zero or undefined".to_string()
            } else {
                String::new()
            };
            Value {
                name,
                value,
                jackknife_se: if j.is_finite() && j > 0.0 {
                    j
                } else {
                    f64::NAN
                },
                run_clustered_se: run_se,
                note,
            }
        })
        .collect();
    ExtendedDetail {
        values,
        cord_log_mu: obs
            .groups
            .iter()
            .zip(&ext.u)
            .map(|(g, u)| (g.label.clone(), *u))
            .collect(),
        sigma_u: ext.sigma_u.unwrap_or(f64::NAN),
        lambda: ext.lambda.unwrap_or(f64::NAN),
        n_fixed: ext.n_fixed(),
        edf_random: ext.edf_random,
        effective_dof: ext.n_params_edf(),
        rmse_population_t2_n: obs.rmse_t2(&f.pred.extended_population),
        termination: ext.termination.clone(),
    }
}
