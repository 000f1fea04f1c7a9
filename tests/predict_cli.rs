//! `capstan predict` as a user meets it: one warning per quantity however long the T1 list,
//! negative numbers taken as values and refused by name.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn capstan(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_capstan"))
        .args(args)
        .output()
        .expect("capstan runs")
}

/// `capstan predict --from FROM --wrap-deg WRAP --diameter-mm 20 --t1-n T1` and `more`.
fn predict_at(from: &str, wrap: &str, t1: &str, more: &[&str]) -> Output {
    let mut a = vec![
        "predict",
        "--from",
        from,
        "--wrap-deg",
        wrap,
        "--diameter-mm",
        "20",
        "--t1-n",
        t1,
    ];
    a.extend(more);
    capstan(&a)
}

/// metrics.json of the thesis data, as `capstan analyze` writes it.
fn metrics(dir: &Path) -> PathBuf {
    use capstan_engine::analysis::{self, Options};
    let a = analysis::run(&capstan_data::thesis_dataset(), Options::default()).unwrap();
    let ctx = capstan_report::Context::library();
    let m = serde_json::to_value(capstan_report::Metrics::new(&a, None, &ctx)).unwrap();
    let path = dir.join("metrics.json");
    std::fs::write(&path, serde_json::to_string(&m).unwrap()).unwrap();
    path
}

#[test]
fn a_long_range_warns_once_per_quantity_and_negative_numbers_are_refused_by_name() {
    let dir = std::env::temp_dir().join(format!("capstan-predict-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let m = metrics(&dir);
    let from = m.to_str().unwrap();

    // 1000 T1 values from 0.1 N to 100 N, most outside the thesis's fitted T1, at a wrap and a
    // diameter outside theirs too: one warning for each of the three quantities, and one for
    // each rig limit the T2 passes (the firmware's 45 N over-force, the sensors' 52.5 N).
    let base = ["predict", "--from", from, "--wrap-deg", "900"];
    let mut args = base.to_vec();
    args.extend(["--diameter-mm", "50", "--t1-n", "0.1:100:0.1"]);
    let r = capstan(&args);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let err = String::from_utf8_lossy(&r.stderr);
    let warnings: Vec<&str> = (err.lines())
        .filter(|l| l.starts_with("warning: extrapolating"))
        .collect();
    assert_eq!(warnings.len(), 3, "{err}");
    let t1 = warnings.iter().find(|w| w.contains("T1")).unwrap();
    assert!(
        t1.contains("of 1000 values") && t1.contains("to 100 N"),
        "{t1}"
    );
    assert!(warnings.iter().any(|w| w.contains("wrap 900°")), "{err}");
    assert!(err.contains("over-force limit of 45 N") && err.contains("sensors' range (52.5 N"));
    assert_eq!(err.lines().count(), 5, "{err}");
    // At 50 mm, outside the fitted 12.7–25.4 mm, no held-out cord measured the model's error:
    // the intervals say "not identified", and why, in their own columns.
    let stdout = String::from_utf8_lossy(&r.stdout);
    assert!(
        stdout.contains("intervals not identified: diameter 50 mm"),
        "{stdout}"
    );
    assert_eq!(stdout.matches("not identified").count(), 1 + 2 * 1000);
    assert_eq!(stdout.lines().count(), 3 + 1000);

    // The same in JSON: the warnings once, every prediction in order, the intervals null and
    // each prediction flagged.
    args.push("--json");
    let r = capstan(&args);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let v: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    assert_eq!(v["warnings"].as_array().unwrap().len(), 5);
    assert_eq!(v["extrapolating"], true);
    assert_eq!(v["beyond_rig"], true);
    let preds = v["predictions"].as_array().unwrap();
    assert_eq!(preds.len(), 1000);
    assert!(preds[999]["t2_pi95"].is_null() && preds[999]["t2_ci95"].is_null());
    let flags = &preds[999]["flags"];
    for f in [
        "over_force_limit",
        "sensor_range",
        "t1_outside_fitted",
        "not_identified",
    ] {
        assert!(
            flags.as_array().unwrap().iter().any(|x| x == f),
            "{f}: {flags}"
        );
    }
    assert!(v["not_identified"]
        .as_str()
        .unwrap()
        .contains("diameter 50 mm"));
    assert!(v["new_cord_error"]["abs_n"].as_f64().unwrap() >= 0.0);
    assert!(v["new_cord_error"]["rel"].as_f64().unwrap() > 0.0);
    assert!(v["wrap_extrapolation_error_sd_n"].as_f64().unwrap() >= 0.0);

    // At 20 mm, inside the fitted diameters, the same wrap's interval holds a new cord's error
    // and what extrapolating in wrap cost, and says so.
    let r = predict_at(from, "900", "5", &[]);
    let stdout = String::from_utf8_lossy(&r.stdout);
    assert!(stdout.contains("a new cord's error"), "{stdout}");
    assert!(stdout.contains("extrapolating in wrap cost"), "{stdout}");
    assert!(!stdout.contains("not identified"), "{stdout}");

    // Negative numbers are values, refused with the flag named (`--drive-v -1` and
    // `--drive-v=-1` alike), never a parser's "unexpected argument".
    for (flag, value) in [
        ("--drive-v", "-1"),
        ("--drive-v=-1", ""),
        ("--wrap-deg", "-90"),
        ("--diameter-mm", "-20"),
    ] {
        let mut a = vec!["predict", "--from", from, "--t1-n", "5"];
        for (f, v) in [("--wrap-deg", "540"), ("--diameter-mm", "20")] {
            if !flag.starts_with(f) {
                a.extend([f, v]);
            }
        }
        a.push(flag);
        if !value.is_empty() {
            a.push(value);
        }
        let r = capstan(&a);
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(!r.status.success(), "{flag} {value} was accepted");
        let name = flag.split('=').next().unwrap();
        assert!(
            err.contains(&format!("{name} -")) && !err.contains("unexpected argument"),
            "{flag} {value}: {err}"
        );
    }
    // A huge number is repeated as the user could read it, not as 309 digits.
    for (r, shown) in [
        (predict_at(from, "1e308", "5", &[]), "--wrap-deg 1e308:"),
        (
            predict_at(from, "540", "5,1e300", &[]),
            "1e300 N is not a tension",
        ),
    ] {
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(
            !r.status.success() && err.contains(shown) && err.len() < 200,
            "{err}"
        );
    }
    // An edited model whose numbers give no finite interval, or a physical T2 below T1, is
    // refused by name: never an interval of no width, never "inf" in the table.
    let model: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&m).unwrap()).unwrap();
    for (what, edit) in [
        (
            "a variance of 1e308",
            ("covariance", serde_json::json!(1e308)),
        ),
        (
            "a new cord's error of 1e308",
            ("new_cord_error", serde_json::json!(1e308)),
        ),
        (
            "a negative heating",
            ("heat_per_ns", serde_json::json!(-10.0)),
        ),
        ("an exponent of 1e308", ("n", serde_json::json!(1e308))),
    ] {
        let mut v = model.clone();
        let pm = &mut v["prediction_model"];
        match edit.0 {
            "covariance" => pm["covariance"][0][0] = edit.1,
            "new_cord_error" => pm["new_cord_error"]["rel"] = edit.1,
            name => pm["values"][name] = edit.1,
        }
        let path = dir.join("edited.json");
        std::fs::write(&path, serde_json::to_string(&v).unwrap()).unwrap();
        let r = predict_at(path.to_str().unwrap(), "540", "0.5,5,20", &[]);
        let err = String::from_utf8_lossy(&r.stderr);
        let out = String::from_utf8_lossy(&r.stdout);
        assert!(!r.status.success(), "{what} was accepted: {out}");
        assert!(
            err.contains("edited?") && !out.contains("inf"),
            "{what}: {err}"
        );
    }
    // The interval of a query inside the fitted data carries no warning.
    let r = predict_at(from, "540", "5", &["--drive-v=10"]);
    assert!(r.status.success() && r.stderr.is_empty());
    let _ = std::fs::remove_dir_all(&dir);
}

/// One run per cord: a new cord's error still comes from the held-out cords (run-to-run and
/// cord-to-cord scatter are both in their residuals), and `predict` gives its interval with it.
#[test]
fn predict_with_one_run_per_cord_takes_a_new_cords_error_from_held_out_cords() {
    use capstan_engine::analysis::{self, Options};
    let dir = std::env::temp_dir().join(format!("capstan-predict-run1-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut lines = capstan_data::THESIS_CSV.lines();
    let mut text = format!("{}\n", lines.next().unwrap());
    for l in lines.filter(|l| l.split(',').nth(3) == Some("1")) {
        text += &format!("{l}\n");
    }
    let data = capstan_data::read_pairs(text.as_bytes(), "run1.csv").unwrap();
    let a = analysis::run(&data, Options::default()).unwrap();
    let ctx = capstan_report::Context::library();
    let m = serde_json::to_value(capstan_report::Metrics::new(&a, None, &ctx)).unwrap();
    let path = dir.join("metrics.json");
    std::fs::write(&path, serde_json::to_string(&m).unwrap()).unwrap();
    let o = predict_at(path.to_str().unwrap(), "450", "2", &["--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let e = &v["new_cord_error"];
    assert_eq!(e["cords"], 10);
    assert_eq!(e["rows"], 120);
    // At T2 ≈ 6 N a new cord's SD is the held-out cords' (≈ 0.8–1.5 N on these data), never
    // 0: the interval is more than a second wide on each side.
    let p = &v["predictions"][0];
    let half = (p["t2_pi95"]["hi"].as_f64().unwrap() - p["t2_pi95"]["lo"].as_f64().unwrap()) / 2.0;
    assert!(half > 1.0 && half < 6.0, "{half}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--from DIR` reads DIR/metrics.json (it said "Is a directory"); as measured, a T2
/// reading below zero at a small T1 gives no amplification (it printed −4.3): a dash, null in
/// JSON, and a warning that says why; the JSON carries the provenance.
#[test]
fn from_a_directory_and_no_amplification_from_readings_below_zero() {
    let dir = std::env::temp_dir().join(format!("capstan-predict-dir-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    metrics(&dir);
    let d = dir.to_str().unwrap();
    let o = predict_at(d, "360", "0.1,5", &["--as-measured", "--json"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let p = v["predictions"].as_array().unwrap();
    assert!(p[0]["t2_n"].as_f64().unwrap() < 0.0, "{v}");
    assert!(p[0]["amplification"].is_null(), "{v}");
    assert!(p[1]["amplification"].as_f64().unwrap() > 1.0, "{v}");
    assert_eq!(
        v["provenance"]["program"],
        format!("capstan {}", env!("CARGO_PKG_VERSION"))
    );
    assert_eq!(v["provenance"]["input_sha256"].as_str().unwrap().len(), 64);
    let o = predict_at(d, "360", "0.1", &["--as-measured"]);
    let out = String::from_utf8_lossy(&o.stdout);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(out.contains(" — ") && !out.contains("-4."), "{out}");
    assert!(err.contains("no amplification"), "{err}");
    // A directory without metrics.json: said what to give.
    let empty = dir.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let o = predict_at(empty.to_str().unwrap(), "360", "1", &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("a directory without metrics.json"),
        "{err}"
    );
}

/// `capstan predict --t2-n`: the T1 a wanted T2 needs, read back by the forward command (a
/// round trip within 1e-6 N), its intervals, the rig's limits, and a drive the rig cannot run
/// refused.
#[test]
fn predict_backwards_gives_the_t1_a_wanted_t2_needs() {
    let dir = std::env::temp_dir().join(format!("capstan-predict-t2-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let m = metrics(&dir);
    let from = m.to_str().unwrap();
    let json = |args: &[&str]| -> serde_json::Value {
        let mut a = vec!["predict", "--from", from, "--json"];
        a.extend(args);
        let r = capstan(&a);
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        serde_json::from_slice(&r.stdout).unwrap()
    };
    let num = |v: &serde_json::Value| v.as_f64().unwrap();
    let at = ["--wrap-deg", "540", "--diameter-mm", "20"];
    let mut a = vec!["--t2-n", "30", "--sure", "0.975"];
    a.extend(at);
    let v = json(&a);
    let p = &v["predictions"][0];
    let (t1, sure) = (num(&p["t1_n"]), num(&p["t1_for_sure"]));
    let (lo, hi) = (num(&p["t1_ci95"]["lo"]), num(&p["t1_ci95"]["hi"]));
    // 30 N at 540° with the thesis's mu ≈ 0.14 (e^(0.14·3π) ≈ 3.8, less the heating): T1 is
    // between 6 and 12 N, inside its interval, and a new cord needs more.
    assert!(
        t1 > 6.0 && t1 < 12.0 && lo < t1 && t1 < hi && sure > hi,
        "{p}"
    );
    assert_eq!(p["t2_n"], 30.0);
    assert_eq!(v["flags"].as_array().unwrap().len(), 0, "{v}");
    // Forward at the T1 found: T2 is 30 N again within 1e-6 N; at the T1 for 97.5 % sure the
    // 95 % PI begins at 30 N (a new cord's T2 is above it with probability 0.975).
    let t1s = format!("{t1:.12},{sure:.12}");
    let mut b = vec!["--t1-n", &t1s];
    b.extend(at);
    let f = json(&b);
    assert!(
        (num(&f["predictions"][0]["t2_n"]) - 30.0).abs() < 1e-6,
        "{f}"
    );
    assert!(
        (num(&f["predictions"][1]["t2_pi95"]["lo"]) - 30.0).abs() < 1e-6,
        "{f}"
    );
    // And back: T1 → T2 → T1 within 1e-6 N.
    let t2 = format!("{:.12}", num(&f["predictions"][1]["t2_n"]));
    let mut c = vec!["--t2-n", &t2];
    c.extend(at);
    let back = num(&json(&c)["predictions"][0]["t1_n"]);
    assert!((back - sure).abs() < 1e-6, "{back} {sure}");

    // 100 N is past the firmware's 45 N and the sensors' 52.5 N: flagged and warned.
    let mut d = vec!["--t2-n", "30,100"];
    d.extend(at);
    let v = json(&d);
    assert_eq!(v["beyond_rig"], true);
    let f1 = v["predictions"][1]["flags"].as_array().unwrap();
    assert!(f1.iter().any(|f| f == "over_force_limit") && f1.iter().any(|f| f == "sensor_range"));
    assert!(v["predictions"][0]["flags"].as_array().unwrap().is_empty());
    // 44 N is inside the limit, but the T1 that makes a new cord sure of it (about 16.6 N)
    // lets a new cord pull beyond 45 N (the forward PI's top, about 54 N): flagged too.
    let mut e = vec!["--t2-n", "44"];
    e.extend(at);
    let v = json(&e);
    let f44 = v["predictions"][0]["flags"].as_array().unwrap();
    assert!(f44.iter().any(|f| f == "over_force_limit"), "{v}");
    let w = v["warnings"].as_array().unwrap();
    assert!(
        w.iter()
            .any(|w| w.as_str().unwrap().contains("over-force limit of 45 N")),
        "{w:?}"
    );
    // A human table too, with its warnings on stderr.
    let mut e = vec!["predict", "--from", from, "--t2-n", "30,100"];
    e.extend(at);
    let r = capstan(&e);
    let out = String::from_utf8_lossy(&r.stdout);
    assert!(
        r.status.success() && out.contains("T1 97.5 % sure (N)"),
        "{out}"
    );
    assert!(String::from_utf8_lossy(&r.stderr).contains("over-force"));

    // Outside the fitted voltages (10 V only) the intervals are not identified, in words.
    let mut g = vec!["--t2-n", "30", "--drive-v", "12"];
    g.extend(at);
    let v = json(&g);
    assert!(
        v["predictions"][0]["t1_ci95"].is_null() && v["predictions"][0]["t1_for_sure"].is_null()
    );
    assert!(
        v["not_identified"]
            .as_str()
            .unwrap()
            .contains("drive voltage 12 V"),
        "{v}"
    );
    // Beyond the rig's 13.2 V the command refuses, naming the limit; --sure must be a
    // probability.
    for (flag, value, says) in [
        (
            "--drive-v",
            "100",
            "--drive-v 100: the rig's drive gives 0 to 13.2 V",
        ),
        (
            "--drive-v",
            "13.3",
            "--drive-v 13.3: the rig's drive gives 0 to 13.2 V",
        ),
        ("--sure", "1", "--sure 1: a probability"),
    ] {
        let mut a = vec!["predict", "--from", from, "--t2-n", "30", flag, value];
        a.extend(at);
        let r = capstan(&a);
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(
            !r.status.success() && err.contains(says),
            "{flag} {value}: {err}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A `metrics.json` of another layout version (`schema_version` 1, 3, "x", null, 2.0 or
/// missing: an adversarial pass found them all predicted from) is refused by name, forward,
/// backward and by `rig load-model`, which read it through the same reader; a covariance entry
/// of 1e999 (inf once parsed) is refused naming the covariance.
#[test]
fn another_layout_version_and_an_infinite_covariance_are_refused_by_name() {
    let dir = std::env::temp_dir().join(format!("capstan-predict-version-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let good = metrics(&dir);
    let text = std::fs::read_to_string(&good).unwrap();
    assert!(text.contains("\"schema_version\":2,"), "{text:.80}");
    let at = ["--wrap-deg", "540", "--diameter-mm", "20"];
    let given = [["--t1-n", "5"], ["--t2-n", "30"]];
    let board = dir.join("board");
    let rig = |from: &str| {
        capstan(&[
            "rig",
            "--sim",
            board.to_str().unwrap(),
            "--sim-wrap-deg",
            "540",
            "load-model",
            "--from",
            from,
        ])
    };
    // `from` predicted from, either way, and loaded by the rig: each refused, saying `want`.
    let refused = |from: &str, want: &str, what: &str| {
        for g in given {
            let mut a = vec!["predict", "--from", from];
            a.extend(g);
            a.extend(at);
            let r = capstan(&a);
            let err = String::from_utf8_lossy(&r.stderr);
            assert!(!r.status.success(), "{what} {g:?} was accepted: {err}");
            assert!(err.contains(want), "{what} {g:?}: {err}");
        }
        let r = rig(from);
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(
            !r.status.success() && err.contains(want),
            "rig {what}: {err}"
        );
    };
    for (found, says) in [
        (
            "1",
            "schema_version is 1; this capstan reads 2 (run capstan analyze again)",
        ),
        (
            "3",
            "schema_version is 3, newer than this capstan reads (2)",
        ),
        ("\"x\"", "schema_version is \"x\"; this capstan reads 2"),
        ("null", "schema_version is null; this capstan reads 2"),
        ("2.0", "schema_version is 2.0; this capstan reads 2"),
        (
            "",
            "no schema_version (this capstan reads 2; run capstan analyze again)",
        ),
    ] {
        let edited = match found {
            "" => text.replacen("\"schema_version\":2,", "", 1),
            v => text.replacen(
                "\"schema_version\":2,",
                &format!("\"schema_version\":{v},"),
                1,
            ),
        };
        let path = dir.join("edited.json");
        std::fs::write(&path, edited).unwrap();
        let from = path.to_str().unwrap();
        refused(
            from,
            &format!("{from}: {says}"),
            &format!("schema_version {found:?}"),
        );
    }
    // A variance and a covariance of 1e999, written as text (JSON has no inf to write).
    let cov = text.find("\"covariance\":[[").unwrap() + "\"covariance\":[[".len();
    let first = cov + text[cov..].find(',').unwrap();
    let second = first + 1 + text[first + 1..].find(',').unwrap();
    for (what, range) in [
        ("a variance", cov..first),
        ("a covariance", first + 1..second),
    ] {
        let mut edited = text.clone();
        edited.replace_range(range, "1e999");
        let path = dir.join("inf.json");
        std::fs::write(&path, edited).unwrap();
        let from = path.to_str().unwrap();
        let want = format!("{from}: prediction_model: covariance row 1 is not finite");
        refused(from, &want, what);
    }
    // The file as written still predicts (and the rig, at 540°, loads it).
    let r = predict_at(good.to_str().unwrap(), "540", "5", &[]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}
