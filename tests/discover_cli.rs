//! `capstan discover`: the JSON contract through the binary, `--out DIR`, and a bad file named
//! with its line.

use std::process::Command;

fn capstan() -> Command {
    Command::new(env!("CARGO_BIN_EXE_capstan"))
}

/// `capstan ARGS`, which must succeed (its stderr in the failure if not).
fn ok<I, S>(args: I) -> std::process::Output
where
    I: IntoIterator<Item = S>,
    S: AsRef<std::ffi::OsStr>,
{
    let out = capstan().args(args).output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

fn tmp(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("capstan-discover-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

#[test]
fn thesis_json_through_the_binary_and_out_dir() {
    let out_dir = tmp("out");
    let out = ok(["discover", "--json", "--out", out_dir.to_str().unwrap()]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    assert_eq!(v["terms"], serde_json::json!([]));
    // The engine takes the thesis's lack of fit for cord-to-cord scatter (the cords share no
    // pattern beyond their own T2 zero and heating), not for structure left unexplained.
    assert_eq!(v["unexplained_after"], serde_json::json!(false));
    assert!(v["elapsed_s"].as_f64().is_some_and(|t| t > 0.0 && t < 30.0));
    let saved: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out_dir.join("discover.json")).unwrap()).unwrap();
    assert_eq!(saved["catalogue_effects"], v["catalogue_effects"]);
    // The summary says the answer in words.
    let out = capstan().arg("discover").output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("Nothing to add"), "{text}");
}

#[test]
fn a_bad_file_is_named_with_its_line() {
    let p = tmp("bad.csv");
    std::fs::write(&p, "wrap_deg,t1_n,t2_n\n360,1.0,2.0\n360,x,3.0\n").unwrap();
    let out = capstan()
        .args(["discover", p.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.csv") && err.contains('3'), "{err}");
}

/// One cord (the thesis's 12.7 mm capstan at 450°, its six runs; and one run of it): whole
/// cords can be neither resampled nor held out, so the stability and the held-out gain are not
/// computed: the summary says so instead of printing a count of resamples, the JSON has nulls
/// with the reason, and one run has no run-clustered error to print as "± 0.0000".
#[test]
fn one_cord_says_stability_and_held_out_cannot_be_computed() {
    let thesis = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/thesis-conditioned.csv"),
    )
    .unwrap();
    let mut lines = thesis.lines();
    let header = lines.next().unwrap();
    let rows: Vec<&str> = lines.filter(|l| l.starts_with("12.7,450,")).collect();
    assert_eq!(rows.len(), 72);
    for (name, keep) in [("one-cord.csv", rows.len()), ("one-run.csv", 12)] {
        let p = tmp(name);
        std::fs::write(&p, format!("{header}\n{}\n", rows[..keep].join("\n"))).unwrap();
        let out = ok(["discover", p.to_str().unwrap()]);
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(text.contains("cannot be computed from 1 cord"), "{text}");
        assert!(!text.contains("cord resamples"), "{text}");
        assert!(!text.contains("± 0.0000"), "{text}");
        let out = capstan()
            .args(["discover", "--json", p.to_str().unwrap()])
            .output()
            .unwrap();
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
        assert_eq!(v["search"]["resamples"], serde_json::Value::Null);
        assert_eq!(v["search"]["cords"], serde_json::json!(1));
        assert!(v["search"]["cord_checks"]
            .as_str()
            .is_some_and(|s| s.contains("at least 3")));
        assert_eq!(v["terms"], serde_json::json!([]));
        let screen = v["search"]["screen"].as_array().unwrap();
        assert!(!screen.is_empty());
        for r in screen {
            let se = &r["se"];
            if keep == 12 {
                assert_eq!(se, &serde_json::Value::Null, "one run: {r}");
            } else {
                assert!(se.as_f64().is_some_and(|s| s > 0.0), "six runs: {r}");
            }
        }
    }
}

/// Simulate a campaign into a fresh directory `name` (the simulator's default seed) and return
/// its pairs.csv.
fn simulate(name: &str, args: &[&str]) -> std::path::PathBuf {
    let dir = tmp(name);
    let _ = std::fs::remove_dir_all(&dir);
    let out = capstan()
        .args([
            "simulate",
            "--out",
            dir.to_str().unwrap(),
            "--noise",
            "thesis",
        ])
        .args(args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    dir.join("pairs.csv")
}

fn discover_json(p: &std::path::Path) -> serde_json::Value {
    let out = ok(["discover", "--json", p.to_str().unwrap()]);
    serde_json::from_slice(&out.stdout).expect("one JSON object")
}

/// One capstan diameter (and the catalogue's T2 offset selected): every term that depends on
/// the diameter is "not testable" with that reason, whatever the catalogue holds; none is
/// screened, ranked or gated on round-off (before: `t2_offset_diameter` θ = −4·10²³ ranked
/// first).
#[test]
fn one_diameter_terms_of_the_diameter_are_not_testable() {
    let p = simulate(
        "one-diameter",
        &[
            "--diameters",
            "12.7",
            "--wraps",
            "270,450,720",
            "--runs",
            "4",
            "--order",
            "updown",
            "--unmodelled",
            "t2_lowforce=0.8",
            "--no-raw",
        ],
    );
    let v = discover_json(&p);
    let lib = |name: &str| capstan_discover::library::term(name).unwrap();
    let on_diameter = |name: &str| {
        lib(name)
            .depends_on
            .contains(&capstan_discover::library::Var::Diameter)
    };
    let not: Vec<(&str, &str)> = v["not_testable"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| (n["name"].as_str().unwrap(), n["reason"].as_str().unwrap()))
        .collect();
    for t in capstan_discover::library::LIBRARY.iter() {
        if on_diameter(t.name) {
            let why = not.iter().find(|(n, _)| *n == t.name).map(|(_, r)| *r);
            assert!(
                why.is_some_and(|r| r.contains("one capstan diameter")),
                "{}: {why:?}",
                t.name
            );
        }
    }
    let screen = v["search"]["screen"].as_array().unwrap();
    assert!(!screen.is_empty());
    assert_eq!(
        v["search"]["tried"].as_u64().unwrap() as usize,
        capstan_discover::library::LIBRARY.len() - not.len()
    );
    for r in screen {
        let name = r["name"].as_str().unwrap();
        assert!(!on_diameter(name), "{r}");
        // No round-off estimates: θ and its SE are of a physical size.
        assert!(r["theta"].as_f64().is_some_and(|t| t.abs() < 1e3), "{r}");
        assert!(r["se"].as_f64().is_none_or(|s| s < 1e3), "{r}");
    }
    // The summary ranks none of them either.
    let out = capstan()
        .args(["discover", p.to_str().unwrap()])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    let ranked = text
        .split("strongest candidates")
        .nth(1)
        .and_then(|s| s.split("not testable").next())
        .unwrap();
    assert!(!ranked.contains("t2_offset_diameter"), "{text}");
    assert!(
        text.contains("not testable: t2_offset_diameter: one capstan diameter"),
        "{text}"
    );
}

/// One run per cord: there are no replicate cells, so a term proposed (here the planted
/// hysteresis) is proposed without the replicate gate, and the verdict, its words and the JSON
/// say so; its dimensionless parameter has no bare "1" for a unit. With two runs in all, no
/// run-clustered standard error is shown (two clusters claim more than they know).
#[test]
fn one_run_per_cord_says_the_replicate_gate_was_not_applied() {
    let p = simulate(
        "one-run-per-cord",
        &[
            "--diameters",
            "12.7,25.4",
            "--wraps",
            "270,450,630,720",
            "--runs",
            "1",
            "--order",
            "updown",
            "--unmodelled",
            "hysteresis=0.3",
            "--no-raw",
        ],
    );
    let v = discover_json(&p);
    let terms = v["terms"].as_array().unwrap();
    assert_eq!(terms.len(), 1, "{}", v["verdict"]);
    let t = &terms[0];
    assert_eq!(t["name"], "hysteresis");
    assert_eq!(t["replicate"], serde_json::Value::Null);
    assert!(t["replicate_gate_not_applied"]
        .as_str()
        .is_some_and(|s| s.contains("replicate cells")));
    let words = t["words"].as_str().unwrap();
    assert!(words.contains("replicate gate was not applied"), "{words}");
    let se = t["parameter_se"]["c"].as_f64().unwrap();
    assert!(!words.contains(&format!("{se:.4} 1)")), "{words}");
    assert!(words.contains(&format!("{se:.4})")), "{words}");
    assert!(v["verdict"]
        .as_str()
        .unwrap()
        .contains("hysteresis (without the replicate gate)"));

    let p = simulate(
        "two-runs",
        &["--diameters", "12.7", "--wraps", "360,540", "--runs", "1"],
    );
    let v = discover_json(&p);
    for r in v["search"]["screen"].as_array().unwrap() {
        assert_eq!(r["se"], serde_json::Value::Null, "two runs: {r}");
    }
    let out = capstan()
        .args(["discover", p.to_str().unwrap()])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("SE n/a: fewer than 3 runs"), "{text}");
    assert!(!text.contains(" ± "), "{text}");
}

/// The search line does not count "one of its 0 within-run effects" (a catalogue of one
/// between-level effect: `diameter_dependence` on a planted T1 tare, science/discover/tests/data).
#[test]
fn the_search_line_words_a_catalogue_without_within_run_effects() {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("science/discover/tests/data/tare_catalogue_seed4.csv");
    let out = ok(["discover", p.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(!text.contains("one of its 0"), "{text}");
    assert!(
        text.contains("each added to the catalogue (it has no within-run effect"),
        "{text}"
    );
}
