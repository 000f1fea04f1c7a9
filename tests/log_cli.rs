//! `capstan log` as a user runs it: the binary, its exit status, its messages and its files.

// The recorded stream and its tools, shared with the log session's own tests.
#[path = "../host/log/tests/support/mod.rs"]
mod log_support;

use log_support::{elf_path, split, stream};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

fn capstan(args: &[&str], stdin: Option<&[u8]>) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_capstan"));
    cmd.args(args)
        .stdin(if stdin.is_some() {
            Stdio::piped()
        } else {
            Stdio::null()
        })
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let mut child = cmd.spawn().expect("capstan runs");
    if let Some(data) = stdin {
        let mut pipe = child.stdin.take().unwrap();
        pipe.write_all(data).unwrap();
    }
    child.wait_with_output().unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn out_dir(name: &str) -> PathBuf {
    log_support::fresh_dir("cli", name)
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// `capstan log [FLAGS] --elf <the recorded firmware> --from FROM --out DIR [EXTRA]`.
fn decode(flags: &[&str], from: &str, dir: &Path, extra: &[&str], stdin: Option<&[u8]>) -> Output {
    let elf = elf_path();
    let mut args = vec!["log"];
    args.extend(flags);
    args.extend(["--elf", s(&elf), "--from", from, "--out", s(dir)]);
    args.extend(extra);
    capstan(&args, stdin)
}

#[test]
fn help_documents_the_board_flow() {
    let o = capstan(&["log", "--help"], None);
    assert!(o.status.success());
    let help = String::from_utf8_lossy(&o.stdout);
    for needle in [
        "--chip RP2040",
        "debug probe",
        "cargo build --release -p capstan-board --target thumbv6m-none-eabi",
        "Ctrl-C",
        "pairs.csv",
        "summary.json",
        "--from",
        "--no-flash",
        "--strict",
    ] {
        assert!(
            help.contains(needle),
            "`capstan log --help` lacks {needle:?}:\n{help}"
        );
    }
}

#[test]
fn a_saved_stream_is_decoded_into_the_run_files() {
    let dir = out_dir("file");
    let stream_path = log_support::data("qemu-run.defmt");
    let o = decode(&[], s(&stream_path), &dir, &[], None);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("run 1 step 1: T1 "), "{err}");
    assert!(err.contains("FAULT over_force at 1.302 s (run 2)"), "{err}");
    assert!(
        err.contains(
            "2 run(s) (1 complete, 1 ended by a fault), 4 pairs, 202 raw samples, 1 faults"
        ),
        "{err}"
    );
    for f in [
        "raw.csv",
        "pairs.csv",
        "faults.csv",
        "messages.txt",
        "summary.json",
    ] {
        assert!(dir.join(f).exists(), "{f}");
    }
    // Read from a file, the stream is not copied.
    assert!(!dir.join("stream.defmt").exists());
    let pairs = capstan_data::load_pairs(&dir.join("pairs.csv")).unwrap();
    assert_eq!(
        pairs.header.join(","),
        capstan_data::PAIRS_HEADER.join(",") + ",t2_target_n,boot"
    );
    assert_eq!(pairs.pairs.len(), 4);
    // Running again into the same directory is refused unless --overwrite.
    let again = decode(&[], s(&stream_path), &dir, &[], None);
    assert!(!again.status.success());
    assert!(stderr(&again).contains("--overwrite"), "{}", stderr(&again));
}

#[test]
fn stdin_works_and_flags_override_the_run_start_set_up() {
    let dir = out_dir("stdin");
    let set_up = ["--wrap-deg", "450", "--diameter-mm", "25.4"];
    let o = decode(&["--quiet"], "-", &dir, &set_up, Some(&stream()));
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("step 1"), "--quiet: {}", stderr(&o));
    let pairs = capstan_data::load_pairs(&dir.join("pairs.csv")).unwrap();
    assert!(pairs.pairs.iter().all(|p| p.wrap_deg == 450.0));
    assert!(pairs
        .pairs
        .iter()
        .all(|p| p.capstan_diameter_mm == Some(25.4)));
    assert!(pairs.pairs.iter().all(|p| p.drive_v == Some(10.0)));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["runs"][0]["wrap_deg"]["from"], "flag");
    assert_eq!(summary["runs"][0]["drive_v"]["from"], "run_start");
    // From stdin the bytes are kept, to decode again later.
    assert_eq!(std::fs::read(dir.join("stream.defmt")).unwrap(), stream());
}

/// `--drive-v` is recorded into pairs.csv and summary.json: a voltage outside the rig's drive
/// (0 to 13.2 V, as `condition`, `predict` and `simulate` say; it was checked only against
/// ±1000 V) is refused by name before the directory is made, and the top of the range is a
/// drive the rig runs, recorded as given.
#[test]
fn a_drive_the_rig_cannot_run_is_refused_and_its_top_recorded() {
    let stream_path = log_support::data("qemu-run.defmt");
    for (v, says) in [
        (
            "20",
            "--drive-v 20: the rig's drive gives 0 to 13.2 V (the firmware's full control \
             voltage times the amplifier's gain); pairs.csv would record a drive the rig cannot \
             run",
        ),
        ("13.3", "--drive-v 13.3: the rig's drive gives 0 to 13.2 V"),
        ("-1", "--drive-v -1: the rig's drive gives 0 to 13.2 V"),
        (
            "1e6",
            "--drive-v 1000000: the rig's drive gives 0 to 13.2 V",
        ),
        ("nan", "--drive-v NaN: the rig's drive gives 0 to 13.2 V"),
    ] {
        let dir = out_dir("drive-refused");
        let o = decode(&[], s(&stream_path), &dir, &["--drive-v", v], None);
        let err = stderr(&o);
        assert!(
            !o.status.success() && err.contains(says),
            "--drive-v {v}: {err}"
        );
        assert!(
            !dir.exists(),
            "--drive-v {v}: refused, yet {dir:?} was made"
        );
    }
    let dir = out_dir("drive-top");
    let o = decode(&[], s(&stream_path), &dir, &["--drive-v", "13.2"], None);
    assert!(o.status.success(), "{}", stderr(&o));
    let pairs = capstan_data::load_pairs(&dir.join("pairs.csv")).unwrap();
    assert_eq!(pairs.pairs.len(), 4);
    assert!(pairs.pairs.iter().all(|p| p.drive_v == Some(13.2)));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["runs"][0]["drive_v"]["from"], "flag");
    assert_eq!(summary["runs"][0]["drive_v"]["value"], 13.2);
}

#[test]
fn lost_records_are_reported_and_strict_makes_them_fail() {
    let frames = split(&stream());
    let damaged = frames.without(&[30, 31, 32]);
    let dir = out_dir("strict");
    let o = decode(&[], "-", &dir, &[], Some(&damaged));
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("LOST 3 record(s) after seq"),
        "{}",
        stderr(&o)
    );
    let dir2 = out_dir("strict2");
    let o = decode(&["--strict"], "-", &dir2, &[], Some(&damaged));
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.contains("--strict: 3 record(s) lost"), "{err}");
    // The files are there all the same.
    assert!(dir2.join("summary.json").exists());
}

#[test]
fn a_wrong_elf_or_a_foreign_stream_fails_with_a_message() {
    let dir = out_dir("wrong");
    // A small host ELF (the `capstan` binary itself is one too, but a release build with its
    // debug information is over 256 MiB and refused by its size before it is read).
    let host_elf = ["/bin/true", "/usr/bin/true"]
        .into_iter()
        .find(|p| std::path::Path::new(p).exists())
        .unwrap_or(env!("CARGO_BIN_EXE_capstan"));
    let o = capstan(
        &["log", "--elf", host_elf, "--from", "-", "--out", s(&dir)],
        Some(&stream()),
    );
    assert!(!o.status.success());
    assert!(stderr(&o).contains("has no defmt table"), "{}", stderr(&o));

    // Bytes that are not a defmt stream of this firmware at all.
    let mut junk = Vec::new();
    let mut x = 0x2545_f491_4f6c_dd1du64;
    for _ in 0..5000 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        junk.push((x >> 24) as u8);
    }
    let o = decode(&[], "-", &dir, &[], Some(&junk));
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.contains("no rig records in 5000 bytes"), "{err}");
    assert!(err.contains("did not decode"), "{err}");
}

#[test]
fn the_board_flow_says_what_is_missing() {
    // The QEMU build logs over semihosting, not RTT: refused before any probe is looked for,
    // and no session directory is left behind.
    let dir = out_dir("board");
    let o = capstan(
        &[
            "log",
            "--chip",
            "RP2040",
            "--elf",
            s(&elf_path()),
            "--out",
            s(&dir),
        ],
        None,
    );
    assert!(!o.status.success());
    let err = stderr(&o);
    if cfg!(feature = "probe") {
        assert!(
            err.contains("has no `_SEGGER_RTT` symbol: the firmware does not log over RTT"),
            "{err}"
        );
    } else {
        assert!(err.contains("without the `probe` feature"), "{err}");
    }
    assert!(!dir.exists());
    // --chip and --from exclude each other; one of them is needed.
    let o = capstan(&["log", "--elf", s(&elf_path()), "--out", s(&dir)], None);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--chip"), "{}", stderr(&o));
}

#[cfg(unix)]
#[test]
fn ctrl_c_keeps_everything_received_and_says_so() {
    let dir = out_dir("ctrlc");
    let bytes = stream();
    let mut child = Command::new(env!("CARGO_BIN_EXE_capstan"))
        .args([
            "log",
            "--elf",
            s(&elf_path()),
            "--from",
            "-",
            "--out",
            s(&dir),
        ])
        .stdin(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Half the stream, then the pipe stays open (a board still running) and Ctrl-C comes.
    let mut pipe = child.stdin.take().unwrap();
    pipe.write_all(&bytes[..bytes.len() / 2]).unwrap();
    pipe.flush().unwrap();
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(20);
    // Wait until what was sent has been written out: the session's files grow in its staging
    // directory and are moved into place when it ends.
    let live_raw = || -> usize {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            return 0;
        };
        entries
            .flatten()
            .filter(|e| {
                e.file_name()
                    .to_string_lossy()
                    .starts_with(".capstan-staging-")
            })
            .map(|e| {
                std::fs::read_to_string(e.path().join("raw.csv")).map_or(0, |r| r.lines().count())
            })
            .sum()
    };
    while live_raw() < 50 {
        assert!(std::time::Instant::now() < deadline, "capstan did not log");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let o = child.wait_with_output().unwrap();
    drop(pipe);
    let err = stderr(&o);
    // Half the stream holds no complete run: the session replaces nothing (the directory was
    // empty and stays so), and everything received is kept where the message says.
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(err.contains("interrupted (Ctrl-C)"), "{err}");
    let kept = err
        .split("what was received is kept in ")
        .nth(1)
        .and_then(|r| r.split(';').next())
        .unwrap_or_else(|| panic!("{err}"));
    let kept = Path::new(kept);
    assert!(!dir.join("summary.json").exists());
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(kept.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["stopped"], "interrupted (Ctrl-C)");
    let raw = std::fs::read_to_string(kept.join("raw.csv")).unwrap();
    assert_eq!(
        raw.lines().count() as u64 - 1,
        summary["records"]["raw"].as_u64().unwrap()
    );
    assert_eq!(
        std::fs::read(kept.join("stream.defmt")).unwrap(),
        &bytes[..bytes.len() / 2]
    );
}
