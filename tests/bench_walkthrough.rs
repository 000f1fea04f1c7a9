//! The README's bench walk-through ("Setting up the rig at the bench"), run as written on the
//! simulated board: its shell blocks, in order, with `BOARD="--sim DIR"` for the board's
//! options. Every command must succeed; the calibration it stores must be the simulated
//! sensors' true one (the truth in DIR/sim-truth.json, hidden from the firmware), and the runs
//! it logs must be what `analyze` reads.

use std::path::{Path, PathBuf};
use std::process::Command;

const SECTION: &str = "### Setting up the rig at the bench";
const SECTION_END: &str = "### Configuration";

/// The section's `sh` blocks, in order, joined.
fn walkthrough_script() -> String {
    let readme = include_str!("../README.md");
    let start = readme
        .find(SECTION)
        .expect("the README has the walk-through");
    let end = start + readme[start..].find(SECTION_END).expect("and its end");
    let mut script = String::new();
    let mut inside = false;
    for line in readme[start..end].lines() {
        let t = line.trim();
        if t == "```sh" {
            inside = true;
        } else if t == "```" {
            inside = false;
        } else if inside {
            script.push_str(t);
            script.push('\n');
        }
    }
    script
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("capstan-bench-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn json(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
    serde_json::from_str(&text).unwrap()
}

#[test]
fn the_readme_walkthrough_runs_on_the_simulated_board_and_stores_the_true_calibration() {
    let script = walkthrough_script();
    let board_line = script
        .lines()
        .find(|l| l.starts_with("BOARD="))
        .expect("the walk-through sets BOARD");
    assert!(board_line.contains("--chip RP2040"), "{board_line}");
    for needed in [
        "rig setup",
        "rig zero",
        "rig weigh t1",
        "rig store",
        "capstan log $BOARD",
    ] {
        assert!(script.contains(needed), "the walk-through has `{needed}`");
    }
    let script = script.replace(board_line, "BOARD=\"--sim rehearsal\"");
    let dir = tmp("walk");
    let bin = PathBuf::from(env!("CARGO_BIN_EXE_capstan"));
    let path = format!(
        "{}:{}",
        bin.parent().unwrap().display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let out = Command::new("bash")
        .arg("-c")
        .arg(format!("set -eu\n{script}"))
        .current_dir(&dir)
        .env("PATH", path)
        .output()
        .expect("bash runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "the walk-through failed:\n{script}\n--- stdout\n{stdout}\n--- stderr\n{stderr}"
    );
    assert!(!stdout.contains("refused"), "{stdout}");
    // After the power cycle the board says where its settings came from.
    assert!(stdout.contains("loaded from flash at boot"), "{stdout}");

    // The stored calibration against the hidden truth: within 1 %.
    let truth = json(&dir.join("rehearsal/sim-truth.json"));
    let summary = json(&dir.join("runs/first/summary.json"));
    let runs = summary["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 3, "{summary}");
    for run in runs {
        assert_eq!(run["complete"], true, "{run}");
        for ch in ["t1", "t2"] {
            let stored = run["calibration"][format!("{ch}_n_per_count")]
                .as_f64()
                .unwrap();
            let true_npc = truth[ch]["n_per_count"].as_f64().unwrap();
            let err = stored / true_npc - 1.0;
            assert!(
                err.abs() < 0.01,
                "{ch}: stored {stored} N/count, true {true_npc} ({:+.2} %)",
                err * 100.0
            );
        }
        assert_eq!(run["capstan_diameter_mm"]["value"], 12.7, "{run}");
        assert_eq!(run["wrap_deg"]["value"], 360.0, "{run}");
    }
    // The sensors' errors were large enough to matter: uncalibrated, one would read > 1 % off.
    let off = ["t1", "t2"]
        .iter()
        .map(|ch| (truth[ch]["vs_nominal"].as_f64().unwrap() - 1.0).abs())
        .fold(0.0, f64::max);
    assert!(off > 0.01, "seed 1's sensors are off by {off}");
    // analyze read the runs.
    assert!(
        dir.join("runs/first-report/metrics.json").is_file(),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
