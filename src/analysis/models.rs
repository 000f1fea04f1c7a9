//! The model specs of the analysis: the baseline, the extended model and its variants.

use crate::fit::{ModelSpec, Param, Transform};
use capstan_friction::Model;

/// Euler-Eytelwein with one free mu.
pub fn baseline() -> ModelSpec {
    ModelSpec::new("baseline", Model::euler_eytelwein(0.115)).free(Param::Mu)
}

/// Bounds of the load-memory time constant, s (the thesis protocol cannot resolve memories
/// much shorter than the 2 s settling before each window, nor longer than a run).
pub const TAU_BOUNDS_S: (f64, f64) = (0.1, 300.0);

/// The extended model: Euler-Eytelwein with
/// * a T1-path loss e1 (`sensors.t1_offset_n`),
/// * mu0 with a wrap slope of ln mu (`law.mu_log_slope_per_rad`, anchored at 540°),
/// * contact heating: mu falls by exp(−h·H), H the friction-load memory (`law.heat_per_ns`,
///   `law.heat_tau_s`), carried along each run with the protocol's step timing,
/// * per-cord random log-mu offsets (mixed model).
pub fn extended() -> ModelSpec {
    let mut base = Model::euler_eytelwein(0.145);
    base.law.heat_tau_s = 1.0;
    base.law.heat_per_ns = 0.009;
    base.law.mu_log_slope_per_rad = 0.015;
    base.sensors.t1_offset_n = 0.2;
    ModelSpec::new("extended", base)
        .free(Param::Mu)
        .free(Param::HeatPerNs)
        .free_with(
            Param::HeatTauS,
            Transform::Logistic {
                lo: TAU_BOUNDS_S.0,
                hi: TAU_BOUNDS_S.1,
            },
        )
        .free(Param::T1Offset)
        .free(Param::MuLogSlopePerRad)
        .random_effect_on(Param::Mu)
}

/// Power law dT/dθ = k·Tⁿ with mu and n free.
pub fn power_law() -> ModelSpec {
    ModelSpec::new("power_law", Model::euler_eytelwein(0.12))
        .with_value(Param::TensionExponent, 0.9)
        .free(Param::Mu)
        .free(Param::TensionExponent)
}
