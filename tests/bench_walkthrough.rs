//! The user guide's bench walk-through (docs/book/src/bench.md, "Setting up the rig at the bench"
//! and "Rehearsing the bench without hardware"), run as written on the
//! simulated board: its shell blocks, in order, with `BOARD="--sim DIR"` for the board's
//! options. Every command must succeed; the calibration it stores must be the simulated
//! sensors' true one (the truth in DIR/sim-truth.json, hidden from the firmware), and the runs
//! it logs must be what `analyze` reads.

use std::path::{Path, PathBuf};
use std::process::Command;

const SECTION: &str = "## Setting up the rig at the bench";
const SECTION_END: &str = "## Logging a run to disk";

/// The section's `sh` blocks, in order, joined.
fn walkthrough_script() -> String {
    let readme = include_str!("../docs/book/src/bench.md");
    let start = readme
        .find(SECTION)
        .expect("the bench chapter has the walk-through");
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

fn rig(dir: &Path, board: &str, words: &str) -> (bool, String) {
    let mut args = vec!["rig", "--sim", board];
    args.extend(words.split(' '));
    let o = Command::new(env!("CARGO_BIN_EXE_capstan"))
        .args(&args)
        .current_dir(dir)
        .output()
        .expect("capstan runs");
    let text = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
    (o.status.success(), text)
}

/// The rehearsal goes through the firmware's safety rules, not around them: a zero under load
/// that would blind the over-force check is refused, a weight over the limit latches a fault,
/// a run needs `ack` after it, a tare under load ends the run, and the board keeps all of
/// that between commands.
#[test]
fn the_simulated_board_keeps_the_safety_rules_between_commands() {
    let dir = tmp("safety");
    let ok = |words: &str| {
        let (ok, text) = rig(&dir, "b", words);
        assert!(ok, "`rig {words}` failed: {text}");
        text
    };
    let refused = |words: &str, why: &str| {
        let (ok, text) = rig(&dir, "b", words);
        assert!(!ok && text.contains(why), "`rig {words}`: {text}");
    };
    // A fresh board's sensitivities are a placeholder nobody measured: no run on them.
    assert!(ok("show").contains("UNMEASURED: T1's sensitivity"));
    refused("run", "sensitivity was never measured");
    // Typed by the person (their sensors' data sheets), they run.
    ok("set t1_n_per_count 0.015");
    ok("set t2_n_per_count 0.015");
    assert!(!ok("show").contains("UNMEASURED"));
    ok("setup");
    ok("bench load t1 30");
    refused("zero", "over-force limit would read above the high rail");
    assert!(ok("bench load t1 47").contains("FAULT over_force on T1"));
    refused("run", "a fault is latched");
    ok("bench unload");
    // Still latched in the next command: the board kept it.
    refused("setup", "a fault is latched");
    ok("ack");
    ok("bench load t2 20");
    let log = |out: &str| {
        Command::new(env!("CARGO_BIN_EXE_capstan"))
            .args(["log", "--sim", "b", "--start", "--runs", "1", "--out", out])
            .current_dir(&dir)
            .output()
            .expect("capstan runs")
    };
    let o = log("loaded");
    let text = String::from_utf8_lossy(&o.stderr);
    assert!(text.contains("FAULT tare_load"), "{text}");
    ok("bench unload");
    // The tare fault is latched: the run command is refused, no run is recorded.
    let o = log("unacknowledged");
    assert!(
        !o.status.success(),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    ok("ack");
    let o = log("clean");
    let text = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{text}");
    assert!(text.contains("12 pairs"), "{text}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A new board whose description is refused leaves nothing behind: the same directory then
/// makes a board as if it had never been tried.
#[test]
fn a_refused_new_board_leaves_its_directory_usable() {
    let dir = tmp("refused");
    let (ok, text) = rig(&dir, "b", "--sim-mu -1 show");
    assert!(!ok, "a negative mu was accepted: {text}");
    let (ok, text) = rig(&dir, "b", "show");
    assert!(ok, "the directory was left unusable: {text}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A session never goes into the simulated board's own directory (nor the board into the
/// session's): the board's journal and flash stay as they were; and a wrong channel is named
/// in the refusal's words.
#[test]
fn a_session_is_not_written_into_the_boards_directory() {
    let dir = tmp("into-board");
    let (ok, text) = rig(&dir, "b", "show");
    assert!(ok, "{text}");
    let journal = std::fs::read(dir.join("b/journal.txt")).expect("journal");
    for out in ["b", "b/session", "."] {
        let o = Command::new(env!("CARGO_BIN_EXE_capstan"))
            .args(["log", "--sim", "b", "--start", "--runs", "1", "--out", out])
            .current_dir(&dir)
            .output()
            .expect("capstan runs");
        let text = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "--out {out} accepted: {text}");
        assert!(text.contains("choose another --out"), "{text}");
    }
    assert_eq!(std::fs::read(dir.join("b/journal.txt")).unwrap(), journal);
    assert!(!dir.join("b/pairs.csv").exists() && !dir.join("b/session").exists());
    let (ok, text) = rig(&dir, "b", "weigh t3 2");
    assert!(!ok && text.contains("weigh t1|t2 NEWTONS"), "{text}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A run the firmware refuses at its tare (a weight left on the T2 hook: `tare_load`, no pair,
/// no raw sample) is cut short, not complete: `log --overwrite` with it replaces nothing. The
/// recorded session stays byte for byte, what came in is kept apart, the exit status says so.
#[test]
fn a_run_refused_at_its_tare_does_not_overwrite_a_recorded_session() {
    let dir = tmp("tare-overwrite");
    let ok = |words: &str| {
        let (ok, text) = rig(&dir, "b", words);
        assert!(ok, "`rig {words}` failed: {text}");
    };
    ok("set wrap_deg 360");
    ok("set diameter_mm 12.7");
    ok("set t1_n_per_count 0.015");
    ok("set t2_n_per_count 0.015");
    ok("store");
    let log = |extra: &[&str]| {
        let mut args = vec![
            "log", "--sim", "b", "--start", "--runs", "1", "--out", "sess",
        ];
        args.extend(extra);
        Command::new(env!("CARGO_BIN_EXE_capstan"))
            .args(&args)
            .current_dir(&dir)
            .output()
            .expect("capstan runs")
    };
    let o = log(&[]);
    let text = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{text}");
    assert!(text.contains("(1 complete)"), "{text}");
    let sess = dir.join("sess");
    let files = ["pairs.csv", "raw.csv", "faults.csv", "summary.json"];
    let before: Vec<Vec<u8>> = files
        .iter()
        .map(|f| std::fs::read(sess.join(f)).unwrap())
        .collect();
    assert_eq!(String::from_utf8_lossy(&before[0]).lines().count(), 13);
    // The simulated board sends records, not a defmt stream: no stream.defmt to decode again.
    assert!(!sess.join("stream.defmt").exists());

    ok("bench load t2 20");
    let o = log(&["--overwrite"]);
    let text = String::from_utf8_lossy(&o.stderr);
    assert!(text.contains("FAULT tare_load"), "{text}");
    assert_eq!(o.status.code(), Some(1), "{text}");
    assert!(text.contains("0 complete, 1 ended by a fault"), "{text}");
    assert!(text.contains("cut short by the fault tare_load"), "{text}");
    assert!(text.contains("sess is as it was"), "{text}");
    for (f, old) in files.iter().zip(&before) {
        assert_eq!(&std::fs::read(sess.join(f)).unwrap(), old, "{f} changed");
    }
    // What came in is kept apart: its fault, no pair.
    let kept: Vec<PathBuf> = std::fs::read_dir(&sess)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            p.file_name()
                .unwrap()
                .to_string_lossy()
                .starts_with("incomplete-")
        })
        .collect();
    assert_eq!(kept.len(), 1, "{kept:?}");
    let faults = std::fs::read_to_string(kept[0].join("faults.csv")).unwrap();
    assert!(faults.contains("tare_load"), "{faults}");
    let _ = std::fs::remove_dir_all(&dir);
}
