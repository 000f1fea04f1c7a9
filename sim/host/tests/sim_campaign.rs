//! Campaigns through the firmware's own sampling and conditioning: Euler-Eytelwein with noise,
//! determinism, scatter, and the signature of every catalogue effect.

use capstan_physics::{Effect, EffectKind};
use capstan_sim::campaign::{run_campaign, CampaignConfig, CampaignResult, PairRow};
use std::collections::BTreeMap;

/// The thesis protocol with 3 s steps (1.5 s windows): the same code paths, a third of the time.
fn short_protocol() -> capstan_rig::Protocol {
    capstan_rig::Protocol {
        dwell_ms: 3_000,
        window_after_change_ms: 1_000,
        window_before_next_ms: 500,
        ..capstan_rig::Protocol::default()
    }
}

fn ln_ratio(r: &PairRow) -> f64 {
    (r.t2_n / r.t1_n).ln()
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

fn sd(v: &[f64]) -> f64 {
    let m = mean(v);
    (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() as f64 - 1.0)).sqrt()
}

/// Key of a (diameter, wrap) group.
fn group(r: &PairRow) -> (u64, u64) {
    (r.capstan_diameter_mm.to_bits(), r.wrap_deg.to_bits())
}

/// The default campaign (thesis: 2 × 5 × 6 runs of 131.5 s, noise on): every pair follows
/// T1·exp(mu·β) with the plant's mu.
#[test]
fn no_effect_pairs_follow_euler_eytelwein_with_noise_on() {
    let cfg = CampaignConfig::default();
    assert!(cfg.sensor_noise && cfg.effects.is_empty() && cfg.scatter_pct == 0.0);
    let r = run_campaign(&cfg).unwrap();
    assert_eq!(r.runs.len(), 60);
    assert_eq!(r.rows.len(), 720, "12 pairs per run, no fault");
    assert!(r.faults.is_empty(), "{:?}", r.faults);
    let mu = cfg.model.law.mu;
    let mut groups: BTreeMap<(u64, u64), Vec<&PairRow>> = BTreeMap::new();
    for row in &r.rows {
        groups.entry(group(row)).or_default().push(row);
    }
    assert_eq!(groups.len(), 10);
    let mut worst_sd: f64 = 0.0;
    let mut worst_mu: f64 = 0.0;
    for rows in groups.values() {
        let beta = rows[0].wrap_deg.to_radians();
        let lr: Vec<f64> = rows
            .iter()
            .filter(|p| p.t1_n > 2.0)
            .map(|p| ln_ratio(p))
            .collect();
        assert!(lr.len() >= 40, "{} pairs above 2 N", lr.len());
        let s = sd(&lr);
        worst_sd = worst_sd.max(s);
        assert!(
            s <= 0.005,
            "{} mm {}°: sd of ln(T2/T1) {s}",
            rows[0].capstan_diameter_mm,
            rows[0].wrap_deg
        );
        // Euler-Eytelwein: mean ln(T2/T1)/β is the plant's mu, within 0.1 %.
        let mu_hat = mean(&lr) / beta;
        worst_mu = worst_mu.max((mu_hat / mu - 1.0).abs());
        assert!(
            (mu_hat / mu - 1.0).abs() < 1e-3,
            "{} mm {}°: mu {mu_hat} vs {mu}",
            rows[0].capstan_diameter_mm,
            rows[0].wrap_deg
        );
    }
    // The pairs' times are the window centres of the thesis protocol: 10 k + 6 s.
    for row in &r.rows {
        assert_eq!(row.time_s, 10.0 * row.step as f64 + 6.0);
    }
    eprintln!(
        "default campaign: worst sd of ln(T2/T1) {worst_sd:.5}, worst |mu error| {:.4} %, \
         {:.0} s simulated in {:.3} s ({:.0}x)",
        worst_mu * 100.0,
        r.simulated_s,
        r.wall_s,
        r.realtime_factor()
    );
}

fn small(seed: u64, threads: usize) -> CampaignResult {
    let cfg = CampaignConfig {
        diameters_mm: vec![12.7],
        wraps_deg: vec![270.0, 630.0],
        runs: 2,
        protocol: short_protocol(),
        seed,
        threads,
        scatter_pct: 5.0,
        ..CampaignConfig::default()
    };
    run_campaign(&cfg).unwrap()
}

#[test]
fn a_seed_gives_the_same_data_whatever_the_thread_count() {
    let a = small(7, 1);
    let b = small(7, 2);
    let c = small(8, 2);
    assert_eq!(a.rows, b.rows);
    for (x, y) in a.runs.iter().zip(&b.runs) {
        assert_eq!(x.log, y.log, "run {}", x.index);
    }
    assert_ne!(a.rows, c.rows);
    // A cord's data do not depend on which other cords are in the campaign.
    let alone = run_campaign(&CampaignConfig {
        diameters_mm: vec![12.7],
        wraps_deg: vec![630.0],
        runs: 2,
        protocol: short_protocol(),
        seed: 7,
        scatter_pct: 5.0,
        ..CampaignConfig::default()
    })
    .unwrap();
    let with: Vec<PairRow> = a
        .rows
        .iter()
        .filter(|r| r.wrap_deg == 630.0)
        .copied()
        .collect();
    assert_eq!(alone.rows, with);
}

#[test]
fn scatter_spreads_mu_between_cords_and_half_as_much_between_runs() {
    let cfg = CampaignConfig {
        diameters_mm: vec![12.7, 25.4],
        wraps_deg: (0..10).map(|k| 270.0 + 50.0 * k as f64).collect(),
        runs: 3,
        scatter_pct: 10.0,
        // Noise on: it dithers the ADC (noiseless 12-bit conversions are biased by rounding).
        protocol: short_protocol(),
        keep_raw: false,
        ..CampaignConfig::default()
    };
    let r = run_campaign(&cfg).unwrap();
    let mu0 = cfg.model.law.mu;
    // Per cord: mean of its runs' mu; within a cord, the runs' spread.
    let mut cords: BTreeMap<(u64, u64), Vec<f64>> = BTreeMap::new();
    for run in &r.runs {
        let key = (run.cord.diameter_mm.to_bits(), run.cord.wrap_deg.to_bits());
        cords.entry(key).or_default().push(run.model.law.mu / mu0);
        // Each run's pairs follow its own mu.
        let beta = run.cord.wrap_deg.to_radians();
        let lr: Vec<f64> = run
            .log
            .pairs
            .iter()
            .filter(|p| p.t1.mean_n > 2.0)
            .map(|p| ((p.t2.mean_n / p.t1.mean_n) as f64).ln())
            .collect();
        let mu_hat = mean(&lr) / beta;
        assert!(
            (mu_hat / run.model.law.mu - 1.0).abs() < 2e-3,
            "run {}: {mu_hat} vs {}",
            run.index,
            run.model.law.mu
        );
    }
    assert_eq!(cords.len(), 20);
    let cord_means: Vec<f64> = cords.values().map(|v| mean(v)).collect();
    let within: Vec<f64> = cords
        .values()
        .flat_map(|v| {
            let m = mean(v);
            v.iter().map(move |x| x / m - 1.0)
        })
        .collect();
    let between = sd(&cord_means);
    // Pooled within-cord sd (3 runs each: 2 degrees of freedom per cord).
    let pooled = (within.iter().map(|d| d * d).sum::<f64>() / (2.0 * 20.0)).sqrt();
    assert!((0.06..0.15).contains(&between), "cord-to-cord sd {between}");
    assert!((0.03..0.075).contains(&pooled), "run-to-run sd {pooled}");
}

/// One cord per (diameter, wrap, voltage) with and without `effect`, same seed.
fn with_and_without(
    effect: Effect,
    tweak: impl Fn(&mut CampaignConfig),
) -> (CampaignResult, CampaignResult) {
    let mut cfg = CampaignConfig {
        diameters_mm: vec![12.7],
        wraps_deg: vec![450.0],
        runs: 1,
        protocol: short_protocol(),
        keep_raw: false,
        ..CampaignConfig::default()
    };
    tweak(&mut cfg);
    let base = run_campaign(&cfg).unwrap();
    cfg.effects = vec![effect];
    let on = run_campaign(&cfg).unwrap();
    assert_eq!(base.rows.len(), on.rows.len());
    (base, on)
}

/// mu measured from one run's pairs above 2 N.
fn mu_of(rows: &[PairRow]) -> f64 {
    let lr: Vec<f64> = rows.iter().filter(|r| r.t1_n > 2.0).map(ln_ratio).collect();
    mean(&lr) / rows[0].wrap_deg.to_radians()
}

fn select(rows: &[PairRow], f: impl Fn(&PairRow) -> bool) -> Vec<PairRow> {
    rows.iter().filter(|r| f(r)).copied().collect()
}

#[test]
fn every_catalogue_effect_shows_its_signature() {
    let e = |kind, value| Effect { kind, value };

    // Sensor artefacts survive the tare and are not seen by it (they ride on the drive): the
    // data show the catalogue's measured T1 = T1 + e1, measured T2 = g·T2 + e2.
    let (b, o) = with_and_without(e(EffectKind::T1Offset, 0.3), |_| {});
    for (x, y) in b.rows.iter().zip(&o.rows) {
        assert!((y.t1_n - x.t1_n - 0.3).abs() < 0.003, "{x:?} {y:?}");
        assert!((y.t2_n - x.t2_n).abs() < 0.003);
    }
    let (b, o) = with_and_without(e(EffectKind::T2Offset, -0.4), |_| {});
    for (x, y) in b.rows.iter().zip(&o.rows) {
        assert!((y.t2_n - x.t2_n + 0.4).abs() < 0.003, "{x:?} {y:?}");
    }
    let (b, o) = with_and_without(e(EffectKind::SensorGain, 1.05), |_| {});
    for (x, y) in b.rows.iter().zip(&o.rows) {
        // No T2 offset from the tare (it would be −(g − 1)·0.1 N = −5 mN): the pure gain, at
        // every tension.
        assert!((y.t2_n - 1.05 * x.t2_n).abs() < 0.003, "{x:?} {y:?}");
        assert!((y.t1_n - x.t1_n).abs() < 0.003);
    }

    // Pressure-dependent friction: amplification falls with tension.
    let (b, o) = with_and_without(e(EffectKind::PressureFriction, 0.85), |_| {});
    let amp = |r: &PairRow| r.t2_n / r.t1_n;
    let (first, last) = (&o.rows[2], &o.rows[o.rows.len() - 1]);
    assert!(amp(first) > amp(last) * 1.15, "{first:?} {last:?}");
    let (first, last) = (&b.rows[2], &b.rows[b.rows.len() - 1]);
    assert!((amp(first) / amp(last) - 1.0).abs() < 0.01);

    // Bending stiffness: amplification lost at low tension.
    let (b, o) = with_and_without(e(EffectKind::BendingStiffness, 2e-5), |_| {});
    assert!(amp(&o.rows[0]) < amp(&b.rows[0]) * 0.9);
    let n = o.rows.len() - 1;
    assert!(amp(&o.rows[n]) > amp(&b.rows[n]) * 0.95);

    // Thermal drift: mu rises along the run at +10 %/100 s.
    let (b, o) = with_and_without(e(EffectKind::ThermalDrift, 0.1), |_| {});
    let mu_t = |rows: &[PairRow], k: usize| ln_ratio(&rows[k]) / rows[k].wrap_deg.to_radians();
    let (t0, t1) = (o.rows[4].time_s, o.rows[11].time_s);
    let want = (1.0 + 0.1 * t1 / 100.0) / (1.0 + 0.1 * t0 / 100.0);
    assert!((mu_t(&o.rows, 11) / mu_t(&o.rows, 4) / want - 1.0).abs() < 2e-3);
    assert!((mu_t(&b.rows, 11) / mu_t(&b.rows, 4) - 1.0).abs() < 2e-3);

    // Wear: mu changes from run to run.
    let (_, o) = with_and_without(e(EffectKind::Wear, -0.05), |c| c.runs = 3);
    let r1 = mu_of(&select(&o.rows, |r| r.run == 1));
    let r3 = mu_of(&select(&o.rows, |r| r.run == 3));
    assert!((r3 / r1 - 0.9).abs() < 2e-3, "{r1} {r3}");

    // Diameter dependence: mu differs between capstans.
    let (_, o) = with_and_without(e(EffectKind::DiameterDependence, 0.01), |c| {
        c.diameters_mm = vec![12.7, 25.4]
    });
    let small = mu_of(&select(&o.rows, |r| r.capstan_diameter_mm == 12.7));
    let big = mu_of(&select(&o.rows, |r| r.capstan_diameter_mm == 25.4));
    assert!((big / small - 1.127).abs() < 2e-3, "{small} {big}");

    // Speed dependence: mu follows the drive voltage.
    let (_, o) = with_and_without(e(EffectKind::SpeedDependence, 0.02), |c| {
        c.drive_vs = vec![7.5, 10.0]
    });
    let slow = mu_of(&select(&o.rows, |r| r.drive_v == 7.5));
    let fast = mu_of(&select(&o.rows, |r| r.drive_v == 10.0));
    assert!((slow / fast - 0.95).abs() < 2e-3, "{slow} {fast}");
}

#[test]
fn bad_campaigns_are_refused_with_a_reason() {
    let bad = |f: fn(&mut CampaignConfig)| {
        let mut c = CampaignConfig::default();
        f(&mut c);
        run_campaign(&c).unwrap_err().to_string()
    };
    assert!(bad(|c| c.wraps_deg.clear()).contains("wraps_deg"));
    assert!(bad(|c| c.drive_vs = vec![20.0]).contains("13.2"));
    assert!(bad(|c| c.diameters_mm = vec![-1.0]).contains("diameter"));
    assert!(bad(|c| c.scatter_pct = f64::NAN).contains("scatter"));
    assert!(bad(|c| c.runs = 0).contains("runs"));
    assert!(bad(|c| c.protocol.dwell_ms = 0).contains("protocol"));
    assert!(bad(|c| c.faults = vec!["abort@1#61".parse().unwrap()]).contains("61"));
    assert!("cord_break".parse::<capstan_sim::FaultSpec>().is_err());
    assert!("melt@3"
        .parse::<capstan_sim::FaultSpec>()
        .unwrap_err()
        .to_string()
        .contains("unknown fault"));
    assert!("abort@-1".parse::<capstan_sim::FaultSpec>().is_err());
    assert!("abort@x".parse::<capstan_sim::FaultSpec>().is_err());
    assert!("abort@1#0".parse::<capstan_sim::FaultSpec>().is_err());
}
