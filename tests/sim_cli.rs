//! `capstan simulate` as a user meets it: files, JSON, faults, bad arguments.

use std::path::PathBuf;
use std::process::{Command, Output};

fn capstan(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_capstan"))
        .args(args)
        .output()
        .expect("capstan runs")
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("capstan-sim-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// A short campaign: 3 s steps.
const SHORT: [&str; 6] = [
    "--dwell-ms",
    "3000",
    "--window-after-ms",
    "1000",
    "--window-before-ms",
    "500",
];

#[test]
fn simulate_writes_pairs_raw_logs_and_one_json_object() {
    let out = tmp("json");
    let o = out.to_str().unwrap();
    let mut args = vec![
        "simulate",
        "--out",
        o,
        "--diameters",
        "12.7",
        "--wraps",
        "270,720",
    ];
    args.extend([
        "--runs",
        "2",
        "--json",
        "--seed",
        "77",
        "--effect",
        "t2_offset=-0.5",
    ]);
    args.extend(SHORT);
    let r = capstan(&args);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let stdout = String::from_utf8(r.stdout).unwrap();
    let v: serde_json::Value =
        serde_json::from_str(stdout.trim()).expect("exactly one JSON object");
    assert_eq!(v["runs"], 4);
    assert_eq!(v["pairs"], 48);
    assert!(v["simulated_s"].as_f64().unwrap() > 4.0 * 40.0);
    // Reported, not judged: a wall-clock bound would flake on a busy machine (the benchmark
    // measures speed).
    assert!(v["realtime_factor"].as_f64().unwrap() > 0.0);
    assert!(v["wall_s"].as_f64().unwrap() > 0.0);
    assert_eq!(v["faults"], serde_json::json!([]));
    // Provenance: what made these data, in summary.json as in the printed object.
    let prov = &v["provenance"];
    assert_eq!(prov["seed"], 77);
    assert_eq!(prov["effects"][0]["name"], "t2_offset");
    assert_eq!(prov["effects"][0]["value"], -0.5);
    assert!(prov["noise"]["profile"].is_string() && prov["commit"].is_string());
    // The scatter used, never null: run to run is half the cord-to-cord when not given.
    let cord = prov["noise"]["cord_scatter_pct"].as_f64().unwrap();
    let run = prov["noise"]["run_scatter_pct"].as_f64().unwrap();
    assert!((run - 0.5 * cord).abs() < 1e-12, "{run} {cord}");
    assert!(prov["command_line"].as_str().unwrap().contains("--seed 77"));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["provenance"], *prov);
    // No progress bar when not on a terminal.
    assert!(
        r.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&r.stderr)
    );
    let text = std::fs::read_to_string(out.join("pairs.csv")).unwrap();
    assert_eq!(
        text.lines().next().unwrap(),
        "capstan_diameter_mm,wrap_deg,drive_v,run,step,time_s,t1_n,t2_n"
    );
    let d = capstan_data::load_pairs(&out.join("pairs.csv")).unwrap();
    assert_eq!(d.pairs.len(), 48);
    let p = &d.pairs[0];
    assert_eq!(
        (p.capstan_diameter_mm, p.wrap_deg, p.drive_v),
        (Some(12.7), 270.0, Some(10.0))
    );
    assert_eq!(
        (p.run, p.step, p.time_s),
        (Some(1.0), Some(1.0), Some(5.25))
    );
    let raw = std::fs::read_to_string(out.join("raw/d12.7_w720_v10_run2.csv")).unwrap();
    assert_eq!(
        raw.lines().next().unwrap(),
        "t_s,t1_counts,t2_counts,t1_n,t2_n"
    );
    assert!(raw.lines().count() > 4_000);
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn injected_faults_are_reported_in_json_and_faults_csv() {
    let out = tmp("faults");
    let o = out.to_str().unwrap();
    let mut args = vec![
        "simulate",
        "--out",
        o,
        "--diameters",
        "12.7",
        "--wraps",
        "360",
    ];
    args.extend(["--runs", "4", "--json", "--no-raw"]);
    args.extend([
        "--fault",
        "cord_break@20.2#1",
        "--fault",
        "sensor_unplugged@20.2#2",
    ]);
    args.extend(["--fault", "over_force@20.2#3", "--fault", "abort@20.2#4"]);
    args.extend(SHORT);
    let r = capstan(&args);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let v: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    let faults = v["faults"].as_array().unwrap();
    let names: Vec<&str> = faults
        .iter()
        .map(|f| f["fault"].as_str().unwrap())
        .collect();
    assert_eq!(
        names,
        ["cord_break", "sensor_unplugged", "over_force", "abort"]
    );
    for (k, f) in faults.iter().enumerate() {
        assert_eq!(f["run"], k as u64 + 1);
        assert_eq!(f["at_s"], 20.2);
        let safe = f["safe_after_ms"].as_f64().unwrap();
        assert!(safe <= 20.0, "{f}");
        assert_eq!(f["pairs_kept"], 5, "{f}"); // windows end at 6, 9, 12, 15, 18 s
    }
    assert_eq!(v["pairs"], 20);
    let csv = std::fs::read_to_string(out.join("faults.csv")).unwrap();
    assert_eq!(csv.lines().count(), 5);
    assert!(csv
        .lines()
        .nth(1)
        .unwrap()
        .starts_with("1,12.7,360,10,1,cord_break,cord_break,20.2,"));
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn two_control_writes_the_drive_series_and_the_crosstalk() {
    let out = tmp("two");
    let o = out.to_str().unwrap();
    let mut args = vec!["simulate", "--out", o, "--two-control", "--json"];
    args.extend(SHORT);
    args.extend(["--delays-ms", "0,1500"]);
    let r = capstan(&args);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let v: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    assert_eq!(v["channels"], 2);
    assert_eq!(v["pairs"], 24);
    assert!(v["crosstalk_events"].as_u64().unwrap() > 10);
    assert!(v["worst_t2_crosstalk_rel"].as_f64().unwrap() < 1e-9);
    // Provenance, as a campaign's: what made these data, enough to make them again.
    let prov = &v["provenance"];
    assert!(prov["program"].as_str().unwrap().starts_with("capstan"));
    assert!(prov["commit"].is_string());
    assert!(prov["command_line"]
        .as_str()
        .unwrap()
        .contains("--delays-ms 0,1500"));
    assert_eq!(prov["seed"], 1);
    assert_eq!(prov["mu"], 0.115);
    assert_eq!(prov["effects"], serde_json::json!([]));
    assert_eq!(prov["noise"]["sensor_noise"], true);
    assert_eq!(prov["rig"]["channels"][1]["order"], "pulse");
    assert_eq!(prov["rig"]["channels"][1]["delay_ms"], 1500);
    let series = std::fs::read_to_string(out.join("two_control.csv")).unwrap();
    assert!(series.starts_with("t_s,drive_v,capstan_rpm,current_a,power_w"));
    assert!(out.join("crosstalk.csv").exists() && out.join("pairs_ch2.csv").exists());
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn bad_arguments_are_clear_errors_not_panics() {
    let out = tmp("bad");
    let o = out.to_str().unwrap();
    for (args, want) in [
        (vec!["--effect", "heat=1"], "unknown effect"),
        (vec!["--fault", "melt@3"], "unknown fault"),
        (vec!["--fault", "abort"], "NAME@SECONDS"),
        (vec!["--drive-v", "24"], "13.2"),
        (vec!["--runs", "0"], "runs"),
        (vec!["--wraps", "-5"], "wrap"),
        (vec!["--dwell-ms", "100"], "protocol"),
        // The refusal gives the values in force, the defaults the user did not type too.
        (vec!["--dwell-ms", "100"], "--window-after-ms 2000"),
        (vec!["--scatter", "-3"], "scatter"),
        (
            vec!["--two-control", "--wraps", "720,720,720,720,720"],
            "1 to 4",
        ),
        // A campaign's option given to the two-control rig is refused, never dropped.
        (vec!["--two-control", "--order", "updown"], "use --orders"),
        (vec!["--two-control", "--order", "monotone"], "use --orders"),
        (vec!["--orders", "updown,pulse"], "is for --two-control"),
    ] {
        let mut a = vec!["simulate", "--out", o];
        a.extend(&args);
        let r = capstan(&a);
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(!r.status.success(), "{args:?} succeeded");
        assert!(err.contains(want), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert!(!out.exists(), "{args:?} wrote {o}");
    }
}

#[test]
fn a_campaign_that_makes_no_pair_fails_and_replaces_nothing() {
    let dir = tmp("sim-empty");
    let d = dir.to_str().unwrap();
    let first = capstan(&["simulate", "--out", d, "--runs", "1", "--no-raw"]);
    assert!(first.status.success());
    let pairs = std::fs::read_to_string(dir.join("pairs.csv")).unwrap();
    // A sensor unplugged half a second into every run: every run ends with a fault, no pair
    // is made.
    let o = capstan(&[
        "simulate",
        "--out",
        d,
        "--runs",
        "1",
        "--no-raw",
        "--fault",
        "sensor_unplugged@0.5",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert!(err.contains("no usable pair was made"), "{err}");
    assert!(err.contains("faults.csv"), "{err}");
    assert_eq!(
        std::fs::read_to_string(dir.join("pairs.csv")).unwrap(),
        pairs
    );
    // `none` takes no value; a size no rig holds is refused before anything is simulated
    // (a T2 zero 1e9 N off, a sensor of no gain: the catalogue entry's physical range).
    let o = capstan(&["simulate", "--out", d, "--effect", "none=1"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("takes no value"));
    // And so is a wrap given twice (two cords of one key, which every reader refuses).
    for (flag, value, says) in [
        ("--effect", "t2_offset=1e9", "offset_n must be -3 to 5 N"),
        ("--effect", "sensor_gain=0", "gain must be 0.5 to 2"),
        ("--wraps", "270,360,270", "--wraps 270 is given twice"),
    ] {
        let o = capstan(&["simulate", "--out", d, flag, value]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(says), "{value}: {err}");
    }
    assert_eq!(
        std::fs::read_to_string(dir.join("pairs.csv")).unwrap(),
        pairs
    );
}
