//! `capstan diagnose`: the command line, the JSON object, several effects at once, structure no
//! catalogue effect explains, readings at or below zero, effects whose column is absent, and
//! the thesis data.

use capstan_data::{read_pairs, thesis_dataset, write_pairs, write_pairs_to, Dataset};
use capstan_engine::diagnose::{self, Options};
use capstan_physics::EffectKind;
use capstan_validation::cases::{self, Class};
use std::process::Command;

fn capstan() -> Command {
    Command::new(env!("CARGO_BIN_EXE_capstan"))
}

fn tmp(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("capstan-diagnose-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// The first pair case of a seed is the thesis's two mechanisms: contact heating and a T1-path
/// loss. Diagnosed through the binary with `--json`: both are named, each with its evidence
/// given the other.
#[test]
fn json_object_names_both_effects_with_evidence_given_the_other() {
    let case = cases::draw_case(7, Class::Pair, 0);
    assert_eq!(
        case.truth_kinds(),
        [EffectKind::T1Offset, EffectKind::ContactHeating]
    );
    let (data, _) = case.generate().unwrap();
    let path = tmp("pair.csv");
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
    let effects = v["effects"].as_array().unwrap();
    let mut names: Vec<&str> = effects
        .iter()
        .map(|e| e["effect"].as_str().unwrap())
        .collect();
    names.sort();
    assert_eq!(names, ["contact_heating", "t1_offset"], "{v}");
    assert_eq!(v["unexplained"], false, "{v}");
    // `effect` is the strongest, for scripts that read one name.
    assert_eq!(v["effect"], effects[0]["effect"]);
    for e in effects {
        assert!(e["delta_bic_given_others"].as_f64().unwrap() < -10.0, "{e}");
        assert!(e["parameter_se"].as_f64().unwrap() > 0.0, "{e}");
        let truth = case
            .effects
            .iter()
            .find(|t| t.kind.name() == e["effect"].as_str().unwrap())
            .unwrap();
        let got = e["parameters"][truth.kind.parameter().unwrap()]
            .as_f64()
            .unwrap();
        assert!(
            ((got - truth.value) / truth.value).abs() < 0.25,
            "{}: {got} vs {}",
            truth.kind,
            truth.value
        );
    }
    let cands = v["candidates"].as_array().unwrap();
    assert!(cands.iter().all(|c| c["parameters"].is_object()));
    assert!(
        v["adequacy"]["lack_of_fit"]["p"].as_f64().unwrap() > 1e-3,
        "{v}"
    );
    assert!(v["baseline"]["mu"].as_f64().unwrap() > 0.05);
    assert!(
        v["extended"]["rmse_t2_n"].as_f64().unwrap() < v["baseline"]["rmse_t2_n"].as_f64().unwrap()
    );
    assert_eq!(v["rows_used"]["t2_fits"], data.pairs.len());
    // The human summary says the same.
    let out = capstan()
        .args(["diagnose", path.to_str().unwrap()])
        .output()
        .unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("The data hold"), "{text}");
    assert!(
        text.contains("contact_heating") && text.contains("t1_offset"),
        "{text}"
    );
}

/// A T2 reading that depends on the step direction (hysteresis, outside the catalogue) is
/// reported as unexplained, with the pattern, in JSON and in words.
#[test]
fn structure_outside_the_catalogue_is_unexplained() {
    let mut case = cases::draw_case(7, Class::Outside, 0);
    assert_eq!(case.outside.unwrap().0, "hysteresis");
    case.config.unmodelled.hysteresis = 0.15;
    let (data, _) = case.generate().unwrap();
    let d = diagnose::diagnose(&data);
    assert!(d.unexplained, "{}", d.to_json());
    // In an up-down run the falling steps are the later ones: what is left shows as the step
    // direction, or as time inside the run once a drift has taken part of it.
    let pattern = d.residual_pattern.unwrap_or("none");
    assert!(
        ["step_direction", "time"].contains(&pattern),
        "{pattern}: {}",
        d.to_json()
    );
    assert!(
        d.verdict.starts_with("Unexplained:")
            && d.verdict.contains("no catalogue effect explains it"),
        "{}",
        d.verdict
    );
    let path = tmp("hysteresis.csv");
    write_pairs(&path, &data.pairs).unwrap();
    let out = capstan()
        .args(["diagnose", path.to_str().unwrap()])
        .output()
        .unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains(&format!("UNEXPLAINED ({pattern})")), "{text}");
}

/// Data whose T1 sensor reads 0.3-0.5 N low (a zero offset) have readings at or below zero;
/// they are data: read, used, and the offset is found.
#[test]
fn readings_at_or_below_zero_are_data() {
    let mut case = cases::draw_case(7, Class::Clean, 1);
    case.config.effects = vec![capstan_physics::Effect {
        kind: EffectKind::T1Offset,
        value: -0.4,
    }];
    let (data, _) = case.generate().unwrap();
    let low = data.pairs.iter().filter(|p| p.t1_n <= 0.0).count();
    assert!(low > 0, "the offset pushes some readings below zero");
    // Through the CSV reader: accepted.
    let mut csv = Vec::new();
    write_pairs_to(&mut csv, &data.pairs).unwrap();
    let data: Dataset = read_pairs(csv.as_slice(), "offset.csv").unwrap();
    let d = diagnose::diagnose(&data);
    let e1 = d.candidate(EffectKind::T1Offset).unwrap();
    assert!(e1.selected, "{}", d.to_json());
    assert!((e1.value + 0.4).abs() < 0.1, "{}", e1.value);
    assert_eq!(d.rows_used.t2_fits, data.pairs.len());
    let positive = data
        .pairs
        .iter()
        .filter(|p| p.t1_n > 0.0 && p.t2_n > 0.0)
        .count();
    assert_eq!(d.rows_used.logarithms, positive);
}

/// An effect whose column is absent is reported as not testable, and not guessed.
#[test]
fn an_effect_whose_column_is_absent_is_not_testable() {
    // Thermal drift hidden, `time_s` dropped: not testable, and not named.
    let mut case = cases::draw_case(11, Class::Single, 5);
    assert_eq!(case.truth_kinds(), [EffectKind::ThermalDrift]);
    case.drop_columns = vec!["time_s"];
    let (data, _) = case.generate().unwrap();
    assert!(!data.has_column("time_s"));
    let d = diagnose::diagnose(&data);
    assert!(!d
        .found_effects()
        .iter()
        .any(|e| e.kind == EffectKind::ThermalDrift));
    assert!(d.candidate(EffectKind::ThermalDrift).is_none());
    assert!(
        d.not_testable
            .iter()
            .any(|n| n.effect == "thermal_drift" && n.reason.contains("time_s")),
        "{:?}",
        d.not_testable
    );
    // Wear hidden, `run` dropped: wear is not testable.
    let mut case = cases::draw_case(11, Class::Single, 6);
    assert_eq!(case.truth_kinds(), [EffectKind::Wear]);
    case.drop_columns = vec!["run"];
    let (data, _) = case.generate().unwrap();
    let d = diagnose::diagnose(&data);
    assert!(!d.found_effects().iter().any(|e| e.kind == EffectKind::Wear));
    assert!(
        d.not_testable
            .iter()
            .any(|n| n.effect == "wear" && n.reason.contains("run")),
        "{:?}",
        d.not_testable
    );
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
    let out = capstan()
        .args(["diagnose", "--within-threshold", "nan"])
        .output()
        .unwrap();
    assert!(!out.status.success());
}

/// The thesis data: no `time_s`, one voltage; the answer names both mechanisms the analysis
/// finds, or says why not (documented in `docs/diagnose-thesis.json`).
#[test]
fn thesis_data_diagnosis() {
    let data = thesis_dataset();
    let d = diagnose::diagnose(&data);
    let names: Vec<&str> = d.not_testable.iter().map(|n| n.effect).collect();
    assert!(names.contains(&"thermal_drift"), "{names:?}");
    assert!(names.contains(&"speed_dependence"), "{names:?}");
    assert!(
        d.found_effects()
            .iter()
            .any(|e| e.kind == EffectKind::ContactHeating),
        "{}",
        d.to_json()
    );
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
