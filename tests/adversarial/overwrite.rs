//! `capstan log --overwrite` over a good recorded session, against every class of bad stream,
//! interrupted at several points: the old session is byte-identical afterwards (case 1), and
//! what the bad session received is kept apart, where the message says.

use super::{checked, scratch};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::Duration;

const ELF: &str = "tests/data/qemu-fw.elf";
const STREAM: &str = "tests/data/qemu-run.defmt";

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Every file under `dir` but the lock (rewritten by every process) and kept sets, with its
/// bytes.
fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    fn walk(root: &Path, d: &Path, out: &mut BTreeMap<PathBuf, Vec<u8>>) {
        for e in std::fs::read_dir(d).unwrap().flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            if name == ".capstan.lock" || name.starts_with("incomplete-") {
                continue;
            }
            let p = e.path();
            if p.is_dir() {
                walk(root, &p, out);
            } else {
                out.insert(
                    p.strip_prefix(root).unwrap().into(),
                    std::fs::read(&p).unwrap(),
                );
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

/// A directory holding a good recorded session (from the stream given on stdin, so
/// `stream.defmt` is part of it).
fn good_session(name: &str) -> PathBuf {
    let d = scratch(name).join("session");
    let o = log_stdin(&d, &std::fs::read(STREAM).unwrap(), &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    d
}

fn log_stdin(out: &Path, bytes: &[u8], extra: &[&str]) -> Output {
    let mut args = vec!["log", "--elf", ELF, "--from", "-", "--out", s(out), "-q"];
    args.extend_from_slice(extra);
    let mut child = Command::new(env!("CARGO_BIN_EXE_capstan"))
        .args(&args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child.stdin.take().unwrap().write_all(bytes).unwrap();
    child.wait_with_output().unwrap()
}

/// `bytes` on stdin, the pipe kept open, then `signals` (each `(name, after)`): the session is
/// interrupted with what it received so far.
fn log_interrupted(out: &Path, bytes: &[u8], signals: &[(&str, u64)]) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_capstan"))
        .args([
            "log",
            "--elf",
            ELF,
            "--from",
            "-",
            "--out",
            s(out),
            "--overwrite",
            "-q",
        ])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut pipe = child.stdin.take().unwrap();
    pipe.write_all(bytes).unwrap();
    pipe.flush().unwrap();
    // Let the bytes be read and written out before the signal.
    std::thread::sleep(Duration::from_millis(400));
    for (sig, after_ms) in signals {
        std::thread::sleep(Duration::from_millis(*after_ms));
        let ok = Command::new("kill")
            .args([&format!("-{sig}"), &child.id().to_string()])
            .status()
            .unwrap();
        assert!(ok.success());
    }
    let o = child.wait_with_output().unwrap();
    drop(pipe);
    o
}

fn bad_file(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// The session in `d` is as `before`; the command failed, and said the directory is as it was.
fn untouched(d: &Path, before: &BTreeMap<PathBuf, Vec<u8>>, o: &Output, what: &str) {
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{what}: {e}");
    assert!(!e.contains("panicked"), "{what}: {e}");
    assert!(
        snapshot(d) == *before,
        "{what}: the old session changed: {e}"
    );
    checked();
}

#[cfg(unix)]
#[test]
fn a_bad_or_interrupted_overwrite_leaves_the_recorded_session_byte_identical() {
    let d = good_session("overwrite");
    let before = snapshot(&d);
    assert!(
        before.contains_key(Path::new("pairs.csv"))
            && before.contains_key(Path::new("stream.defmt"))
    );
    let work = d.parent().unwrap().to_path_buf();
    let good = std::fs::read(STREAM).unwrap();
    let mut junk = Vec::new();
    let mut x = 0x2545_f491_4f6c_dd1du64;
    for _ in 0..5000 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        junk.push((x >> 24) as u8);
    }
    // The recorded stream holds two runs; the first ends (its run_end record) between bytes
    // 3560 and 3580: every cut below is inside it.
    let end = 3560;
    let mut damaged = good[..3600].to_vec();
    for b in &mut damaged[3500..] {
        *b ^= 0x5a; // the first run's last records, its run_end among them
    }
    let mut files: Vec<(&str, Vec<u8>)> = vec![
        ("random.defmt", junk),
        ("seven.defmt", vec![1, 2, 3, 4, 5, 6, 7]),
        ("zeros.defmt", vec![0; 10_000]),
        ("empty.defmt", Vec::new()),
        ("one-byte.defmt", vec![0x42]),
        ("damaged-end.defmt", damaged),
    ];
    // The good stream cut inside its run, at several points.
    for cut in [1, 37, end / 5, end / 2, end - 200, end] {
        files.push(("cut.defmt", good[..cut].to_vec()));
    }
    for (name, bytes) in &files {
        let f = bad_file(&work, name, bytes);
        let o = Command::new(env!("CARGO_BIN_EXE_capstan"))
            .args([
                "log",
                "--elf",
                ELF,
                "--from",
                s(&f),
                "--out",
                s(&d),
                "--overwrite",
                "-q",
            ])
            .output()
            .unwrap();
        untouched(&d, &before, &o, name);
        // Also through stdin (the session then keeps a copy of what it received).
        untouched(&d, &before, &log_stdin(&d, bytes, &["--overwrite"]), name);
    }
    // A directory, a host binary as the ELF: refused before anything is opened.
    let o = Command::new(env!("CARGO_BIN_EXE_capstan"))
        .args([
            "log",
            "--elf",
            ELF,
            "--from",
            s(&work),
            "--out",
            s(&d),
            "--overwrite",
        ])
        .output()
        .unwrap();
    untouched(&d, &before, &o, "a directory");
    let o = Command::new(env!("CARGO_BIN_EXE_capstan"))
        .args([
            "log",
            "--elf",
            env!("CARGO_BIN_EXE_capstan"),
            "--from",
            STREAM,
            "--out",
            s(&d),
            "--overwrite",
        ])
        .output()
        .unwrap();
    untouched(&d, &before, &o, "a host ELF");
    // Interrupted at several points: before any data, inside the run; by SIGINT, SIGTERM, and
    // a double Ctrl-C (two signals 5 ms apart count as one).
    for cut in [0, 100, end / 3, end - 10] {
        for signals in [&[("INT", 0)][..], &[("TERM", 0)], &[("INT", 0), ("INT", 5)]] {
            let o = log_interrupted(&d, &good[..cut], signals);
            assert_eq!(
                o.status.code(),
                Some(130),
                "{}",
                String::from_utf8_lossy(&o.stderr)
            );
            untouched(&d, &before, &o, &format!("cut at {cut}, {signals:?}"));
            let e = String::from_utf8_lossy(&o.stderr);
            if cut > 0 {
                // What was received is kept, where the message says, byte for byte.
                let kept = e.split("what was received is kept in ").nth(1).unwrap();
                let kept = Path::new(kept.split(';').next().unwrap());
                assert_eq!(
                    std::fs::read(kept.join("stream.defmt")).unwrap(),
                    &good[..cut]
                );
            } else {
                assert!(e.contains("nothing was received"), "{e}");
            }
        }
    }
    // A good stream does replace it (two runs now), and --allow-empty replaces it even with
    // none.
    let two = [good.clone(), good.clone()].concat();
    let o = log_stdin(&d, &two, &["--overwrite"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(snapshot(&d) != before);
    let o = log_stdin(&d, &[], &["--overwrite", "--allow-empty"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary = std::fs::read_to_string(d.join("summary.json")).unwrap();
    assert!(summary.contains("\"bytes\": 0"), "{summary}");
    checked();
}
