//! `capstan diagnose` and `capstan analyze` on any data set the reader accepts: no panic, no
//! hang, the same cords and runs in both (one data model), and no inf or NaN in a verdict,
//! a sentence, the report or the printed summary (a number that cannot be computed is said to
//! be "not identified", or is null in JSON).
//!
//! Data sets are drawn at random (proptest): 0-60 rows, wraps from a handful of values or any
//! within the reader's range, tensions mostly rig-like (T2 an amplified T1) but anywhere in
//! ±10 kN at times, including zero, negative, 1e-300 and T2 < T1; optional columns present or
//! not, runs and steps repeated or out of order, a label column. What the reader refuses is not
//! analysed (its errors have their own tests); what it accepts must come back with an answer.
//!
//! Reproducible and bounded: a fixed seed (`PROPTEST_RNG_SEED` is ignored), failures persisted
//! next to this file (`diagnose_any_input.proptest-regressions`, replayed first), shrinking
//! stopped after 60 s, and every analysis bounded by the fits' budgets.
//! `PROPTEST_CASES=N` draws more (default 40 for diagnose, 8 for analyze).

use capstan_data::{check_capstan_data, read_pairs, Dataset};
use capstan_engine::diagnose::diagnose;
use proptest::prelude::*;
use proptest::test_runner::{FileFailurePersistence, RngSeed};

fn config(default_cases: u32, seed: u64) -> ProptestConfig {
    let cases = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default_cases);
    ProptestConfig {
        cases,
        rng_seed: RngSeed::Fixed(seed),
        failure_persistence: Some(Box::new(FileFailurePersistence::WithSource(
            "proptest-regressions",
        ))),
        max_shrink_time: 60_000,
        max_shrink_iters: 2_000,
        ..ProptestConfig::default()
    }
}

/// A tension: mostly rig-like, sometimes at the edges of what a reading can be.
fn tension() -> impl Strategy<Value = f64> {
    prop_oneof![
        6 => -2.0..60.0f64,
        1 => Just(0.0),
        1 => -10_000.0..10_000.0f64,
        1 => prop::sample::select(vec![1e-300, -1e-300, 1e-9, 9_999.999, -9_999.999]),
    ]
}

/// One row's cells: wrap, T1, T2 (as an amplification of T1, or a tension of its own),
/// diameter, drive, run, step, time, label.
type Row = (f64, f64, (bool, f64), f64, f64, f64, f64, f64, u8);

fn row() -> impl Strategy<Value = Row> {
    (
        prop_oneof![
            4 => prop::sample::select(vec![270.0, 360.0, 450.0, 630.0, 720.0]),
            1 => 0.001..3600.0f64,
        ],
        tension(),
        prop_oneof![3 => (Just(true), 1.0..8.0f64), 1 => (Just(false), -10_000.0..10_000.0f64), 1 => tension().prop_map(|t| (false, t))],
        prop::sample::select(vec![12.7, 19.05, 25.4, 0.5, 999.0]),
        prop::sample::select(vec![6.0, 10.0, 12.0, -3.0, 0.0]),
        prop::sample::select(vec![1.0, 2.0, 3.0, 1.0e6]),
        0.0..14.0f64,
        prop_oneof![3 => 0.0..100.0f64, 1 => -1e9..1e9f64],
        0..3u8,
    )
}

/// Which optional columns the CSV has: diameter, drive, run, step, time, material.
fn columns() -> impl Strategy<Value = [bool; 6]> {
    prop::array::uniform6(any::<bool>())
}

fn csv(rows: &[Row], cols: [bool; 6]) -> String {
    let names = [
        "capstan_diameter_mm",
        "drive_v",
        "run",
        "step",
        "time_s",
        "material",
    ];
    let mut s = String::from("wrap_deg,t1_n,t2_n");
    for (name, on) in names.iter().zip(cols) {
        if on {
            s += &format!(",{name}");
        }
    }
    s.push('\n');
    for r in rows {
        let t2 = match r.2 {
            (true, amp) => (r.1 * amp).clamp(-9_999.0, 9_999.0),
            (false, t) => t,
        };
        s += &format!("{},{},{}", r.0, r.1, t2);
        let opt = [r.3, r.4, r.5, r.6.floor(), r.7];
        for (v, on) in opt.iter().zip(cols) {
            if on {
                s += &format!(",{v}");
            }
        }
        if cols[5] {
            s += [",nylon", ",\"polyester, braided\"", ","][r.8 as usize];
        }
        s.push('\n');
    }
    s
}

fn accepted(text: &str) -> Option<Dataset> {
    let d = read_pairs(text.as_bytes(), "random.csv").ok()?;
    check_capstan_data(&d).ok()?;
    Some(d)
}

/// `inf`, `-inf` or `NaN` as a word of `text` (not inside "information" or "infinite").
fn non_finite_word(text: &str) -> Option<String> {
    let b = text.as_bytes();
    for word in ["inf", "NaN"] {
        let mut from = 0;
        while let Some(k) = text[from..].find(word) {
            let at = from + k;
            let end = at + word.len();
            let before = at.checked_sub(1).map(|i| b[i]);
            let after = b.get(end).copied();
            let letter = |c: Option<u8>| c.is_some_and(|c| c.is_ascii_alphanumeric() || c == b'_');
            if !letter(before) && !letter(after) {
                let mut lo = at.saturating_sub(60);
                while !text.is_char_boundary(lo) {
                    lo -= 1;
                }
                let mut hi = (end + 60).min(text.len());
                while !text.is_char_boundary(hi) {
                    hi += 1;
                }
                return Some(text[lo..hi].to_string());
            }
            from = end;
        }
    }
    None
}

proptest! {
    #![proptest_config(config(40, 0x0023_d1a6))]

    #[test]
    fn diagnose_answers_any_accepted_data_set(
        rows in prop::collection::vec(row(), 0..60),
        cols in columns(),
    ) {
        let text = csv(&rows, cols);
        if let Some(d) = accepted(&text) {
            let a = diagnose(&d);
            prop_assert!(!a.verdict.is_empty());
            prop_assert_eq!(a.effects.is_empty(), a.effect == "none", "{}", a.to_json());
            for e in &a.effects {
                prop_assert!(e.delta_bic_given_others.is_finite(), "{}", a.to_json());
                prop_assert!(e.parameters.values().all(|v| v.is_finite()), "{}", a.to_json());
            }
            for r in &a.rivals {
                prop_assert!(r.delta_bic.is_finite(), "{}", a.to_json());
                prop_assert!(a.effects.iter().any(|e| e.effect == r.instead_of));
            }
            // One data model: the structure the reader found is the one diagnosed.
            prop_assert_eq!(a.design.cords, d.structure.cords.len());
            prop_assert_eq!(a.design.runs, d.structure.run_cord.len());
            // No inf or NaN in what a user reads.
            let summary = capstan::cli::diagnose::summary(&a, &d.source);
            prop_assert!(non_finite_word(&summary).is_none(), "{:?}\n{}", non_finite_word(&summary), summary);
            // The JSON object is valid JSON (a number that is not finite is null).
            prop_assert!(serde_json::from_str::<serde_json::Value>(&a.to_json()).is_ok());
        }
    }
}

proptest! {
    // Each analysis fits every model with leave-one-cord-out folds: fewer cases by default.
    #![proptest_config(config(8, 0x0023_a7a1))]

    #[test]
    fn analyze_and_diagnose_agree_on_any_accepted_data_set(
        rows in prop::collection::vec(row(), 0..60),
        cols in columns(),
    ) {
        let text = csv(&rows, cols);
        if let Some(d) = accepted(&text) {
            let opts = capstan_engine::analysis::Options { threads: 1, ..Default::default() };
            // Too few rows is a clear refusal; anything else must come back analysed.
            match capstan_engine::analysis::run(&d, opts) {
                Ok(a) => {
                    prop_assert!(a.mechanisms.tests.len() == capstan_physics::EffectKind::ALL.len() - 1);
                    // The same cords and runs as diagnose.
                    prop_assert_eq!(a.obs.groups.len(), a.evidence.design.cords);
                    prop_assert_eq!(a.obs.runs.len(), a.evidence.design.runs);
                    let html = capstan_report::report_html(&a, None, "", &capstan_report::Context::library()).unwrap().0;
                    prop_assert!(non_finite_word(&html).is_none(), "{:?}", non_finite_word(&html));
                    let words = serde_json::to_string(&a.mechanisms).unwrap();
                    prop_assert!(non_finite_word(&words).is_none(), "{:?}", non_finite_word(&words));
                }
                Err(e) => prop_assert!(e.to_string().contains("too few"), "{e}"),
            }
        }
    }
}
