//! `capstan diagnose`: the command line, the JSON object, effects whose column is absent, and
//! the thesis data.

use capstan::data::{thesis_dataset, write_pairs};
use capstan::diagnose::{self, cases, Options};
use capstan_friction::EffectKind;
use std::process::Command;

fn capstan() -> Command {
    Command::new(env!("CARGO_BIN_EXE_capstan"))
}

fn tmp(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("capstan-diagnose-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// A generated wear case, written as CSV, diagnosed through the binary with `--json`.
#[test]
fn json_object_has_the_documented_fields() {
    let case = cases::draw_case(7, EffectKind::Wear, 0);
    let (data, _) = case.generate().unwrap();
    let path = tmp("wear.csv");
    write_pairs(&path, &data.pairs).unwrap();
    let out = capstan()
        .args(["diagnose", path.to_str().unwrap(), "--json"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["effect"], "wear", "{v}");
    let w = v["parameters"]["mu_change_per_run"].as_f64().unwrap();
    assert!(
        ((w - case.effect.value) / case.effect.value).abs() < 0.25,
        "{w} vs {}",
        case.effect.value
    );
    let cands = v["candidates"].as_array().unwrap();
    assert_eq!(cands[0]["effect"], "wear");
    let dbic: Vec<f64> = cands
        .iter()
        .map(|c| c["delta_bic"].as_f64().unwrap())
        .collect();
    assert!(
        dbic.windows(2).all(|w| w[0] <= w[1]),
        "best first: {dbic:?}"
    );
    for c in cands {
        assert!(c["parameters"].is_object());
    }
    assert!(v["baseline"]["mu"].as_f64().unwrap() > 0.05);
    assert!(v["baseline"]["rmse_t2_n"].as_f64().unwrap() > 0.0);
    assert!(
        v["extended"]["rmse_t2_n"].as_f64().unwrap()
            <= v["baseline"]["rmse_t2_n"].as_f64().unwrap()
    );
    assert!(v["elapsed_s"].as_f64().unwrap() < 5.0);

    // The human summary names the effect and the evidence.
    let out = capstan()
        .args(["diagnose", path.to_str().unwrap()])
        .output()
        .unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("diagnosis: wear"), "{text}");
    assert!(text.contains("ΔBIC"), "{text}");
}

/// An effect whose column is absent is reported as not testable, and not guessed.
#[test]
fn an_effect_whose_column_is_absent_is_not_testable() {
    // Thermal drift hidden, `time_s` dropped: not testable, and not named.
    let mut case = cases::draw_case(11, EffectKind::ThermalDrift, 1);
    case.drop_columns = vec!["time_s"];
    let (data, _) = case.generate().unwrap();
    assert!(!data.has_column("time_s"));
    let d = diagnose::diagnose(&data);
    assert_ne!(d.kind, EffectKind::ThermalDrift);
    assert!(d.candidate(EffectKind::ThermalDrift).is_none());
    assert!(
        d.not_testable
            .iter()
            .any(|n| n.effect == "thermal_drift" && n.reason.contains("time_s")),
        "{:?}",
        d.not_testable
    );
    // Wear hidden, `run` and `drive_v` dropped: wear and speed are not testable.
    let mut case = cases::draw_case(11, EffectKind::Wear, 2);
    case.drop_columns = vec!["run", "drive_v"];
    let (data, _) = case.generate().unwrap();
    let d = diagnose::diagnose(&data);
    assert_ne!(d.kind, EffectKind::Wear);
    for (effect, col) in [("wear", "run"), ("speed_dependence", "drive_v")] {
        assert!(
            d.not_testable
                .iter()
                .any(|n| n.effect == effect && n.reason.contains(col)),
            "{effect}: {:?}",
            d.not_testable
        );
    }
    // A pressure effect is still found without the optional columns it does not need.
    let mut case = cases::draw_case(11, EffectKind::PressureFriction, 3);
    case.drop_columns = vec!["time_s", "drive_v", "capstan_diameter_mm"];
    let (data, _) = case.generate().unwrap();
    let d = diagnose::diagnose(&data);
    assert_eq!(d.kind, EffectKind::PressureFriction, "{}", case.describe());
    for effect in ["bending_stiffness", "diameter_dependence", "thermal_drift"] {
        assert!(
            d.not_testable.iter().any(|n| n.effect == effect),
            "{effect}"
        );
    }
}

/// Bad input is reported with its place, not diagnosed.
#[test]
fn bad_input_fails_with_a_located_error() {
    let path = tmp("bad.csv");
    std::fs::write(&path, "wrap_deg,t1_n,t2_n\n270,1,2\n270,x,3\n").unwrap();
    let out = capstan()
        .args(["diagnose", path.to_str().unwrap(), "--json"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.csv:3:2"), "{err}");
}

/// The thesis data: no `time_s`, one voltage; the call is stable and documented in
/// `docs/diagnose-thesis.json`.
#[test]
fn thesis_data_diagnosis() {
    let data = thesis_dataset();
    let d = diagnose::diagnose(&data);
    let names: Vec<&str> = d.not_testable.iter().map(|n| n.effect).collect();
    assert!(names.contains(&"thermal_drift"), "{names:?}");
    assert!(names.contains(&"speed_dependence"), "{names:?}");
    assert_ne!(d.kind, EffectKind::None, "{}", d.to_json());
    // With the protocol's step times, drift becomes testable.
    let d2 = diagnose::diagnose_with(
        &data,
        &Options {
            protocol_times: true,
            ..Options::default()
        },
    );
    assert!(d2.candidate(EffectKind::ThermalDrift).is_some());
}
