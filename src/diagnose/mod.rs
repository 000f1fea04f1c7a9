//! `capstan diagnose`: which single catalogue effect (if any) makes a data set depart from
//! Euler-Eytelwein, and how large it is.
//!
//! # Statistics
//! Rows are not independent: every run of every cord has its own mu (cord-to-cord and
//! run-to-run scatter), and each run its own tare. The diagnosis works on the two levels of a
//! hierarchical model and never lets rows count as independent evidence about anything that
//! varies between runs or cords:
//!
//! * **Within runs** ([`within`]): every run gets its own mu (fixed run effects: the within
//!   estimator), and a candidate adds one shared parameter that changes the *shape* of T2
//!   against T1, time and wrap inside runs: `pressure_friction`, `bending_stiffness`,
//!   `t1_offset`, `t2_offset`, `thermal_drift`. Evidence: the likelihood ratio of the T2
//!   residuals, divided by an overdispersion factor ĉ (the cluster-robust / model-based
//!   variance ratio of the best candidate's parameter, runs as clusters: residuals within a run
//!   are correlated), ΔBIC = −LR/ĉ + ln n.
//! * **Between runs and cords** ([`between_test`]): the runs' mu from the within-run
//!   Euler-Eytelwein fit, regressed on the effect's covariate at the level where it varies.
//!   `diameter_dependence` (d − 12.7 mm), `speed_dependence` (V − 10 V) and `sensor_gain`
//!   (1/β: a gain g adds ln g/β to the apparent mu) vary between cords: the cord means of mu
//!   are regressed on it, so the error term is the cord-to-cord scatter (t with G − 2 df).
//!   `wear` (run − 1) varies within cords: the runs' mu with one intercept per cord, error
//!   term the run-to-run scatter (t with R − G − 1 df). The t statistic is put on the
//!   likelihood-ratio scale (the χ²₁ value of the same tail probability), ΔBIC = −χ² + ln N,
//!   N the number of cords or runs.
//!
//! The two levels are the two factors of one likelihood (the shape within runs given each
//! run's mu, and the runs' mu given the covariates). A candidate is supported when its ΔBIC is
//! below the threshold of its level ([`WITHIN_THRESHOLD`], [`BETWEEN_THRESHOLD`], calibrated on
//! generated `none` data sets so that false alarms stay under 5 %; see
//! `docs/README-diagnose.md`); the supported candidate with the lowest ΔBIC is the diagnosis,
//! else `none`. An effect whose column is absent, or whose covariate has a single level, is
//! listed as not testable and never chosen.

pub mod between;
pub mod cases;
mod diagnosis;
pub mod prep;
pub mod within;

pub use diagnosis::{
    Baseline, Candidate, Design, Diagnosis, Extended, Level, NotTestable, Options, Scatter,
    Thresholds,
};

use crate::data::Dataset;
use crate::fit::params::{ModelSpec, Param};
use crate::fit::solve::fit_fixed;
use crate::fit::stats;
use between::between_test;
use capstan_friction::{EffectKind, Model};
use prep::Prepared;
use std::collections::BTreeMap;
use std::time::Instant;
use within::ThetaMap;

/// Decision threshold for effects seen in the shape inside runs: reported when ΔBIC < −25.
pub const WITHIN_THRESHOLD: f64 = 25.0;
/// Decision threshold for effects seen between runs or cords: reported when ΔBIC < −8.
pub const BETWEEN_THRESHOLD: f64 = 8.0;
/// Diagnose with the default options (the function behind `capstan diagnose`).
pub fn diagnose(d: &Dataset) -> Diagnosis {
    diagnose_with(d, &Options::default())
}

const WITHIN: [EffectKind; 5] = [
    EffectKind::PressureFriction,
    EffectKind::BendingStiffness,
    EffectKind::T1Offset,
    EffectKind::T2Offset,
    EffectKind::ThermalDrift,
];

/// Why `kind` cannot be tested on `p`, if it cannot.
fn untestable(kind: EffectKind, p: &Prepared) -> Option<String> {
    if let Some(col) = kind.required_column() {
        if !p.columns.has(col) {
            return Some(format!("no `{col}` column"));
        }
    }
    match kind {
        EffectKind::DiameterDependence if p.diameters().len() < 2 => {
            Some("a single capstan diameter".into())
        }
        EffectKind::SpeedDependence if p.voltages().len() < 2 => {
            Some("a single drive voltage".into())
        }
        EffectKind::SensorGain if p.wraps().len() < 2 => {
            Some("a single wrap (a gain error only shows across wraps)".into())
        }
        EffectKind::Wear if p.max_runs_per_cord() < 2 => Some("one run per cord".into()),
        EffectKind::ThermalDrift if p.max_time_spread_s() <= 0.0 => {
            Some("no time spread within runs".into())
        }
        _ => None,
    }
}
/// The χ²₁ value with the same tail probability as a t statistic with `df` degrees of freedom
/// (small-sample tests on the likelihood-ratio scale of BIC).
fn chi2_equivalent(t: f64, df: f64) -> f64 {
    if !t.is_finite() {
        return 0.0;
    }
    let p = stats::t_p_two_sided(t, df.max(1.0));
    if p.is_nan() || p <= 1e-280 {
        // Far in the tail the distinction no longer matters.
        return t * t;
    }
    // Solve erfc(z/√2) = p for z by bisection; χ² = z².
    let (mut lo, mut hi) = (0.0f64, 40.0f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if erfc(mid / std::f64::consts::SQRT_2) > p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let z = 0.5 * (lo + hi);
    z * z
}

/// Complementary error function (Numerical Recipes' Chebyshev fit, relative error < 1.2e-7).
fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let r = t
        * (-z * z - 1.265_512_23
            + t * (1.000_023_68
                + t * (0.374_091_96
                    + t * (0.096_784_18
                        + t * (-0.186_288_06
                            + t * (0.278_868_07
                                + t * (-1.135_203_98
                                    + t * (1.488_515_87
                                        + t * (-0.822_152_23 + t * 0.170_872_77)))))))))
            .exp();
    if x >= 0.0 {
        r
    } else {
        2.0 - r
    }
}

/// Is an effect of this size more than the rig can resolve? The region of practical
/// equivalence with `none`: offsets under 0.02 N (about one ADC count, 0.015 N), a gain within
/// 1 % of 1, an exponent within 0.01 of 1, a bending stiffness under 2·10⁻⁶ N m², and a drift,
/// wear, diameter or speed dependence that changes mu by less than 1 % across the data set's
/// span of time, runs, diameters or voltages. Every magnitude met in practice is far outside it
/// (offsets ≥ 0.2 N, gains ≥ 5 %, n ≤ 0.95, B ≥ 2·10⁻⁵ N m², mu changes ≥ 5 %); inside it,
/// statistically clear departures are artefacts of the data pipeline (e.g. the simulator's
/// tare leaves ~0.5 mN on T1), not effects.
pub fn practically_relevant(kind: EffectKind, value: f64, p: &Prepared) -> bool {
    let span = |v: Vec<f64>| v.last().copied().unwrap_or(0.0) - v.first().copied().unwrap_or(0.0);
    match kind {
        EffectKind::None => false,
        EffectKind::T1Offset | EffectKind::T2Offset => value.abs() >= 0.02,
        EffectKind::SensorGain => (value - 1.0).abs() >= 0.01,
        EffectKind::PressureFriction => (1.0 - value).abs() >= 0.01,
        EffectKind::BendingStiffness => value >= 2e-6,
        EffectKind::ThermalDrift => (value * p.max_time_spread_s() / 100.0).abs() >= 0.01,
        EffectKind::Wear => {
            let mut runs: Vec<f64> = p.unit_run.clone();
            runs.sort_by(f64::total_cmp);
            let runs = span(runs);
            (value * runs).abs() >= 0.01
        }
        EffectKind::DiameterDependence => (value * span(p.diameters())).abs() >= 0.01,
        EffectKind::SpeedDependence => (value * span(p.voltages())).abs() >= 0.01,
    }
}

/// Diagnose `d`.
pub fn diagnose_with(d: &Dataset, opts: &Options) -> Diagnosis {
    let t0 = Instant::now();
    let p = Prepared::new(d, opts.protocol_times);
    let n = p.n() as f64;
    let mut not_testable = Vec::new();
    let mut candidates = Vec::new();

    // Level 1: within runs. The null: Euler-Eytelwein with every run's own mu.
    let none_map = ThetaMap::for_kind(EffectKind::None, &p);
    let mu_start = within::start_mu(&p);
    let none = within::fit(&p, &none_map, 0.0, &mu_start);
    let mut within_fits = Vec::new();
    for kind in WITHIN {
        if let Some(reason) = untestable(kind, &p) {
            not_testable.push(NotTestable {
                effect: kind.name(),
                reason,
            });
            continue;
        }
        let map = ThetaMap::for_kind(kind, &p);
        let f = within::fit_multistart(&p, &map, &within::starts(&map), &none.mu);
        // Likelihood ratio on the T2 residuals (Gaussian, σ profiled).
        let lr = (-n * (f.rss / none.rss).ln()).max(0.0);
        // Design effect of θ: cluster-robust (runs) over model-based variance.
        let deff = (f.theta_se_robust / f.theta_se).powi(2);
        within_fits.push((kind, map, f, lr, deff));
    }
    // Residuals within a run are not independent (each run has its own tare, its own zero
    // errors): the likelihood ratios are divided by one overdispersion factor ĉ (quasi-BIC),
    // the design effect of the best-fitting candidate's parameter (at least 1). One factor
    // for all keeps their order; it only scales the evidence against `none`.
    let c_hat = within_fits
        .iter()
        .max_by(|a, b| a.3.total_cmp(&b.3))
        .map_or(1.0, |w| if w.4.is_finite() { w.4.max(1.0) } else { 1.0 });
    for (kind, map, f, lr, _) in &within_fits {
        let dbic = -lr / c_hat + n.ln();
        let value = map.value(f.theta);
        let se = match kind {
            EffectKind::BendingStiffness => 2.0 * f.theta * f.theta_se_robust,
            _ => f.theta_se_robust,
        };
        candidates.push(candidate(*kind, value, se, dbic, Level::WithinRun));
    }

    // Level 2: the runs' mu against covariates, with a random cord intercept.
    let y = &none.mu;
    let cord = &p.unit_cord;
    let nc = p.cords.len();
    let ones: Vec<Vec<f64>> = y.iter().map(|_| vec![1.0]).collect();
    let null = between::fit_lmm(y, &ones, cord, nc);
    let between_kinds = [
        EffectKind::SensorGain,
        EffectKind::Wear,
        EffectKind::DiameterDependence,
        EffectKind::SpeedDependence,
    ];
    for kind in between_kinds {
        if let Some(reason) = untestable(kind, &p) {
            not_testable.push(NotTestable {
                effect: kind.name(),
                reason,
            });
            continue;
        }
        let Some(t) = between_test(kind, &p, y) else {
            not_testable.push(NotTestable {
                effect: kind.name(),
                reason: "too few cords or runs for a test".into(),
            });
            continue;
        };
        let dbic = -chi2_equivalent(t.t, t.df) + (t.n_units as f64).ln();
        candidates.push(candidate(kind, t.value, t.se, dbic, t.level));
    }
    candidates.sort_by(|a, b| a.delta_bic.total_cmp(&b.delta_bic));

    let threshold = |c: &Candidate| match c.level {
        Level::WithinRun => opts.within_threshold,
        _ => opts.between_threshold,
    };
    for c in &mut candidates {
        c.relevant = practically_relevant(c.kind, c.value, &p);
        c.supported = c.relevant && c.delta_bic < -threshold(c);
    }
    let chosen = candidates
        .iter()
        .find(|c| c.supported)
        .map(|c| (c.kind, c.value));
    let (kind, value) = chosen.unwrap_or((EffectKind::None, 0.0));

    // Population fits through src/fit: one mu, and one mu with the chosen effect.
    let runs = p.obs.all_runs();
    let ee = ModelSpec::new("ee", Model::euler_eytelwein(stats::mean(&none.mu))).free(Param::Mu);
    let base_fit = fit_fixed(&ee, &p.obs, &runs, None);
    let mu_pop = base_fit.model(None).law.mu;
    let ext_rmse = match Param::from_effect(kind) {
        None => base_fit.rmse(),
        Some(param) => {
            let start = match kind {
                EffectKind::BendingStiffness => value.max(1e-8),
                EffectKind::SensorGain => value.max(0.1),
                _ => value,
            };
            let spec = ModelSpec::new(kind.name(), Model::euler_eytelwein(mu_pop))
                .free(Param::Mu)
                .free(param)
                .with_value(param, start);
            let f = fit_fixed(&spec, &p.obs, &runs, None);
            f.rmse().min(base_fit.rmse())
        }
    };
    let ext_run_rmse = within_fits
        .iter()
        .find(|w| w.0 == kind)
        .map_or((none.rss / n).sqrt(), |w| (w.2.rss / w.2.n as f64).sqrt());
    let mu_bar = stats::mean(&none.mu);
    let scatter = Scatter {
        cord_pct: null
            .as_ref()
            .map_or(f64::NAN, |m| 100.0 * m.sigma2_c.sqrt() / mu_bar),
        run_pct: null
            .as_ref()
            .map_or(f64::NAN, |m| 100.0 * m.sigma2_e.sqrt() / mu_bar),
        within_run_sd_n: (none.rss / (n - p.units.len() as f64).max(1.0)).sqrt(),
        overdispersion: c_hat,
    };
    let mut parameters = BTreeMap::new();
    if let Some(name) = kind.parameter() {
        parameters.insert(name, value);
    }
    Diagnosis {
        effect: kind.name(),
        parameters,
        baseline: Baseline {
            mu: mu_pop,
            rmse_t2_n: base_fit.rmse(),
            rmse_t2_run_mu_n: (none.rss / n).sqrt(),
        },
        extended: Extended {
            rmse_t2_n: ext_rmse,
            rmse_t2_run_mu_n: ext_run_rmse,
        },
        candidates,
        not_testable,
        design: Design {
            rows: p.n(),
            cords: p.cords.len(),
            runs: p.units.len(),
            wraps_deg: p.wraps(),
            diameters_mm: p.diameters(),
            drive_v: p.voltages(),
            columns: p.columns,
        },
        scatter,
        thresholds: Thresholds {
            within_run: -opts.within_threshold,
            between: -opts.between_threshold,
        },
        kind,
        value: if kind == EffectKind::None {
            EffectKind::None.neutral_value()
        } else {
            value
        },
        elapsed_s: t0.elapsed().as_secs_f64(),
    }
}

fn candidate(kind: EffectKind, value: f64, se: f64, dbic: f64, level: Level) -> Candidate {
    let mut parameters = BTreeMap::new();
    if let Some(name) = kind.parameter() {
        parameters.insert(name, value);
    }
    Candidate {
        effect: kind.name(),
        delta_bic: dbic,
        parameters,
        parameter_se: se,
        level,
        relevant: false,
        supported: false,
        kind,
        value,
    }
}
#[cfg(test)]
mod tests;
