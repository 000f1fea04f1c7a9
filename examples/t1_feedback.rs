//! Why a planted drift on rising runs is named contact heating: T1 answers to mu.
//!
//! ```text
//! cargo run --release --example t1_feedback -- [--seed N] [--runs R] [--wrap DEG] [--volt V]
//! ```
//! One cord of the generated drift case (master seed 1), a drift of −0.28 per 100 s, the thesis
//! wander of mu and nothing else (no scatter between cords or runs, no zero errors), monotone
//! runs. Prints each candidate's WRSS alone (every run's own mu, the engine's weights) and what
//! is named, under three conditions:
//! * the data as measured (the engine reads the law's shape at the other runs' T1 only above
//!   `fit::predict::SHAPE_MIN_T1_N`, 8 N: at 630° most steps are below it);
//! * every T1 replaced by the mean T1 of all runs at its step, T2 scaled to keep T2/T1 (T1 then
//!   no longer carries the row's own wander);
//! * the wander switched off.
//!
//! The figures are in docs/README-diagnose.md ("The cause: T1 answers to mu").
use capstan_data::Dataset;
use capstan_engine::evidence::{assess, candidates::ThetaMap, within, Options};
use capstan_physics::{Effect, EffectKind};
use capstan_validation::cases::{draw_case, Class};
use std::collections::HashMap;

fn arg(args: &[String], name: &str, default: f64) -> f64 {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// T1 of every row replaced by its (wrap, step) mean over the runs, T2/T1 kept.
fn exogenous_t1(d: &mut Dataset) {
    let key = |p: &capstan_data::Pair| (p.wrap_deg.to_bits(), p.step.map(f64::to_bits));
    let mut m: HashMap<_, (f64, f64)> = HashMap::new();
    for p in &d.pairs {
        let e = m.entry(key(p)).or_insert((0.0, 0.0));
        e.0 += p.t1_n;
        e.1 += 1.0;
    }
    for p in d.pairs.iter_mut() {
        let (sum, n) = m[&key(p)];
        let ratio = p.t2_n / p.t1_n;
        p.t1_n = sum / n;
        p.t2_n = p.t1_n * ratio;
    }
}

fn report(label: &str, d: &Dataset) {
    let a = assess(d, &Options::default());
    let named: Vec<String> = a
        .selected_evidence()
        .iter()
        .map(|e| format!("{} = {:+.4}", e.effect, e.value))
        .collect();
    println!("{label}: named [{}]", named.join(", "));
    for kind in [
        EffectKind::ThermalDrift,
        EffectKind::ContactHeating,
        EffectKind::PressureFriction,
    ] {
        let maps = vec![ThetaMap::for_kind(kind, &a.design)];
        let f = within::fit_multistart(&a.design, &maps, &[0.0], &a.null.mu, &a.weights);
        println!(
            "  {:<18} alone: WRSS {:>10.2}  value {:+.5}",
            kind.name(),
            f.wrss,
            f.value(0)
        );
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let index = (0..11)
        .find(|&i| draw_case(1, Class::Single, i).effects[0].kind == EffectKind::ThermalDrift)
        .expect("the catalogue has a drift");
    let mut c = draw_case(1, Class::Single, index);
    let cfg = &mut c.config;
    cfg.seed = arg(&args, "--seed", 1.0) as u64;
    cfg.effects = vec![Effect {
        kind: EffectKind::ThermalDrift,
        value: -0.28,
    }];
    cfg.wraps_deg = vec![arg(&args, "--wrap", 630.0)];
    cfg.drive_vs = vec![arg(&args, "--volt", 6.0)];
    cfg.diameters_mm.truncate(1);
    cfg.runs = arg(&args, "--runs", 120.0) as u32;
    cfg.order = capstan_rig::StepOrder::Monotone;
    cfg.scatter_pct = 0.0;
    cfg.run_scatter_pct = Some(0.0);
    cfg.plant.disturbances.zero_error_sd_n = 0.0;
    c.drop_columns.clear();
    eprintln!("{}", c.describe());
    let (measured, _) = c.generate().expect("the case simulates");
    report("measured T1", &measured);
    let mut exo = measured.clone();
    exogenous_t1(&mut exo);
    report("T1 = mean of all runs at the step", &exo);
    c.config.plant.disturbances.mu_wander_sd = 0.0;
    let (quiet, _) = c.generate().expect("the case simulates");
    report("wander off", &quiet);
}
