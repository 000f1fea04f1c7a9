//! `capstan diagnose` against effects hidden in generated data.
//!
//! Every case is a data set made by the firmware-in-the-loop simulator (`host-sim`: the
//! firmware's own protocol, sampling and conditioning against the simulated plant) with one
//! catalogue effect at a random magnitude in the ranges met in practice, or none; cord-to-cord
//! and run-to-run scatter of mu (1-3 %), sensor noise, both step orders, varied wraps,
//! diameters, voltages and run counts (see `capstan::diagnose::cases`). `diagnose` must name
//! the effect.
//!
//! Assertions (over 238 cases: 22 per effect, 40 without one):
//! * at least 95 % named correctly overall, and at least 85 % for every effect;
//! * false alarms on `none` at most 5 %;
//! * the parameter within 25 % for at least 90 % of the correct calls (for `n` and `gain`,
//!   25 % of the departure from the neutral value 1);
//! * a constant or a random diagnosis, scored on the same cases, fails these assertions.
//!
//! `cargo test --release --test diagnose_cases -- --nocapture` prints the confusion matrix;
//! `CAPSTAN_DIAGNOSE_SEED=N` draws the cases from another master seed (fresh data).

use capstan::diagnose::{self, cases, Diagnosis};
use capstan_friction::{Effect, EffectKind};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, OnceLock};

/// Seed of the test cases. The thresholds were calibrated on another seed (99), but the
/// practical-equivalence rule was added after a false alarm on this one: its honest check is on
/// fresh seeds (docs/README-diagnose.md, "Fresh seeds").
const MASTER_SEED: u64 = 20_260_522;

/// The master seed: [`MASTER_SEED`], or `CAPSTAN_DIAGNOSE_SEED` to evaluate on fresh cases.
fn master_seed() -> u64 {
    match std::env::var("CAPSTAN_DIAGNOSE_SEED") {
        Ok(s) => s
            .trim()
            .replace('_', "")
            .parse()
            .unwrap_or_else(|_| panic!("CAPSTAN_DIAGNOSE_SEED={s}: not an unsigned integer")),
        Err(_) => MASTER_SEED,
    }
}
/// Cases per effect, and without an effect.
const PER_EFFECT: u64 = 22;
const PER_NONE: u64 = 40;

/// What a diagnosis said about one case.
#[derive(Clone, Debug)]
struct Outcome {
    truth: Effect,
    found: Effect,
    describe: String,
    rows: usize,
    elapsed_s: f64,
    candidates: String,
}

fn outcomes() -> &'static [Outcome] {
    static CELL: OnceLock<Vec<Outcome>> = OnceLock::new();
    CELL.get_or_init(|| {
        let seed = master_seed();
        let mut jobs = Vec::new();
        for kind in EffectKind::ALL {
            let n = if kind == EffectKind::None {
                PER_NONE
            } else {
                PER_EFFECT
            };
            for i in 0..n {
                jobs.push(cases::draw_case(seed, kind, i));
            }
        }
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
        let next = AtomicUsize::new(0);
        let out: Mutex<Vec<Option<Outcome>>> = Mutex::new(vec![None; jobs.len()]);
        let t0 = std::time::Instant::now();
        std::thread::scope(|s| {
            for _ in 0..threads {
                s.spawn(|| loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(case) = jobs.get(i) else { break };
                    let (data, _) = case.generate().expect("the case simulates");
                    let d: Diagnosis = diagnose::diagnose(&data);
                    let o = Outcome {
                        truth: case.effect,
                        found: d.found(),
                        describe: case.describe(),
                        rows: data.pairs.len(),
                        elapsed_s: d.elapsed_s,
                        candidates: d
                            .candidates
                            .iter()
                            .take(3)
                            .map(|c| format!("{}={:.4e} ({:.1})", c.effect, c.value, c.delta_bic))
                            .collect::<Vec<_>>()
                            .join(", "),
                    };
                    out.lock().unwrap()[i] = Some(o);
                });
            }
        });
        eprintln!(
            "master seed {seed}: generated and diagnosed {} cases in {:.1} s on {threads} threads",
            jobs.len(),
            t0.elapsed().as_secs_f64()
        );
        out.into_inner()
            .unwrap()
            .into_iter()
            .map(|o| o.expect("every case ran"))
            .collect()
    })
}

/// Is the estimate within 25 % of the truth? For `n` and `gain` (neutral 1), 25 % of the
/// departure from 1; for the others (neutral 0), 25 % of the value.
fn parameter_ok(truth: Effect, found: Effect) -> bool {
    let neutral = truth.kind.neutral_value();
    ((found.value - truth.value) / (truth.value - neutral)).abs() <= 0.25
}

/// Accuracy figures of a list of (truth, call) pairs.
#[derive(Debug)]
struct Metrics {
    per_effect: Vec<(EffectKind, usize, usize)>,
    overall: f64,
    false_alarms: f64,
    parameter_ok: f64,
}

fn metrics(calls: &[(Effect, Effect)]) -> Metrics {
    let per_effect = EffectKind::ALL
        .iter()
        .map(|&k| {
            let of_k: Vec<_> = calls.iter().filter(|(t, _)| t.kind == k).collect();
            let right = of_k.iter().filter(|(t, f)| t.kind == f.kind).count();
            (k, right, of_k.len())
        })
        .collect();
    let right = calls.iter().filter(|(t, f)| t.kind == f.kind).count();
    let nones: Vec<_> = calls
        .iter()
        .filter(|(t, _)| t.kind == EffectKind::None)
        .collect();
    let alarms = nones
        .iter()
        .filter(|(_, f)| f.kind != EffectKind::None)
        .count();
    let correct_effects: Vec<_> = calls
        .iter()
        .filter(|(t, f)| t.kind == f.kind && t.kind != EffectKind::None)
        .collect();
    let param_ok = correct_effects
        .iter()
        .filter(|(t, f)| parameter_ok(*t, *f))
        .count();
    Metrics {
        per_effect,
        overall: right as f64 / calls.len().max(1) as f64,
        false_alarms: alarms as f64 / nones.len().max(1) as f64,
        parameter_ok: if correct_effects.is_empty() {
            0.0
        } else {
            param_ok as f64 / correct_effects.len() as f64
        },
    }
}

/// The acceptance criteria; the reasons it fails (empty: passes).
fn failures(m: &Metrics) -> Vec<String> {
    let mut why = Vec::new();
    if m.overall < 0.95 {
        why.push(format!("overall accuracy {:.3} < 0.95", m.overall));
    }
    if m.false_alarms > 0.05 {
        why.push(format!("false alarms on none {:.3} > 0.05", m.false_alarms));
    }
    for &(k, right, n) in &m.per_effect {
        if n > 0 && (right as f64) < 0.85 * n as f64 {
            why.push(format!("{k}: {right}/{n} < 85 %"));
        }
    }
    if m.parameter_ok < 0.90 {
        why.push(format!(
            "parameter within 25 % for {:.3} < 0.90 of correct calls",
            m.parameter_ok
        ));
    }
    why
}

fn confusion_matrix(calls: &[(Effect, Effect)]) -> String {
    let short = |k: EffectKind| -> String { k.name().chars().take(6).collect() };
    let mut s = format!("{:>20} |", "truth \\ diagnosis");
    for k in EffectKind::ALL {
        s += &format!(" {:>6}", short(k));
    }
    s += " | accuracy\n";
    for t in EffectKind::ALL {
        s += &format!("{:>20} |", t.name());
        let mut n = 0;
        let mut right = 0;
        for f in EffectKind::ALL {
            let c = calls
                .iter()
                .filter(|(a, b)| a.kind == t && b.kind == f)
                .count();
            n += c;
            if f == t {
                right = c;
            }
            s += &format!(" {:>6}", if c == 0 { ".".into() } else { c.to_string() });
        }
        s += &format!(" | {right}/{n}\n");
    }
    s
}

#[test]
fn diagnose_names_the_hidden_effect() {
    let out = outcomes();
    let calls: Vec<(Effect, Effect)> = out.iter().map(|o| (o.truth, o.found)).collect();
    let m = metrics(&calls);
    println!("{}", confusion_matrix(&calls));
    println!(
        "overall {:.3}, false alarms on none {:.3}, parameter within 25 % for {:.3} of correct calls",
        m.overall, m.false_alarms, m.parameter_ok
    );
    for o in out {
        let wrong = o.truth.kind != o.found.kind;
        let bad_param =
            !wrong && o.truth.kind != EffectKind::None && !parameter_ok(o.truth, o.found);
        if wrong || bad_param {
            println!(
                "{} {} -> {}={:.4e} | {} | {}",
                if wrong { "MISS " } else { "PARAM" },
                o.truth.kind,
                o.found.kind,
                o.found.value,
                o.describe,
                o.candidates
            );
        }
    }
    let rows: usize = out.iter().map(|o| o.rows).sum();
    let secs: f64 = out.iter().map(|o| o.elapsed_s).sum();
    let slowest = out
        .iter()
        .max_by(|a, b| (a.elapsed_s / a.rows as f64).total_cmp(&(b.elapsed_s / b.rows as f64)))
        .unwrap();
    println!(
        "diagnose: {:.1} ms per 1000 rows on average ({} rows in all); slowest {:.1} ms for {} rows",
        1e3 * secs / rows as f64 * 1000.0,
        rows,
        1e3 * slowest.elapsed_s,
        slowest.rows
    );
    let why = failures(&m);
    assert!(why.is_empty(), "{}", why.join("; "));
}

/// The assertions are not met by a diagnosis that does not look at the data.
#[test]
fn a_constant_or_random_diagnosis_fails_the_same_assertions() {
    let out = outcomes();
    let truths: Vec<Effect> = out.iter().map(|o| o.truth).collect();
    for guess in EffectKind::ALL {
        let calls: Vec<(Effect, Effect)> = truths
            .iter()
            .map(|&t| {
                // Even a constant guesser that happens to guess right gets the value right.
                let value = if t.kind == guess { t.value } else { 0.5 };
                (t, Effect { kind: guess, value })
            })
            .collect();
        let why = failures(&metrics(&calls));
        assert!(!why.is_empty(), "constant {guess} passes");
    }
    // A seeded random guesser (uniform over the catalogue), with the true value when right.
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let calls: Vec<(Effect, Effect)> = truths
        .iter()
        .map(|&t| {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            let kind = EffectKind::ALL[(state >> 33) as usize % EffectKind::ALL.len()];
            let value = if kind == t.kind { t.value } else { 0.5 };
            (t, Effect { kind, value })
        })
        .collect();
    let m = metrics(&calls);
    let why = failures(&m);
    assert!(!why.is_empty(), "a random guesser passes: {m:?}");
    assert!(m.overall < 0.3, "{m:?}");
}
