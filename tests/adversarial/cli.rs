//! Command lines: every option against its range, output directories that hold what capstan
//! did not write, stdout errors, signals and silent input. Each refuses before any work.

use super::{checked, scratch};
use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn capstan(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_capstan"))
        .args(args)
        .stdin(Stdio::null())
        .output()
        .expect("capstan runs")
}

fn err(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// `args` fails with status `code` and a message holding every one of `words`, fast.
fn refused(args: &[&str], code: i32, words: &[&str]) {
    let t = Instant::now();
    let o = capstan(args);
    let e = err(&o);
    assert_eq!(o.status.code(), Some(code), "{args:?}: {e}");
    for w in words {
        assert!(e.contains(w), "{args:?}: want `{w}`: {e}");
    }
    assert!(!e.contains("panicked"), "{e}");
    assert!(
        t.elapsed() < Duration::from_secs(20),
        "{args:?} took {:?}",
        t.elapsed()
    );
    checked();
}

const ELF: &str = "tests/data/qemu-fw.elf";
const STREAM: &str = "tests/data/qemu-run.defmt";

#[test]
fn every_numeric_option_is_refused_outside_its_range_with_the_range() {
    let dir = scratch("ranges");
    let out = dir.join("out");
    let o = s(&out);
    let sim: &[(&[&str], &str)] = &[
        (
            &["--fault", "cord_break@1e14"],
            "--fault cord_break@1e14: the time must be from 0 to 1000000 s",
        ),
        (&["--fault", "cord_break@-1"], "0 or more seconds"),
        (
            &["--fault", "cord_break@nan"],
            "the time must be 0 or more seconds",
        ),
        (&["--runs", "0"], "--runs 0: must be from 1 to"),
        (&["--runs", "-3"], "invalid value '-3'"),
        (
            &["--wraps", "1e9"],
            "--wraps 1000000000: must be greater than 0 and at most 3600 deg",
        ),
        (&["--wraps", "-90"], "--wraps -90: must be greater than 0"),
        (
            &["--diameters", "-1"],
            "--diameters -1: must be greater than 0",
        ),
        (&["--diameters", "2000"], "at most 1000 mm"),
        (
            &["--drive-v", "1e6"],
            "--drive-v 1000000: the rig's drive gives 0 to 13.2 V",
        ),
        (
            &["--dwell-ms", "4000000"],
            "--dwell-ms 4000000: must be from 0 to 3600000 ms",
        ),
        (&["--window-after-ms", "-1"], "invalid value '-1'"),
        (&["--threads", "0"], "--threads 0: must be from 1 to 1024"),
        (
            &["--two-control", "--delays-ms", "4294967295,0"],
            "--delays-ms 4294967295: must be from 0 to 3600000 ms",
        ),
        (&["--mu", "3"], "--mu 3: must be 0 to 2"),
        (
            &["--effect", "t2_offset=0.1", "--effect", "t2_offset=0.2"],
            "is given twice",
        ),
    ];
    for (extra, want) in sim {
        let mut args = vec!["simulate", "--out", o];
        args.extend_from_slice(extra);
        // A value that is not a whole number at all is clap's usage error (status 2).
        let code = if want.starts_with("invalid value") {
            2
        } else {
            1
        };
        refused(&args, code, &[want]);
    }
    assert!(!out.exists(), "a refused command leaves no directory");
    let log: &[(&[&str], &str)] = &[
        (
            &["--wrap-deg", "1e9"],
            "--wrap-deg 1000000000: must be greater than 0 and at most 3600 deg",
        ),
        (
            &["--diameter-mm", "-1"],
            "--diameter-mm -1: must be greater than 0",
        ),
        (&["--diameter-mm", "1e6"], "at most 1000 mm"),
        (
            &["--drive-v", "1e6"],
            "--drive-v 1000000: the rig's drive gives 0 to 13.2 V",
        ),
        (&["--duration", "0"], "--duration 0: must be greater than 0"),
        (
            &["--duration", "-5"],
            "--duration -5: must be greater than 0",
        ),
        (&["--duration", "1e30"], "a year"),
        (&["--duration", "nan"], "--duration NaN: not a number"),
        (&["--runs", "0"], "--runs 0: must be 1 or more"),
    ];
    for (extra, want) in log {
        let mut args = vec!["log", "--elf", ELF, "--from", STREAM, "--out", o];
        args.extend_from_slice(extra);
        refused(&args, 1, &[want]);
    }
    for (flag, v) in [("--within-threshold", "nan"), ("--between-threshold", "-1")] {
        refused(
            &["diagnose", flag, v],
            1,
            &[flag, "must be a finite number, 0 or more"],
        );
    }
    refused(
        &["analyze", "--threads", "0", "--out", o],
        1,
        &["--threads 0: must be from 1 to 1024"],
    );
    assert!(!out.exists());
}

#[test]
fn output_directories_holding_what_capstan_did_not_write_are_refused_before_any_work() {
    // Case 2: the user's own pairs.csv, summary.json and a raw file, no manifest.
    let d = scratch("users-files");
    std::fs::create_dir_all(d.join("raw")).unwrap();
    for (f, body) in [
        ("pairs.csv", "mine"),
        ("summary.json", "{}"),
        ("raw/d12.7_w360_v10_run1.csv", "mine"),
    ] {
        std::fs::write(d.join(f), body).unwrap();
    }
    refused(
        &[
            "simulate",
            "--out",
            s(&d),
            "--runs",
            "2",
            "--wraps",
            "360",
            "--diameters",
            "12.7",
        ],
        1,
        &[
            "pairs.csv is a file that `capstan simulate` did not write",
            "move it away",
        ],
    );
    std::fs::remove_file(d.join("pairs.csv")).unwrap();
    std::fs::remove_file(d.join("summary.json")).unwrap();
    refused(
        &[
            "simulate",
            "--out",
            s(&d),
            "--runs",
            "2",
            "--wraps",
            "360",
            "--diameters",
            "12.7",
        ],
        1,
        &["raw/d12.7_w360_v10_run1.csv is a file that `capstan simulate` did not write"],
    );
    assert_eq!(
        std::fs::read_to_string(d.join("raw/d12.7_w360_v10_run1.csv")).unwrap(),
        "mine"
    );
    // ... and analyze over a user's metrics.json.
    let a = scratch("users-metrics");
    std::fs::write(a.join("metrics.json"), "mine").unwrap();
    refused(
        &["analyze", "--out", s(&a)],
        1,
        &["metrics.json is a file that `capstan analyze` did not write"],
    );
    assert_eq!(
        std::fs::read_to_string(a.join("metrics.json")).unwrap(),
        "mine"
    );
    // Case 3: raw a link or a file: refused at once, before the campaign runs.
    #[cfg(unix)]
    {
        let l = scratch("raw-link");
        let elsewhere = scratch("raw-link-target");
        std::os::unix::fs::symlink(&elsewhere, l.join("raw")).unwrap();
        refused(
            &["simulate", "--out", s(&l), "--runs", "50"],
            1,
            &["raw is a symbolic link"],
        );
        assert_eq!(std::fs::read_dir(&elsewhere).unwrap().count(), 0);
        let f = scratch("raw-file");
        std::fs::write(f.join("raw"), "a file").unwrap();
        refused(
            &["simulate", "--out", s(&f), "--runs", "50"],
            1,
            &["raw is a file where capstan simulate writes a directory"],
        );
    }
    // Another command's results, and log's own rule.
    let logged = scratch("logged");
    let o = capstan(&["log", "--elf", ELF, "--from", STREAM, "--out", s(&logged)]);
    assert!(o.status.success(), "{}", err(&o));
    refused(
        &["simulate", "--out", s(&logged)],
        1,
        &["holds the results of `capstan log`"],
    );
    refused(
        &["log", "--elf", ELF, "--from", STREAM, "--out", s(&logged)],
        1,
        &["already holds a logged session", "--overwrite"],
    );
    refused(
        &[
            "log",
            "--elf",
            ELF,
            "--from",
            s(&logged),
            "--out",
            s(&scratch("from-dir")),
        ],
        1,
        &["is a directory"],
    );
}

#[test]
fn a_session_across_a_board_restart_reads_back_with_its_runs_apart() {
    // The recorded stream twice: the board's sequence numbers and run numbers start again.
    let dir = scratch("restart");
    let stream = dir.join("twice.defmt");
    let one = std::fs::read(STREAM).unwrap();
    std::fs::write(&stream, [one.clone(), one].concat()).unwrap();
    let o = capstan(&[
        "log",
        "--elf",
        ELF,
        "--from",
        s(&stream),
        "--out",
        s(&dir.join("o")),
        "-q",
    ]);
    assert!(o.status.success(), "{}", err(&o));
    let d = capstan_data::load_pairs(&dir.join("o/pairs.csv")).unwrap();
    assert_eq!(d.structure.run_level.columns, ["run", "boot"]);
    assert_eq!(d.structure.run_cord.len(), 4, "{}", d.structure.describe());
    checked();
}

#[test]
fn stdout_errors_are_errors_and_a_closed_pipe_is_quiet() {
    // Case 12: a full disk is not a closed pipe.
    let full = std::fs::File::create("/dev/full");
    if let Ok(full) = full {
        let o = Command::new(env!("CARGO_BIN_EXE_capstan"))
            .args(["diagnose", "--json"])
            .stdout(full)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(74), "{}", err(&o));
        assert!(
            err(&o).contains("cannot write to standard output: No space left on device"),
            "{}",
            err(&o)
        );
        checked();
    }
    #[cfg(target_os = "linux")]
    {
        let o = Command::new("sh")
            .args([
                "-c",
                &format!("exec {} diagnose --json >&-", env!("CARGO_BIN_EXE_capstan")),
            ])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(74), "{}", err(&o));
        assert!(err(&o).contains("standard output is closed"), "{}", err(&o));
        checked();
    }
}

#[cfg(unix)]
#[test]
fn duration_ends_on_time_even_when_nothing_arrives() {
    // Case 9: stdin stays open and silent; --duration 1 ends the session after ~1 s.
    let dir = scratch("silent");
    let t = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_capstan"))
        .args([
            "log",
            "--elf",
            ELF,
            "--from",
            "-",
            "--duration",
            "1",
            "--out",
            s(&dir.join("o")),
        ])
        .stdin(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let _stdin = child.stdin.take(); // held open, never written
    let o = child.wait_with_output().unwrap();
    let took = t.elapsed();
    assert!(took < Duration::from_secs(10), "{took:?}");
    let e = err(&o);
    assert!(e.contains("limit reached: 1 s (--duration)"), "{e}");
    // Nothing arrived: nothing replaced, nothing kept, and the same status as any stream
    // without a complete run (an empty stream and a 1-byte one alike).
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("nothing was received"), "{e}");
    checked();
}
