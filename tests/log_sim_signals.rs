//! `capstan log --sim` streams run by run and honours signals: Ctrl-C during `--runs 20
//! --overwrite` keeps the finished runs apart, replaces nothing and exits 130 (it ran all 20,
//! exited 0 and replaced the earlier session); SIGTERM in a long `--duration` stops within
//! seconds (it ran on for minutes); what cannot finish is refused before anything runs
//! (`--runs 1000000000` grew to 24 GB; `--duration 32000000` was silently cut to 49.7 days).

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

fn capstan() -> Command {
    Command::new(env!("CARGO_BIN_EXE_capstan"))
}

fn fresh(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("capstan-logsim-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Start `capstan ARGS` with stderr read line by line into a channel.
fn spawn(args: &[&str]) -> (Child, mpsc::Receiver<String>) {
    let mut child = capstan()
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let err = child.stderr.take().unwrap();
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(err).lines().map_while(Result::ok) {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    (child, rx)
}

fn signal(child: &Child, sig: &str) {
    let ok = Command::new("kill")
        .args([sig, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(ok.success());
}

/// Wait for the child's exit at most `limit`; its status code and every stderr line.
fn finish(mut child: Child, rx: &mpsc::Receiver<String>, limit: Duration) -> (i32, String) {
    let end = Instant::now() + limit;
    loop {
        if let Some(s) = child.try_wait().unwrap() {
            std::thread::sleep(Duration::from_millis(100));
            let rest: Vec<String> = rx.try_iter().collect();
            return (s.code().unwrap_or(-1), rest.join("\n"));
        }
        if Instant::now() > end {
            let _ = child.kill();
            panic!("capstan still running after {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

fn read(p: &Path) -> Vec<u8> {
    std::fs::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

#[test]
fn ctrl_c_keeps_the_finished_runs_apart_and_replaces_no_earlier_session() {
    let dir = fresh("ctrl-c");
    let (board, out) = (dir.join("board"), dir.join("session"));
    let (b, o) = (board.to_str().unwrap(), out.to_str().unwrap());
    // The person types both sensitivities first (a board runs nothing on its placeholder).
    for ch in ["t1", "t2"] {
        let key = format!("{ch}_n_per_count");
        let typed = capstan()
            .args(["rig", "--sim", b, "set", &key, "0.015"])
            .output()
            .unwrap();
        assert!(
            typed.status.success(),
            "{}",
            String::from_utf8_lossy(&typed.stderr)
        );
    }
    let first = capstan()
        .args(["log", "--sim", b, "--start", "--runs", "1", "--out", o])
        .output()
        .unwrap();
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    let before = (
        read(&out.join("pairs.csv")),
        read(&out.join("summary.json")),
    );
    let (child, rx) = spawn(&["log", "--sim", b, "--runs", "20", "--overwrite", "--out", o]);
    // Run 1's records arrive once it has ended: then Ctrl-C.
    let deadline = Instant::now() + Duration::from_secs(120);
    let mut seen = Vec::new();
    loop {
        let line = rx
            .recv_timeout(deadline.saturating_duration_since(Instant::now()))
            .unwrap_or_else(|_| panic!("no run started: {seen:?}"));
        let started = line.contains("capstan log: run 1 started") || line.contains("run 2 started");
        seen.push(line);
        if started {
            break;
        }
    }
    signal(&child, "-INT");
    let (code, err) = finish(child, &rx, Duration::from_secs(60));
    assert_eq!(code, 130, "{err}");
    assert!(err.contains("interrupted (Ctrl-C) after"), "{err}");
    // The earlier session is as it was, byte for byte.
    assert_eq!(read(&out.join("pairs.csv")), before.0);
    assert_eq!(read(&out.join("summary.json")), before.1);
    // The finished runs are kept where the message says, fewer than the 20 asked for.
    let kept = err
        .split("they are kept in ")
        .nth(1)
        .and_then(|r| r.split(';').next())
        .unwrap_or_else(|| panic!("{err}"));
    let s: serde_json::Value = serde_json::from_str(
        &String::from_utf8(read(&Path::new(kept).join("summary.json"))).unwrap(),
    )
    .unwrap();
    let complete = s["runs"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|r| r["complete"] == true)
        .count();
    assert!((1..20).contains(&complete), "{s}");
    assert_eq!(s["stopped"], "interrupted (Ctrl-C)");
    // The board goes on from where it was: another command on it replays the bench.
    let again = capstan()
        .args([
            "log",
            "--sim",
            b,
            "--runs",
            "1",
            "--out",
            dir.join("s2").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(
        again.status.success(),
        "{}",
        String::from_utf8_lossy(&again.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn sigterm_in_a_long_duration_stops_within_seconds() {
    let dir = fresh("sigterm");
    let (board, out) = (dir.join("board"), dir.join("session"));
    // 46 days of the board's time: minutes of this machine's.
    let (child, rx) = spawn(&[
        "log",
        "--sim",
        board.to_str().unwrap(),
        "--duration",
        "4000000",
        "--out",
        out.to_str().unwrap(),
    ]);
    std::thread::sleep(Duration::from_millis(1500));
    signal(&child, "-TERM");
    let t = Instant::now();
    let (code, err) = finish(child, &rx, Duration::from_secs(30));
    assert_eq!(code, 130, "{err}");
    assert!(t.elapsed() < Duration::from_secs(10), "{:?}", t.elapsed());
    assert!(err.contains("SIGTERM"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn what_cannot_finish_is_refused_before_anything_runs() {
    let dir = fresh("refused");
    let (board, out) = (dir.join("board"), dir.join("session"));
    for (flag, value, says) in [
        ("--runs", "1000000000", "at most 100 runs per command"),
        ("--duration", "32000000", "at most 4294967.295 s"),
    ] {
        let o = capstan()
            .args([
                "log",
                "--sim",
                board.to_str().unwrap(),
                flag,
                value,
                "--out",
                out.to_str().unwrap(),
            ])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(says), "{err}");
        assert!(!board.exists() && !out.exists(), "{err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
