//! The one rule for what varies between cords, on planted truths made end to end by the
//! firmware-in-the-loop simulator (`capstan_validation::cord_calibration`): thesis-design campaigns
//! (2 diameters × 5 wraps, 6 runs per cord, monotone steps) whose cords scatter in mu, T2 zero
//! and heating. The rules (`CORD_ALPHA`, the adequacy rule's `alpha_between`) were set on
//! `CALIBRATION_SEED`; the figures are asserted here on `ASSERT_SEED`.
//!
//! `cargo test` runs a fixed slice; `CAPSTAN_CORDS=full cargo test --release -p capstan-validation
//! --test cord_calibration -- --nocapture` runs 100 campaigns per truth (CI, `.ci/run`: about
//! 2 minutes on 2 cores) and prints the figures. The same figures for any seed and count:
//! `cargo run --release -p capstan-validation --example cord_calibration -- 100 2026`.

use capstan_engine::analysis::gain::GainVerdict;
use capstan_validation::cord_calibration::{run, CordFigures, CordOutcome, ASSERT_SEED};
use capstan_validation::cord_cases::{CordCase, Truth};

fn full() -> bool {
    std::env::var("CAPSTAN_CORDS").as_deref() == Ok("full")
}

fn rate((k, n): (usize, usize)) -> f64 {
    k as f64 / n.max(1) as f64
}

fn outcomes(per_truth: &[(Truth, usize)]) -> Vec<CordOutcome> {
    let cases: Vec<CordCase> = per_truth
        .iter()
        .flat_map(|&(t, n)| CordCase::many(t, ASSERT_SEED, n))
        .collect();
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get());
    run(&cases, threads).expect("every campaign simulates")
}

/// Null campaigns get no between-cord claim and gain-null campaigns no established gain in
/// more than 5 %; the power figures are held at what the rule reaches on this seed (a change
/// that loses power fails), and printed against the 80 % (not reached: see
/// docs/README-diagnose.md, "Between cords", for why and how many cords would).
#[test]
fn the_cords_rule_on_planted_truths() {
    if !full() {
        return slice();
    }
    let o = outcomes(&[
        (Truth::Null, 100),
        (Truth::GainNull, 100),
        (Truth::Diameter, 100),
        (Truth::WrapTurn, 100),
    ]);
    let f = CordFigures::of(&o);
    for l in f.lines() {
        eprintln!("{l}");
    }
    assert!(
        rate(f.null_between_claims) <= 0.05,
        "{:?}",
        f.null_between_claims
    );
    assert!(rate(f.gain_null_claims) <= 0.05, "{:?}", f.gain_null_claims);
    assert!(
        rate(f.diameter_found) >= DIAMETER_FOUND,
        "{:?}",
        f.diameter_found
    );
    assert!(rate(f.wrap_found) >= WRAP_FOUND, "{:?}", f.wrap_found);
}

/// What the rule reaches on the asserted seed (44/100 and 12/100 on 2026-11-28), less about
/// two standard errors of sampling.
const DIAMETER_FOUND: f64 = 0.35;
const WRAP_FOUND: f64 = 0.05;

/// The fixed slice: four null campaigns with no between-cord claim, two gain-null ones with no
/// gain established (their whole analyses run), and two with mu 10–15 % apart on the
/// diameters of which the larger change is found.
fn slice() {
    let o = outcomes(&[(Truth::Null, 4), (Truth::GainNull, 2), (Truth::Diameter, 2)]);
    for x in &o {
        eprintln!(
            "{}: named {:?}, unexplained {:?}, gain {:?}",
            x.describe, x.named, x.unexplained, x.gain
        );
    }
    for x in o.iter().filter(|x| x.truth == Truth::Null) {
        assert!(!x.between_claim, "{}: {:?}", x.describe, x.named);
    }
    for x in o.iter().filter(|x| x.truth == Truth::GainNull) {
        assert!(
            x.gain.is_some_and(|g| g != GainVerdict::Established),
            "{}: {:?}",
            x.describe,
            x.gain
        );
    }
    let d: Vec<&CordOutcome> = o.iter().filter(|x| x.truth == Truth::Diameter).collect();
    let big = d
        .iter()
        .max_by(|a, b| a.change.abs().total_cmp(&b.change.abs()))
        .expect("two diameter campaigns");
    assert!(big.diameter_found, "{}: {:?}", big.describe, big.named);
}
