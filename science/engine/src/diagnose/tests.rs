//! The diagnosis on data straight from the shared model, and its run-level mu against
//! `fit`.

use super::*;
use capstan_data::{read_pairs, write_pairs_to, Pair};

/// A data set straight from the shared model: 4 wraps × 2 diameters × 3 runs, each run with
/// its own mu, 12 tension levels, a little deterministic noise. T2 comes from
/// `fit::predict::predict_run` (the load memory carried along each run).
fn synthetic(effect: Effect) -> Dataset {
    synthetic_on(effect, &[270.0, 450.0, 630.0, 720.0], 0.002)
}

/// [`synthetic`] on the wraps `wraps_deg`, with noise up to ±`noise_n` on T2.
fn synthetic_on(effect: Effect, wraps_deg: &[f64], noise_n: f64) -> Dataset {
    let mut pairs = Vec::new();
    let mut models = Vec::new();
    for (di, d) in [12.7, 25.4].into_iter().enumerate() {
        for (wi, &w) in wraps_deg.iter().enumerate() {
            for run in 1..=3 {
                let mu = 0.115 * (1.0 + 0.02 * ((di * 7 + wi * 3 + run) % 5) as f64 - 0.04);
                let m = Model::euler_eytelwein(mu).with_effect(effect);
                for step in 1..=12 {
                    let t1 = 0.4 + 1.6 * step as f64 + effect_t1(effect);
                    models.push(m);
                    pairs.push(Pair {
                        capstan_diameter_mm: Some(d),
                        wrap_deg: w,
                        drive_v: Some(10.0),
                        run: Some(run as f64),
                        step: Some(step as f64),
                        time_s: Some(6.0 + 4.0 * step as f64),
                        t1_n: t1,
                        t2_n: t1,
                        extra: Vec::new(),
                        labels: Vec::new(),
                    });
                }
            }
        }
    }
    let mut csv = Vec::new();
    write_pairs_to(&mut csv, &pairs).unwrap();
    let mut data = read_pairs(csv.as_slice(), "synthetic").unwrap();
    let obs = crate::fit::Observations::from_dataset(&data);
    let t1: Vec<f64> = obs.rows.iter().map(|r| r.t1_n).collect();
    let op: Vec<_> = obs.rows.iter().map(|r| r.op).collect();
    let timing: Vec<_> = obs.rows.iter().map(|r| r.timing).collect();
    let mut t2 = vec![f64::NAN; obs.len()];
    for run in &obs.runs {
        let rows = crate::fit::predict::RunRows {
            t1_n: &t1,
            t1_shape_n: None,
            op: &op,
            timing: &timing,
            rows: run,
        };
        crate::fit::predict::predict_run(&models[run[0]], rows, true, None, &mut t2, None);
    }
    for (k, p) in data.pairs.iter_mut().enumerate() {
        let noise = noise_n * ((((k + 1) as u64 * 2_654_435_761) % 1000) as f64 / 500.0 - 1.0);
        p.t2_n = t2[k] + noise;
    }
    data
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
        (EffectKind::ContactHeating, 0.008, 2e-4),
    ] {
        let d = diagnose(&synthetic(Effect { kind, value }));
        assert_eq!(d.kind, kind, "{}", d.to_json());
        assert_eq!(d.effects.len(), 1, "{}", d.to_json());
        assert!(!d.unexplained, "{}", d.to_json());
        // Clear data leave no rival to the effect found.
        assert!(d.rivals.is_empty(), "{}", d.to_json());
        assert!(
            (d.value - value).abs() < tol,
            "{kind}: {} vs {value}",
            d.value
        );
    }
    let d = diagnose(&synthetic(Effect::NONE));
    assert_eq!(d.kind, EffectKind::None, "{}", d.to_json());
    assert!(d.effects.is_empty() && !d.unexplained, "{}", d.to_json());
}

#[test]
fn run_mu_agree_with_the_fit_module() {
    // The within-run Euler-Eytelwein mu of one run equals fit's fit_fixed on that run
    // (equal weights: the same least squares).
    let data = synthetic(Effect::NONE);
    let des = crate::evidence::Design::new(&data, false);
    let w = crate::evidence::within::Weights::equal(des.n());
    let none =
        crate::evidence::within::fit(&des, &[], &[], &crate::evidence::within::start_mu(&des), &w);
    let spec = ModelSpec::new("ee", Model::euler_eytelwein(0.1)).free(Param::Mu);
    for u in [0, 5, 11] {
        let rows = &des.units[u];
        let run = des.obs.rows[rows[0]].run;
        let f = fit_fixed(&spec, &des.obs, &[run], None);
        let mu = f.model(None).law.mu;
        assert!(
            (mu - none.mu[u]).abs() < 1e-7,
            "unit {u}: {mu} vs {}",
            none.mu[u]
        );
    }
}

#[test]
fn a_rival_the_design_cannot_separate_is_reported_with_why() {
    // On a single wrap a T1 zero offset reaches T2 as a constant (× e^(μβ); the runs' mu
    // differ by a few per cent, a few hundredths of a newton here, under noise of ±0.3 N like
    // the thesis rig's): a T2 offset fits it as well. The answer must name one and report the
    // other as a rival it cannot rule out, with the reason, in the verdict too.
    let d = diagnose(&synthetic_on(
        Effect {
            kind: EffectKind::T1Offset,
            value: 0.5,
        },
        &[450.0],
        0.3,
    ));
    let offsets = [EffectKind::T1Offset, EffectKind::T2Offset];
    assert!(offsets.contains(&d.kind), "{}", d.to_json());
    let r = d
        .rivals
        .iter()
        .find(|r| offsets.contains(&r.kind) && r.kind != d.kind)
        .unwrap_or_else(|| panic!("no offset rival: {}", d.to_json()));
    assert_eq!(r.instead_of_kind, d.kind);
    assert!(r.delta_bic.abs() < 2.0, "{}", r.delta_bic);
    assert!(r
        .reason
        .as_ref()
        .is_some_and(|w| w.contains("wrap") && w.contains("e^(μβ)")));
    assert!(
        d.verdict.contains("cannot rule out") && d.verdict.contains(r.effect),
        "{}",
        d.verdict
    );
}

#[test]
fn the_swaps_are_the_final_set_with_one_member_replaced() {
    // A T2 offset planted in the model and a T1 offset on the readings, four wraps, little
    // noise: both are found, and every swap the selection reports (the rivals' evidence) is
    // the final set of two with the member at its slot replaced, fitted.
    let mut data = synthetic(Effect {
        kind: EffectKind::T2Offset,
        value: -0.7,
    });
    for p in &mut data.pairs {
        p.t1_n += 0.5;
    }
    use crate::evidence::{candidates, select, within};
    let des = crate::evidence::Design::new(&data, false);
    let cold = within::fit(
        &des,
        &[],
        &[],
        &within::start_mu(&des),
        &within::Weights::equal(des.n()),
    );
    let w = within::Weights::from_pure_error(&des, &cold);
    let null = within::fit(&des, &[], &[], &cold.mu, &w);
    let within = candidates::at_level(candidates::Level::WithinRun);
    let sel = select::forward(&des, null, &within, &w, 6.0, 1);
    let mut kinds: Vec<EffectKind> = sel.fit.maps.iter().map(|m| m.kind).collect();
    kinds.sort();
    assert_eq!(kinds, [EffectKind::T1Offset, EffectKind::T2Offset]);
    assert_eq!(sel.swaps.len(), 2 * (within.len() - 2));
    for s in &sel.swaps {
        let mut maps = sel.fit.maps.clone();
        assert_ne!(maps[s.slot].kind, s.kind);
        maps[s.slot] = candidates::ThetaMap::for_kind(s.kind, &des);
        let mut theta = sel.fit.theta.clone();
        theta[s.slot] = maps[s.slot].theta(s.value);
        let refit = within::fit(&des, &maps, &theta, &sel.fit.mu, &w);
        assert!(
            (refit.wrss - s.wrss).abs() <= 1e-6 * s.wrss.max(1e-12) + 1e-9,
            "{:?} at {}: {} vs {}",
            s.kind,
            s.slot,
            refit.wrss,
            s.wrss
        );
    }
}
