//! The diagnosis on data straight from the shared model, its run-level mu against `src/fit`,
//! and the t-to-χ² mapping.

use super::*;
use crate::data::{read_pairs, write_pairs_to, Pair};
use capstan_friction::Effect;

/// A data set straight from the shared model: 4 wraps × 2 diameters × 3 runs, each run with
/// its own mu, 12 tension levels, a little deterministic noise.
fn synthetic(effect: Effect) -> Dataset {
    let mut pairs = Vec::new();
    let mut k = 0u64;
    for (di, d) in [12.7, 25.4].into_iter().enumerate() {
        for (wi, w) in [270.0, 450.0, 630.0, 720.0].into_iter().enumerate() {
            for run in 1..=3 {
                let mu = 0.115 * (1.0 + 0.02 * ((di * 7 + wi * 3 + run) % 5) as f64 - 0.04);
                let m = Model::euler_eytelwein(mu).with_effect(effect);
                for step in 1..=12 {
                    k += 1;
                    let noise = 0.002 * (((k * 2_654_435_761) % 1000) as f64 / 500.0 - 1.0);
                    let t1 = 0.4 + 1.6 * step as f64 + effect_t1(effect);
                    let op = capstan_friction::Operating {
                        wrap_rad: f64::to_radians(w),
                        diameter_mm: d,
                        drive_v: 10.0,
                        run: run as f64,
                        time_s: 6.0 + 4.0 * step as f64,
                        load_memory_ns: 0.0,
                    };
                    pairs.push(Pair {
                        capstan_diameter_mm: Some(d),
                        wrap_deg: w,
                        drive_v: Some(10.0),
                        run: Some(run as f64),
                        step: Some(step as f64),
                        time_s: Some(op.time_s),
                        t1_n: t1,
                        t2_n: m.predict_t2_n(t1, &op) + noise,
                        extra: Vec::new(),
                    });
                }
            }
        }
    }
    let mut csv = Vec::new();
    write_pairs_to(&mut csv, &pairs).unwrap();
    read_pairs(csv.as_slice(), "synthetic").unwrap()
}

fn effect_t1(e: Effect) -> f64 {
    if e.kind == EffectKind::T1Offset {
        e.value
    } else {
        0.0
    }
}

#[test]
fn recovers_effects_from_the_shared_model() {
    for (kind, value, tol) in [
        (EffectKind::T1Offset, 0.5, 0.01),
        (EffectKind::T2Offset, -0.7, 0.01),
        (EffectKind::PressureFriction, 0.85, 0.005),
        (EffectKind::BendingStiffness, 8e-5, 5e-6),
        (EffectKind::ThermalDrift, 0.3, 0.01),
    ] {
        let d = diagnose(&synthetic(Effect { kind, value }));
        assert_eq!(d.kind, kind, "{}", d.to_json());
        assert!(
            (d.value - value).abs() < tol,
            "{kind}: {} vs {value}",
            d.value
        );
    }
    let d = diagnose(&synthetic(Effect::NONE));
    assert_eq!(d.kind, EffectKind::None, "{}", d.to_json());
}

#[test]
fn run_mu_agree_with_the_fit_module() {
    // The within-run Euler-Eytelwein mu of one run equals src/fit's fit_fixed on that run.
    let data = synthetic(Effect::NONE);
    let p = Prepared::new(&data, false);
    let none = within::fit(
        &p,
        &ThetaMap::for_kind(EffectKind::None, &p),
        0.0,
        &within::start_mu(&p),
    );
    let spec = ModelSpec::new("ee", Model::euler_eytelwein(0.1)).free(Param::Mu);
    for u in [0, 5, 11] {
        let rows = &p.units[u];
        let run = p.obs.rows[rows[0]].run;
        let f = fit_fixed(&spec, &p.obs, &[run], None);
        let mu = f.model(None).law.mu;
        assert!(
            (mu - none.mu[u]).abs() < 1e-7,
            "unit {u}: {mu} vs {}",
            none.mu[u]
        );
    }
}

#[test]
fn t_statistics_map_onto_chi_square() {
    // Large df: the χ² equivalent of t is t².
    for t in [1.0, 2.0, 3.5] {
        let c = chi2_equivalent(t, 1e7);
        assert!((c - t * t).abs() < 1e-3 * t * t, "{t}: {c}");
    }
    // Few df: the same t is weaker evidence.
    assert!(chi2_equivalent(3.0, 4.0) < chi2_equivalent(3.0, 40.0));
    assert!((erfc(0.0) - 1.0).abs() < 1e-7 && (erfc(1.0) - 0.157_299_2).abs() < 1e-6);
}
