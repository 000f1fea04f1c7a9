//! One verdict in one wording (issue 42, item 2): on the thesis data `diagnose`'s verdict,
//! `analyze`'s headline, the report and `discover` name the same causes in the same order, and
//! say what is left in the same words (the verdict layer's, `evidence::adequacy::scatter_head`).
//! The headline's plain words for each cause and its numbers (the extended model's) are its
//! own; what it claims of them is the verdict's.

use std::process::Command;

fn capstan(args: &[&str]) -> std::process::Output {
    let o = Command::new(env!("CARGO_BIN_EXE_capstan"))
        .args(args)
        .output()
        .expect("capstan runs");
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

fn json(o: &std::process::Output) -> serde_json::Value {
    serde_json::from_slice(&o.stdout).expect("one JSON object")
}

fn names(v: &serde_json::Value) -> Vec<String> {
    (v.as_array().unwrap().iter())
        .map(|x| {
            x.as_str()
                .unwrap_or_else(|| x["name"].as_str().unwrap())
                .to_string()
        })
        .collect()
}

#[test]
fn diagnose_analyze_the_report_and_discover_give_the_thesis_data_one_verdict() {
    let data = concat!(env!("CARGO_MANIFEST_DIR"), "/data/thesis-conditioned.csv");
    let dir = std::env::temp_dir().join(format!("capstan-one-verdict-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = dir.to_str().unwrap();
    let diagnose = json(&capstan(&["diagnose", data, "--json"]));
    let discover = json(&capstan(&["discover", data, "--json"]));
    capstan(&["analyze", data, "--out", out]);
    let metrics: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("metrics.json")).unwrap()).unwrap();
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    let verdict = diagnose["verdict"].as_str().unwrap();

    // The causes, strongest first, everywhere.
    let named: Vec<String> = (diagnose["effects"].as_array().unwrap().iter())
        .map(|e| e["effect"].as_str().unwrap().to_string())
        .collect();
    assert_eq!(named, ["t2_offset", "contact_heating"], "{verdict}");
    let in_verdict: Vec<usize> = named
        .iter()
        .map(|n| verdict.find(n.as_str()).unwrap())
        .collect();
    assert!(in_verdict.windows(2).all(|w| w[0] < w[1]), "{verdict}");
    assert_eq!(names(&metrics["causes"]), named);
    assert_eq!(names(&discover["catalogue_effects"]), named, "discover");
    let listed = format!("Named causes: <b>{}</b>", named[0]);
    assert!(html.contains(&listed), "the report's technical summary");

    // What is established, and what is left, in the verdict's words.
    let headline: Vec<&str> = (metrics["headline"]["sentences"].as_array().unwrap().iter())
        .map(|s| s.as_str().unwrap())
        .collect();
    assert!(verdict.starts_with("The data hold "), "{verdict}");
    assert!(
        headline[1].starts_with("The data establish that "),
        "{headline:?}"
    );
    let sensor = headline[1].find("T2 needs an additive offset").unwrap();
    assert!(
        sensor < headline[1].find("contact heating").unwrap(),
        "{headline:?}"
    );
    let left = capstan_engine::evidence::adequacy::scatter_head(&[
        "contact heating".to_string(),
        "the T2 offset".to_string(),
    ]);
    let order = capstan_engine::evidence::adequacy::NO_ORDER;
    // diagnose gives each parameter its SD between cords in brackets; the head is the same.
    let bare = strip_brackets(verdict);
    assert!(
        bare.contains(&format!("{left}{order}")),
        "diagnose: {verdict}"
    );
    // The headline says it of the tensions above the lowest, where the model fails (its own
    // sentence before this one).
    let above = format!("{left}{order}").replacen("What is left", "Above them, what is left", 1);
    assert!(
        headline[2].starts_with("At the lowest tensions"),
        "headline: {headline:?}"
    );
    assert!(headline[3].starts_with(&above), "headline: {headline:?}");
    assert!(!verdict.contains("Unexplained") && !headline.join(" ").contains("unexplained"));

    // The report shows the headline and the diagnose verdict, word for word (its negative
    // numbers set with minus signs).
    let esc = |s: &str| capstan_report::cells::minus_signs(&capstan_report::cells::esc(s));
    assert!(
        html.contains(&esc(&headline.join(" "))),
        "the report's headline"
    );
    assert!(
        html.contains(&esc(verdict)),
        "the report's technical summary"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `s` without its bracketed parts (" (SD 0.0011 1/N between cords, p ≤ 5.0e-4)").
fn strip_brackets(s: &str) -> String {
    let mut out = String::new();
    let mut depth = 0;
    for c in s.chars() {
        match c {
            '(' => depth += 1,
            ')' => depth -= 1,
            c if depth == 0 => out.push(c),
            _ => {}
        }
    }
    out.replace(" ,", ",").replace("  ", " ")
}
