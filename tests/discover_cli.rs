//! `capstan discover`: the JSON contract through the binary, `--out DIR`, and a bad file named
//! with its line.

use std::process::Command;

fn capstan() -> Command {
    Command::new(env!("CARGO_BIN_EXE_capstan"))
}

fn tmp(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("capstan-discover-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

#[test]
fn thesis_json_through_the_binary_and_out_dir() {
    let out_dir = tmp("out");
    let out = capstan()
        .args(["discover", "--json", "--out", out_dir.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    assert_eq!(v["terms"], serde_json::json!([]));
    assert_eq!(v["unexplained_after"], serde_json::json!(true));
    assert!(v["elapsed_s"].as_f64().is_some_and(|t| t > 0.0 && t < 30.0));
    let saved: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out_dir.join("discover.json")).unwrap()).unwrap();
    assert_eq!(saved["catalogue_effects"], v["catalogue_effects"]);
    // The summary says the answer in words.
    let out = capstan().arg("discover").output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("Nothing in the library explains"), "{text}");
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
