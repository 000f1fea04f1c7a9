//! `capstan diagnose` and `capstan analyze` on any data set the reader accepts: no panic, no
//! hang, and an answer whose numbers are finite or explicitly absent.
//!
//! Data sets are drawn at random (proptest): 0-60 rows, wraps from a handful of values or any
//! within the reader's range, tensions anywhere in ±10 kN including zero, negative and T2 < T1,
//! duplicates, optional columns present or not, runs and steps repeated or out of order. What
//! the reader refuses is not diagnosed (its errors have their own tests); what it accepts must
//! come back with an answer. `PROPTEST_CASES=N` draws more (default 40 for diagnose, 8 for analyze).

use capstan::data::{check_capstan_data, read_pairs, Dataset};
use capstan::diagnose::diagnose;
use proptest::prelude::*;

fn cases(default: u32) -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
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

/// One row's cells: wrap, T1, T2, diameter, drive, run, step, time.
type Row = (f64, f64, f64, f64, f64, f64, f64, f64);

fn row() -> impl Strategy<Value = Row> {
    (
        prop_oneof![
            4 => prop::sample::select(vec![270.0, 360.0, 450.0, 630.0, 720.0]),
            1 => 0.001..3600.0f64,
        ],
        tension(),
        tension(),
        prop::sample::select(vec![12.7, 19.05, 25.4, 0.5, 999.0]),
        prop::sample::select(vec![6.0, 10.0, 12.0, -3.0, 0.0]),
        prop::sample::select(vec![1.0, 2.0, 3.0, 1.0e6]),
        0.0..14.0f64,
        prop_oneof![3 => 0.0..100.0f64, 1 => -1e9..1e9f64],
    )
}

/// Which optional columns the CSV has: diameter, drive, run, step, time.
fn columns() -> impl Strategy<Value = [bool; 5]> {
    prop::array::uniform5(any::<bool>())
}

fn csv(rows: &[Row], cols: [bool; 5]) -> String {
    let names = ["capstan_diameter_mm", "drive_v", "run", "step", "time_s"];
    let mut s = String::from("wrap_deg,t1_n,t2_n");
    for (name, on) in names.iter().zip(cols) {
        if on {
            s += &format!(",{name}");
        }
    }
    s.push('\n');
    for r in rows {
        s += &format!("{},{},{}", r.0, r.1, r.2);
        let opt = [r.3, r.4, r.5, r.6.floor(), r.7];
        for (v, on) in opt.iter().zip(cols) {
            if on {
                s += &format!(",{v}");
            }
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

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(40), ..ProptestConfig::default() })]

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
            // The JSON object is valid JSON (non-finite numbers become null).
            prop_assert!(serde_json::from_str::<serde_json::Value>(&a.to_json()).is_ok());
        }
    }
}

proptest! {
    // Each analysis fits every model with leave-one-cord-out folds: fewer cases by default.
    #![proptest_config(ProptestConfig { cases: cases(8), ..ProptestConfig::default() })]

    #[test]
    fn analyze_answers_or_refuses_any_accepted_data_set(
        rows in prop::collection::vec(row(), 0..40),
        cols in columns(),
    ) {
        let text = csv(&rows, cols);
        if let Some(d) = accepted(&text) {
            let opts = capstan::analysis::Options { threads: 1 };
            // Too few rows is a clear refusal; anything else must come back analysed.
            match capstan::analysis::run(&d, opts) {
                Ok(a) => prop_assert!(a.mechanisms.tests.len() == 10),
                Err(e) => prop_assert!(e.to_string().contains("too few"), "{e}"),
            }
        }
    }
}
