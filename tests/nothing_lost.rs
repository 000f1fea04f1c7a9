//! Nothing lost, nothing hung: each failure of the "nothing lost" issue kept as a test, run on
//! the binary a user runs.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_capstan"))
}

fn capstan(args: &[&str]) -> Output {
    bin().args(args).output().expect("capstan runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("capstan-lost-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn write(dir: &Path, name: &str, body: &str) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, body).unwrap();
    p
}

/// A short campaign: 3 s steps, one cord.
const SHORT: [&str; 10] = [
    "--dwell-ms",
    "3000",
    "--window-after-ms",
    "1000",
    "--window-before-ms",
    "500",
    "--diameters",
    "12.7",
    "--wraps",
    "360",
];

fn wait_with_deadline(child: &mut Child, secs: u64) -> std::process::ExitStatus {
    let deadline = Instant::now() + Duration::from_secs(secs);
    loop {
        if let Some(st) = child.try_wait().unwrap() {
            return st;
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("capstan did not end within {secs} s");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[cfg(unix)]
#[test]
fn a_closed_pipe_ends_quietly_with_status_141() {
    use std::os::unix::process::ExitStatusExt;
    // The reader is gone before diagnose prints: `capstan diagnose --json | head -c0`.
    let mut child = bin()
        .args(["diagnose", "--json"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let mut err = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    let st = wait_with_deadline(&mut child, 300);
    assert_eq!(st.code(), Some(141), "{st:?} {err}");
    assert!(st.signal().is_none());
    assert!(!err.contains("panicked"), "{err}");
}

#[cfg(unix)]
#[test]
fn a_closed_stderr_still_leaves_the_logged_session() {
    let dir = tmp("log-pipe");
    let mut child = bin()
        .args([
            "log",
            "--elf",
            "tests/data/qemu-fw.elf",
            "--from",
            "tests/data/qemu-run.defmt",
            "--out",
            s(&dir),
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stderr.take());
    let st = wait_with_deadline(&mut child, 60);
    assert_eq!(st.code(), Some(141), "{st:?}");
    let summary = std::fs::read_to_string(dir.join("summary.json")).unwrap();
    assert!(summary.contains("\"runs\""), "{summary}");
}

#[test]
fn an_unwritable_output_fails_before_the_analysis() {
    let dir = tmp("unwritable");
    let file = write(&dir, "a-file", "not a directory");
    let o = capstan(&["analyze", "--out", s(&file.join("report"))]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.contains("cannot create the output directory"), "{err}");
    assert!(!err.contains("analysing"), "the analysis ran first: {err}");
}

#[test]
fn values_no_sensor_produces_and_data_without_friction_are_refused() {
    let dir = tmp("values");
    let cases = [
        (
            "huge.csv",
            "wrap_deg,t1_n,t2_n\n360,1,2\n360,1e154,2\n",
            "huge.csv:3:2: column `t1_n`: must be within ±10000 N",
        ),
        (
            "time.csv",
            "wrap_deg,t1_n,t2_n,time_s\n360,1,2,1e300\n",
            "time.csv:2:4: column `time_s`: must be within",
        ),
        (
            "same.csv",
            "wrap_deg,t1_n,t2_n\n360,1,1\n360,2,2\n360,3,3\n",
            "T2 is at most T1 in all 3 rows",
        ),
        ("empty.csv", "", "empty.csv: the file is empty"),
        (
            "semicolon.csv",
            "wrap_deg;t1_n;t2_n\n360;1;2\n",
            "looks separated by `;`",
        ),
        (
            "tabs.csv",
            "wrap_deg\tt1_n\tt2_n\n360\t1\t2\n",
            "looks separated by tabs",
        ),
        (
            // One run's T1 sensor reversed: every reading at or below zero, down to -22 N.
            "reversed.csv",
            "wrap_deg,run,t1_n,t2_n\n360,1,1,2\n360,1,2,4\n360,1,3,6\n\
             360,2,-0.5,1\n360,2,-22,3\n360,2,-1,5\n360,3,1,2\n360,3,2,4\n",
            "reversed.csv:6:3: t1_n = -22 N, and every t1_n reading of cord",
        ),
    ];
    for (name, body, want) in cases {
        let p = write(&dir, name, body);
        for cmd in ["diagnose", "analyze"] {
            let out = dir.join(format!("out-{name}"));
            let o =
                capstan(&[cmd, s(&p), "--out", s(&out)][..if cmd == "diagnose" { 2 } else { 4 }]);
            assert!(!o.status.success(), "{cmd} {name}");
            assert!(stderr(&o).contains(want), "{cmd} {name}: {}", stderr(&o));
            assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));
        }
    }
}

#[cfg(unix)]
#[test]
fn an_endless_input_is_refused_in_bounded_memory() {
    let o = capstan(&["diagnose", "/dev/zero"]);
    assert!(stderr(&o).contains("a line longer than"), "{}", stderr(&o));
    let o = capstan(&[
        "log",
        "--elf",
        "/dev/zero",
        "--from",
        "tests/data/qemu-run.defmt",
        "--out",
        s(&tmp("zero-elf")),
    ]);
    assert!(stderr(&o).contains("not a firmware ELF"), "{}", stderr(&o));
}

#[test]
fn a_thousand_thousand_column_header_is_checked_in_linear_time() {
    let dir = tmp("wide");
    let mut header: Vec<String> = (0..100_000).map(|i| format!("c{i}")).collect();
    header.push("c5".into());
    let p = write(
        &dir,
        "wide.csv",
        &format!("wrap_deg,t1_n,t2_n,{}\n", header.join(",")),
    );
    let o = capstan(&["diagnose", s(&p)]);
    assert!(
        stderr(&o).contains("column `c5` appears twice"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn contradictory_flags_are_refused() {
    let o = capstan(&[
        "simulate",
        "--out",
        s(&tmp("flags")),
        "--two-control",
        "--runs",
        "6",
    ]);
    assert!(
        stderr(&o).contains("--runs is for campaigns"),
        "{}",
        stderr(&o)
    );
    let o = capstan(&["diagnose", "--within-threshold", "nan"]);
    assert!(
        stderr(&o).contains("--within-threshold NaN"),
        "{}",
        stderr(&o)
    );
    let o = capstan(&[
        "simulate",
        "--out",
        s(&tmp("flags2")),
        "--effect",
        "t2_offset=0.1",
        "--effect",
        "t2_offset=0.2",
    ]);
    assert!(stderr(&o).contains("is given twice"), "{}", stderr(&o));
}

#[cfg(unix)]
#[test]
fn a_stopped_campaign_keeps_every_finished_run_and_a_second_writer_is_refused() {
    let dir = tmp("stop");
    // The user's own file that looks like one of ours: never deleted.
    write(&dir.join("raw"), "d12.7_w360_v10_run0.csv", "mine");
    // A first, complete campaign.
    let mut args = vec!["simulate", "--out", s(&dir), "--runs", "2"];
    args.extend(SHORT);
    assert!(capstan(&args).status.success());
    // A long one, stopped by SIGTERM while it runs.
    let args = long_campaign(&dir);
    let mut child = bin()
        .args(&args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1500));
    let second = bin().args(&args).output().unwrap();
    assert!(
        stderr(&second).contains("in use by another capstan process"),
        "{}",
        stderr(&second)
    );
    let st = terminate(&mut child);
    assert_eq!(st.code(), Some(130), "{st:?}");
    assert!(
        stderr(&child_output(child)).contains("the complete campaign in"),
        "the stop says the complete campaign is as it was"
    );
    // The complete campaign is as it was: a stopped one replaces no complete one.
    let read = |p: &Path| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(p.join("summary.json")).unwrap()).unwrap()
    };
    let first = read(&dir);
    assert_eq!(first["interrupted"], false, "{first}");
    assert_eq!(
        std::fs::read_to_string(dir.join("raw/d12.7_w360_v10_run0.csv")).unwrap(),
        "mine"
    );
    // The stopped one is kept beside it, as incomplete-<id>, every finished run whole.
    let kept: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| {
            p.file_name()
                .unwrap()
                .to_string_lossy()
                .starts_with("incomplete-")
        })
        .collect();
    assert_eq!(kept.len(), 1, "{kept:?}");
    let summary = read(&kept[0]);
    assert_eq!(summary["interrupted"], true);
    let runs = summary["runs"].as_u64().unwrap();
    assert!((1..100_000).contains(&runs), "{summary}");
    // Every finished run is on disk, whole: its raw log, and its pairs (3 s steps: 12 each).
    let raw = std::fs::read_dir(kept[0].join("raw")).unwrap().count();
    assert_eq!(raw as u64, runs, "raw logs");
    let pairs = std::fs::read_to_string(kept[0].join("pairs.csv")).unwrap();
    assert_eq!(
        pairs.lines().count() as u64 - 1,
        summary["pairs"].as_u64().unwrap()
    );
    assert_eq!(summary["pairs"].as_u64().unwrap(), 12 * runs);
    // No staging directory is left behind.
    let hidden: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains("staging"))
        .collect();
    assert!(hidden.is_empty(), "{hidden:?}");
    // Into a directory without a campaign, a stopped one is the set (summary.json says so).
    let fresh = tmp("stop-fresh");
    let mut child = bin()
        .args(long_campaign(&fresh))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1500));
    assert_eq!(terminate(&mut child).code(), Some(130));
    assert_eq!(read(&fresh)["interrupted"], true);
}

/// A 100,000-run campaign into `out` (short steps, one thread): long enough to stop.
fn long_campaign(out: &Path) -> Vec<String> {
    let mut args: Vec<String> = [
        "simulate",
        "--out",
        s(out),
        "--runs",
        "100000",
        "--threads",
        "1",
    ]
    .iter()
    .map(|a| a.to_string())
    .collect();
    args.extend(SHORT.iter().map(|a| a.to_string()));
    args
}

/// SIGTERM to `child`, and its exit status (within a minute).
fn terminate(child: &mut Child) -> std::process::ExitStatus {
    let kill = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    wait_with_deadline(child, 60)
}

/// What a finished child wrote to its piped stderr.
fn child_output(mut child: Child) -> Output {
    let mut err = Vec::new();
    if let Some(mut e) = child.stderr.take() {
        let _ = e.read_to_end(&mut err);
    }
    Output {
        status: child.wait().unwrap(),
        stdout: Vec::new(),
        stderr: err,
    }
}

/// Case 4: two SIGINTs a few ms apart (a double Ctrl-C, or `timeout -s INT` signalling the
/// command and then its process group) are one request: the campaign finishes the run in
/// flight and keeps every completed run, in the directory, with its summary.
#[cfg(unix)]
#[test]
fn a_double_ctrl_c_within_half_a_second_keeps_the_completed_runs() {
    let dir = tmp("double-int");
    // Runs of 50 min of rig time (~0.1-0.3 s each here), no raw logs.
    let args = [
        "simulate",
        "--out",
        s(&dir),
        "--runs",
        "3000",
        "--threads",
        "1",
        "--no-raw",
        "--diameters",
        "12.7",
        "--wraps",
        "360",
        "--dwell-ms",
        "230000",
    ];
    for gap_ms in [1u64, 20] {
        let mut child = bin()
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(1500));
        for k in 0..2 {
            if k == 1 {
                std::thread::sleep(Duration::from_millis(gap_ms));
            }
            let ok = Command::new("kill")
                .args(["-INT", &child.id().to_string()])
                .status()
                .unwrap();
            assert!(ok.success());
        }
        let st = wait_with_deadline(&mut child, 120);
        let mut err = String::new();
        child
            .stderr
            .take()
            .unwrap()
            .read_to_string(&mut err)
            .unwrap();
        assert_eq!(st.code(), Some(130), "{err}");
        assert!(!err.contains("second signal"), "{err}");
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap())
                .unwrap();
        assert_eq!(summary["interrupted"], true);
        let runs = summary["runs"].as_u64().unwrap();
        assert!(runs >= 1, "{summary}");
        let pairs = std::fs::read_to_string(dir.join("pairs.csv")).unwrap();
        assert_eq!(pairs.lines().count() as u64 - 1, 12 * runs, "{summary}");
    }
}

#[test]
fn a_long_stream_stops_at_its_run_limit_with_no_false_truncation() {
    // The saved QEMU stream forty times over: 187 kB, frames across every 64 KiB read.
    let one = std::fs::read("tests/data/qemu-run.defmt").unwrap();
    let dir = tmp("rep");
    let rep = write(&dir, "rep.defmt", "");
    std::fs::write(&rep, one.repeat(40)).unwrap();
    let out = dir.join("out");
    let o = log_from(&rep, &out, &["--runs", "3", "--strict", "-q"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    // --runs counts complete runs: each copy's second run ends by over_force, so the three
    // complete ones come with the two cut short between them.
    let runs = summary["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 5, "{summary}");
    assert_eq!(runs.iter().filter(|r| r["complete"] == true).count(), 3);
    assert!(runs[4]["complete"] == true, "{summary}");
    assert!(summary["truncated_tail"].is_null(), "{summary}");
    // The whole stream, strictly: 80 runs, every frame whole.
    let o = log_from(&rep, &out, &["--overwrite", "--strict", "-q"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("80 run(s) (40 complete, 40 ended by a fault)"),
        "{}",
        stderr(&o)
    );
    // Empty: refused, with or without --strict (nothing replaced, nothing kept).
    let empty = write(&dir, "empty.defmt", "");
    let o = log_from(&empty, &dir.join("out-empty"), &["--strict"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("nothing was received"),
        "{}",
        stderr(&o)
    );
}

/// `capstan log` decoding the saved stream `from` (recorded QEMU firmware) into `out`.
fn log_from(from: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "log",
        "--elf",
        "tests/data/qemu-fw.elf",
        "--from",
        s(from),
        "--out",
        s(out),
    ];
    args.extend(extra);
    capstan(&args)
}

/// A plan stopped by a signal says so, and writes nothing: its directory keeps no file
/// (adversarial pass 2, 10b: it exited 130 without a word).
#[cfg(unix)]
#[test]
fn a_stopped_plan_says_so_and_writes_nothing() {
    let dir = tmp("plan-stopped");
    let mut child = plan_into(&dir, "8");
    std::thread::sleep(Duration::from_millis(1500));
    let st = terminate(&mut child);
    let out = child_output(child);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(st.code(), Some(130), "{err}");
    assert!(
        err.contains("stopped (SIGTERM): the plan was not finished, nothing was written"),
        "{err}"
    );
    // DIR did not exist: it still does not (not even holding a lock file).
    assert!(!dir.exists(), "{err}");
}

/// `plan --out DIR` checks DIR before it plans (adversarial read s35, D2: a user's own
/// plan.json was refused only after minutes of simulation, and the plan was thrown away).
/// With 1000 campaigns per protocol the planning would take far longer than the deadline.
#[test]
fn plan_refuses_a_directory_it_cannot_write_before_it_plans() {
    let dir = tmp("plan-foreign");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("plan.json"), "{\"my\": \"plan\"}").unwrap();
    let mut child = plan_into(&dir, "1000");
    let st = wait_with_deadline(&mut child, 60);
    let out = child_output(child);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!st.success());
    assert!(
        err.contains("plan.json is a file that `capstan plan` did not write"),
        "{err}"
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("plan.json")).unwrap(),
        "{\"my\": \"plan\"}"
    );
}

/// `capstan plan --out DIR --reps REPS` on the thesis data, started with piped output.
fn plan_into(dir: &Path, reps: &str) -> Child {
    bin()
        .args(["plan", "--out", s(dir), "--reps", reps])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}
