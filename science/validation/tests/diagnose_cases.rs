//! `capstan diagnose` against effects hidden the way the rig would hide them.
//!
//! Every case is a data set made end to end by the firmware-in-the-loop simulator (`host-sim`:
//! the firmware's protocol, sampling and conditioning against the plant) with the thesis rig's
//! noise — cord-to-cord and run-to-run scatter of mu, a slow wander of mu inside runs, a zero
//! error per run, sensor noise and the ADC — and a planted truth: nothing, one catalogue effect
//! (at a size that matters, or small), two at once, or physics outside the catalogue that only
//! the plant knows (`capstan_validation::cases`). The thresholds were calibrated on seed 99
//! (`cargo run --release --example calibrate -- 99 --grid`); this test asserts on another.
//!
//! * `cargo test` runs a fixed slice: every 6th case of the test seed (53 cases);
//! * `CAPSTAN_CASES=full cargo test --release --test diagnose_cases -- --nocapture` runs all
//!   317 cases and asserts the targets of `capstan_validation::score` (`.ci/run` does this);
//! * `CAPSTAN_DIAGNOSE_SEED=N` draws the cases from another master seed.

use capstan_physics::{Effect, EffectKind};
use capstan_validation::cases::{self, Case, Class};
use capstan_validation::score::{self, Metrics, Outcome};
use std::sync::OnceLock;

/// Seed of the test cases (the thresholds were calibrated on seed 99).
const MASTER_SEED: u64 = 20_260_522;
/// The slice `cargo test` runs: every this-many-th case.
const SLICE: usize = 6;

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

fn full() -> bool {
    std::env::var("CAPSTAN_CASES").is_ok_and(|v| v == "full")
}

fn the_cases() -> Vec<Case> {
    let every = if full() { 1 } else { SLICE };
    cases::draw_cases(master_seed())
        .into_iter()
        .enumerate()
        .filter(|(i, _)| i % every == 0)
        .map(|x| x.1)
        .collect()
}

fn outcomes() -> &'static [Outcome] {
    static CELL: OnceLock<Vec<Outcome>> = OnceLock::new();
    CELL.get_or_init(|| {
        let cs = the_cases();
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
        let t0 = std::time::Instant::now();
        let out = score::run(&cs, threads, capstan_engine::diagnose::diagnose)
            .unwrap_or_else(|e| panic!("{e}"));
        eprintln!(
            "master seed {}: {} cases simulated and diagnosed in {:.1} s on {threads} threads",
            master_seed(),
            out.len(),
            t0.elapsed().as_secs_f64()
        );
        out
    })
}

#[test]
fn diagnose_names_what_was_planted_and_flags_what_it_cannot_name() {
    let out = outcomes();
    let m = Metrics::of(out);
    println!("{}", m.table());
    for class in [Class::Single, Class::SmallSingle] {
        let pe: Vec<String> = score::per_effect(out, class)
            .iter()
            .filter(|x| x.2 > 0)
            .map(|(k, a, b)| format!("{}:{a}/{b}", k.name()))
            .collect();
        println!("{}: {}", class.name(), pe.join(" "));
    }
    for o in out.iter().filter(|o| !o.correct()) {
        let found: Vec<String> = o
            .found
            .iter()
            .map(|e| format!("{}={:.4}", e.kind, e.value))
            .collect();
        println!(
            "MISS {} -> {found:?} unexplained={} | {}",
            o.describe, o.unexplained, o.candidates
        );
    }
    let rows: usize = out.iter().map(|o| o.rows).sum();
    let secs: f64 = out.iter().map(|o| o.elapsed_s).sum();
    println!(
        "diagnose: {:.1} ms per 1000 rows on average",
        1e3 * secs / rows as f64 * 1000.0
    );
    if full() {
        // On the test seed, the issue's targets (≥ 90 % single with ≥ 90 % of their parameters
        // within 25 %, ≥ 75 % pairs, ≥ 80 % outside, ≤ 5 % clean): the thresholds were
        // calibrated on seed 99 and are judged here on cases they never saw. On any seed
        // (`CAPSTAN_DIAGNOSE_SEED`), the line the three seeds measured all clear: single
        // effects reach 87.3-91.8 % there (the fresh seed 2718281828 is the low one), pairs
        // 78.8-80.3 %, outside 91.7-100 %, clean 0-5 % (docs/README-diagnose.md), and the
        // rivals: 5.9-8.1 % of right calls carry one, 75-100 % of the calls of one effect in
        // place of another report the planted effect as its rival.
        let mut why = m.failures_against(&score::Targets::MEASURED);
        if master_seed() == MASTER_SEED {
            why.extend(m.failures_against(&score::Targets::ISSUE));
        }
        assert!(why.is_empty(), "{}", why.join("; "));
    } else {
        // The slice has too few cases per class for the targets' percentages; it asserts the
        // same behaviour in aggregate, and never a false alarm on a clean set.
        let named = |x: (usize, usize)| x.0;
        let total = |x: (usize, usize)| x.1;
        let right = named(m.single) + named(m.pairs) + named(m.outside);
        let all = total(m.single) + total(m.pairs) + total(m.outside);
        assert!(
            right as f64 >= 0.8 * all as f64,
            "{right}/{all} single, pair and outside cases right (slice)"
        );
        assert_eq!(m.clean_alarms.0, 0, "false alarms on clean sets");
    }
}

/// The assertions are not met by answers that do not look at the data.
#[test]
fn a_constant_or_random_answer_fails_the_same_assertions() {
    let out = outcomes();
    let with = |o: &Outcome, found: Vec<Effect>, unexplained: bool| Outcome {
        found,
        unexplained,
        ..o.clone()
    };
    // Always "none"; always "unexplained"; always one effect (with its true value when right).
    let mut answers: Vec<Vec<Outcome>> = vec![
        out.iter().map(|o| with(o, Vec::new(), false)).collect(),
        out.iter().map(|o| with(o, Vec::new(), true)).collect(),
    ];
    for k in EffectKind::ALL.into_iter().skip(1) {
        answers.push(
            out.iter()
                .map(|o| {
                    let value = o
                        .truth
                        .iter()
                        .find(|t| t.kind == k)
                        .map_or(0.5, |t| t.value);
                    with(o, vec![Effect { kind: k, value }], false)
                })
                .collect(),
        );
    }
    // A seeded random guesser over none, one effect, two effects and unexplained.
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 33) as usize
    };
    answers.push(
        out.iter()
            .map(|o| {
                let pick = |r: usize| EffectKind::ALL[1 + r % (EffectKind::ALL.len() - 1)];
                let value = |k: EffectKind| {
                    o.truth
                        .iter()
                        .find(|t| t.kind == k)
                        .map_or(0.5, |t| t.value)
                };
                match next() % 4 {
                    0 => with(o, Vec::new(), false),
                    1 => with(o, Vec::new(), true),
                    2 => {
                        let k = pick(next());
                        with(
                            o,
                            vec![Effect {
                                kind: k,
                                value: value(k),
                            }],
                            false,
                        )
                    }
                    _ => {
                        let (a, b) = (pick(next()), pick(next()));
                        let found = vec![
                            Effect {
                                kind: a,
                                value: value(a),
                            },
                            Effect {
                                kind: b,
                                value: value(b),
                            },
                        ];
                        with(o, found, false)
                    }
                }
            })
            .collect(),
    );
    for (i, a) in answers.iter().enumerate() {
        let m = Metrics::of(a);
        assert!(!m.failures().is_empty(), "answer {i} passes: {m:?}");
    }
}
