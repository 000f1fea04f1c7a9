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

/// The report's claim that the extended model's residuals still trend (Holm-adjusted p < 0.05
/// over its cord-clustered slope tests, `capstan_report::trends`) fires on thesis-design
/// campaigns with no trend planted at about its nominal 5 %: 4/100 on the calibration seed (11)
/// and 7/100 on this one, where the smallest unadjusted p is below 0.05 in 26 and 35 of 100
/// (most claims are ln(T2/T1) against T1: docs/README-analysis.md says why). Asserted: the claim
/// rate's Wilson interval reaches down to 5 % (a rule that over-claims, such as the unadjusted
/// p, fails), on 100 campaigns under `CAPSTAN_CORDS=full` (about 1 minute in release on 2
/// cores); the fixed slice claims no trend on one campaign.
#[test]
fn a_residual_trend_is_claimed_at_its_size_on_nulls() {
    use capstan_validation::cord_calibration::{residual_trend_p, wilson};
    let n = if full() { 100 } else { 1 };
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get());
    let p = residual_trend_p(&CordCase::many(Truth::Null, ASSERT_SEED, n), threads)
        .expect("every campaign simulates and analyses");
    let claimed = p.iter().filter(|x| x.1 < 0.05).count();
    let raw = p.iter().filter(|x| x.0 < 0.05).count();
    eprintln!("null campaigns: a residual trend claimed (Holm) {claimed}/{n}; smallest p < 0.05 unadjusted {raw}/{n}");
    assert!(p.iter().all(|x| x.1 >= x.0), "{p:?}");
    match full() {
        true => assert!(wilson(claimed, n).0 <= 0.05, "{claimed}/{n}"),
        false => assert_eq!(claimed, 0, "{p:?}"),
    }
}
