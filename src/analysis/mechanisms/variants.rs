//! The nested fits behind the verdicts: variants of the extended model (mixed, compared at its
//! variance ratio λ so that they differ only in their fixed terms), the profile over the
//! load-memory time τ, and fixed-effects variants of Euler-Eytelwein and the power law.

use super::{TauPoint, Variant};
use crate::analysis::metrics::rmse_ln_amp;
use crate::analysis::models;
use crate::fit::par::par_map;
use crate::fit::solve::{fit_fixed_multistart, fit_penalised, Fit};
use crate::fit::{ModelSpec, Observations, Param, Tie, Transform};

/// The memory times of the τ profile, s.
pub const TAUS_S: [f64; 6] = [0.25, 1.0, 3.0, 7.0, 20.0, 60.0];

/// Every nested fit.
pub struct Fitted {
    /// Mixed and fixed variants with ΔAIC/ΔBIC (mixed first, in job order).
    pub variants: Vec<Variant>,
    /// Profile over τ.
    pub tau_profile: Vec<TauPoint>,
    /// The mixed variants' fits, by variant name.
    pub mixed: Vec<(&'static str, Fit)>,
    /// The fixed-effects variants' fits, by variant name.
    pub fixed: Vec<(&'static str, Fit)>,
    /// The data's capstan diameters, ascending, mm.
    pub diameters: Vec<f64>,
    /// Two diameters, the smaller the reference 12.7 mm (Howell's test applies).
    pub two_diameters: bool,
}

/// The population value of `p` in `f`.
pub fn value(f: &Fit, p: Param) -> f64 {
    p.get(&f.model(None))
}

/// `fit` as a variant of `reference` (mixed: parameter count fixed + 1 variance component).
pub fn variant_of(
    name: &str,
    desc: &str,
    reference: &Fit,
    fit: &Fit,
    obs: &Observations,
    mixed: bool,
) -> Variant {
    let pred = &fit.t2_n;
    let p = if mixed {
        fit.n_params_mixed()
    } else {
        fit.n_fixed()
    };
    let p_ref = if mixed {
        reference.n_params_mixed()
    } else {
        reference.n_fixed()
    };
    let (aic, bic) = fit.information_criteria(p as f64);
    let (aic_r, bic_r) = reference.information_criteria(p_ref as f64);
    Variant {
        name: name.into(),
        description: desc.into(),
        reference: reference.spec.name.clone(),
        n_fixed: fit.n_fixed(),
        n_params: p,
        rmse_t2_n: obs.rmse_t2(pred),
        rmse_ln_amp: rmse_ln_amp(obs, pred),
        aic,
        bic,
        delta_aic: aic - aic_r,
        delta_bic: bic - bic_r,
        values: fit
            .values()
            .into_iter()
            .map(|(k, v)| (k.to_string(), v))
            .collect(),
    }
}

/// The mixed variants of the extended model `a` (started from its fitted values).
fn mixed_jobs(
    a: &ModelSpec,
    more_than_one_diameter: bool,
) -> Vec<(&'static str, &'static str, ModelSpec)> {
    let mut jobs = vec![
        (
            "no_heating",
            "extended without contact heating (h = 0)",
            a.clone()
                .fix(Param::HeatPerNs, 0.0)
                .fix(Param::HeatTauS, 1.0)
                .named("no_heating"),
        ),
        (
            "no_t1_loss",
            "extended without the T1-path loss (e1 = 0)",
            a.clone().fix(Param::T1Offset, 0.0).named("no_t1_loss"),
        ),
        (
            "no_wrap_slope",
            "extended without the wrap slope of ln mu",
            a.clone()
                .fix(Param::MuLogSlopePerRad, 0.0)
                .named("no_wrap_slope"),
        ),
        (
            "time_drift_instead_of_heating",
            "heating replaced by a drift of mu with time since the trigger",
            a.clone()
                .fix(Param::HeatPerNs, 0.0)
                .fix(Param::HeatTauS, 1.0)
                .free(Param::MuChangePer100s)
                .named("time_drift"),
        ),
        (
            "plus_power_law",
            "extended + tension exponent n (dT/dθ = k·Tⁿ)",
            a.clone()
                .with_value(Param::TensionExponent, 0.98)
                .free(Param::TensionExponent)
                .named("plus_n"),
        ),
        (
            "plus_bending",
            "extended + bending stiffness B",
            a.clone()
                .with_value(Param::BendingB, 1e-6)
                .free(Param::BendingB)
                .named("plus_b"),
        ),
        (
            "plus_t2_offset",
            "extended + T2 zero offset e2",
            a.clone().free(Param::T2Offset).named("plus_e2"),
        ),
        (
            "plus_gain",
            "extended + T2 gain g",
            a.clone()
                .free_with(Param::T2Gain, Transform::Log)
                .named("plus_g"),
        ),
        (
            "plus_wear",
            "extended + change of mu per run (wear)",
            a.clone().free(Param::MuChangePerRun).named("plus_wear"),
        ),
    ];
    if more_than_one_diameter {
        jobs.push((
            "plus_diameter",
            "extended + change of mu per mm of capstan diameter",
            a.clone().free(Param::MuChangePerMm).named("plus_dmu"),
        ));
    }
    jobs
}

/// Fixed-effects variants: the power law, Euler-Eytelwein + bending, and with two diameters
/// Howell's law in T1/R and the power law with a free diameter factor.
fn fixed_jobs(
    diameters: &[f64],
    two_diameters: bool,
) -> Vec<(&'static str, &'static str, ModelSpec)> {
    let pl = models::power_law();
    let mut jobs = vec![
        (
            "power_law_fixed",
            "power law (mu, n), no cord effects",
            pl.clone().named("power_law"),
        ),
        (
            "bending_fixed",
            "Euler-Eytelwein + bending stiffness B, no cord effects",
            models::baseline()
                .with_value(Param::BendingB, 1e-6)
                .free(Param::BendingB)
                .named("ee_b"),
        ),
    ];
    if two_diameters {
        jobs.push((
            "power_law_howell_fixed",
            "power law in line pressure T1/R (Howell: mu ∝ R^(1−n))",
            pl.clone()
                .with_tie(Tie::HowellDiameter {
                    other_mm: diameters[1],
                })
                .named("howell"),
        ));
        jobs.push((
            "power_law_plus_diameter_fixed",
            "power law + free diameter factor of mu",
            pl.clone().free(Param::MuChangePerMm).named("pl_dmu"),
        ));
    }
    jobs
}

/// Fit every variant of the extended model `ext` and of the fixed-effects `baseline`.
pub fn fit_all(obs: &Observations, baseline: &Fit, ext: &Fit, threads: usize) -> Fitted {
    let all = obs.all_runs();
    let a = ext.spec.clone().starting_from(ext.model(None));
    let h_tau = value(ext, Param::HeatPerNs) * value(ext, Param::HeatTauS);
    let diameters = obs.diameters();
    let two_diameters = diameters.len() == 2 && diameters[0] == capstan_friction::REF_DIAMETER_MM;

    // Mixed variants, then the τ profile (τ held, h started at the same steady-state effect).
    let mut jobs = mixed_jobs(&a, diameters.len() > 1);
    let n_variants = jobs.len();
    for &tau in &TAUS_S {
        let h0 = h_tau / tau.min(5.5);
        jobs.push((
            "tau_profile",
            "",
            a.clone()
                .with_value(Param::HeatPerNs, h0)
                .fix(Param::HeatTauS, tau)
                .named(format!("tau={tau}")),
        ));
    }
    let fits: Vec<Fit> = par_map(&jobs, threads, |(_, _, spec)| {
        // Nested comparisons at the extended model's variance ratio λ.
        fit_penalised(
            spec,
            obs,
            &all,
            ext.lambda.unwrap_or(200.0),
            &spec.start(),
            &ext.u,
        )
    });
    let mut variants = Vec::new();
    let mut mixed = Vec::new();
    let mut tau_profile = Vec::new();
    for (k, ((name, desc, _), fit)) in jobs.iter().zip(fits).enumerate() {
        if k >= n_variants {
            tau_profile.push(TauPoint {
                tau_s: value(&fit, Param::HeatTauS),
                rmse_t2_n: fit.rmse(),
                aic: fit
                    .information_criteria(fit.n_params_mixed() as f64 + 1.0)
                    .0,
                heat_per_ns: value(&fit, Param::HeatPerNs),
            });
            continue;
        }
        variants.push(variant_of(name, desc, ext, &fit, obs, true));
        mixed.push((*name, fit));
    }

    // Fixed-effects power law, Howell, bending.
    let fjobs = fixed_jobs(&diameters, two_diameters);
    let ffits: Vec<Fit> = par_map(&fjobs, threads, |(_, _, spec)| {
        fit_fixed_multistart(spec, obs, &all, &[spec.start()])
    });
    let mut fixed = Vec::new();
    for ((name, desc, _), fit) in fjobs.iter().zip(ffits) {
        variants.push(variant_of(name, desc, baseline, &fit, obs, false));
        fixed.push((*name, fit));
    }
    Fitted {
        variants,
        tau_profile,
        mixed,
        fixed,
        diameters,
        two_diameters,
    }
}
