//! The command line says one thing one way: `--version` names the commit every output's
//! provenance gives, every data command's help names the columns it reads, and the project's
//! citation is complete.

use std::process::Command;

fn capstan(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_capstan"))
        .args(args)
        .output()
        .expect("capstan runs")
}

/// The commit as `build.rs` names it: HEAD, with "-dirty" when tracked files differ from it.
fn git_head() -> Option<String> {
    let head = git(&["rev-parse", "HEAD"])?;
    match git(&["status", "--porcelain", "--untracked-files=no"]).filter(|s| !s.is_empty()) {
        Some(_) => Some(format!("{head}-dirty")),
        None => Some(head),
    }
}

fn git(args: &[&str]) -> Option<String> {
    let o = Command::new("git")
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .ok()?;
    o.status
        .success()
        .then(|| String::from_utf8_lossy(&o.stdout).trim().to_string())
}

#[test]
fn version_names_the_commit_the_provenance_gives() {
    let o = capstan(&["--version"]);
    assert!(o.status.success());
    let out = String::from_utf8_lossy(&o.stdout);
    let want = git_head().unwrap_or_else(|| "unknown".to_string());
    assert_eq!(
        out.trim(),
        format!("capstan {} (commit {want})", env!("CARGO_PKG_VERSION"))
    );
}

/// `CITATION.cff`: the software's version as Cargo.toml's, and every reference with a named
/// author (family and given names, not a placeholder) and a year.
#[test]
fn the_citation_names_the_thesis_author_and_year() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/CITATION.cff"))
        .expect("CITATION.cff");
    assert!(
        text.lines()
            .any(|l| l == format!("version: {}", env!("CARGO_PKG_VERSION"))),
        "the version is Cargo.toml's"
    );
    let refs = text
        .split_once("\nreferences:\n")
        .expect("a references section")
        .1;
    // One entry per `- type:` line.
    let mut entries: Vec<String> = Vec::new();
    for l in refs.lines() {
        if l.trim_start().starts_with("- type:") {
            entries.push(String::new());
        }
        if let Some(e) = entries.last_mut() {
            e.push_str(l);
            e.push('\n');
        }
    }
    assert!(!entries.is_empty());
    for e in entries {
        let value = |key: &str| {
            e.lines()
                .find_map(|l| l.trim().trim_start_matches("- ").strip_prefix(key))
                .map(|v| v.trim().trim_matches('"').to_string())
        };
        let family = value("family-names:").unwrap_or_default();
        let given = value("given-names:").unwrap_or_default();
        assert!(
            !family.is_empty() && !given.is_empty() && !e.contains("author ("),
            "a reference without a named author: {e}"
        );
        let year: u32 = value("year:").and_then(|y| y.parse().ok()).unwrap_or(0);
        assert!(
            (1900..=2100).contains(&year),
            "a reference without a year: {e}"
        );
    }
}

fn tmp(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("capstan-consistency-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Every command that reads data says in its help which columns it reads.
#[test]
fn every_data_command_lists_the_columns_it_reads() {
    for cmd in ["analyze", "diagnose", "discover", "plan"] {
        let o = capstan(&[cmd, "-h"]);
        let help = String::from_utf8_lossy(&o.stdout);
        for col in [
            "wrap_deg",
            "t1_n",
            "t2_n",
            "capstan_diameter_mm",
            "drive_v",
            "run",
            "step",
            "time_s",
            "capstan condition",
        ] {
            assert!(help.contains(col), "{cmd} -h does not name {col}:\n{help}");
        }
    }
    let o = capstan(&["condition", "--help"]);
    let help = String::from_utf8_lossy(&o.stdout);
    for what in [
        "time_s, t1_n, t2_n",
        "column number",
        "--skip-rows",
        "--header-row",
        "Run 2: Time",
    ] {
        assert!(
            help.contains(what),
            "condition --help does not say {what}:\n{help}"
        );
    }
    // --protocol-times wherever protocol times matter.
    for cmd in ["analyze", "diagnose", "discover"] {
        let help = String::from_utf8_lossy(&capstan(&[cmd, "-h"]).stdout).to_string();
        assert!(help.contains("--protocol-times"), "{cmd}");
    }
    // The duration's clock, said once where the option is.
    let help = String::from_utf8_lossy(&capstan(&["log", "--help"]).stdout).to_string();
    assert!(
        help.contains("of the wall clock from a board or a stream; with --sim, of the simulated board's own clock"),
        "{help}"
    );
}

/// A pairs file that is missing, or a directory, is said in one way by every command that
/// reads pairs (analyze said `cannot read X: …` and `Is a directory (os error 21)`), and
/// analyze leaves no output directory behind.
#[test]
fn a_missing_or_directory_data_file_is_said_alike_by_every_data_command() {
    let d = tmp("data-file");
    let missing = d.join("no-such.csv");
    let out = d.join("report");
    for (data, says) in [
        (&missing, "No such file or directory"),
        (&d, "is a directory, not a pairs CSV"),
    ] {
        let p = data.to_str().unwrap();
        let want = format!("error: {p}: {says}");
        for cmd in [
            &["analyze", "--out", out.to_str().unwrap()][..],
            &["diagnose"],
            &["discover"],
            &["plan", "--reps", "1"],
        ] {
            let mut args = cmd.to_vec();
            args.push(p);
            let o = capstan(&args);
            let err = String::from_utf8_lossy(&o.stderr);
            assert!(!o.status.success(), "{cmd:?} {p}: {err}");
            assert!(err.starts_with(&want), "{cmd:?} {p}: {err}");
            assert_eq!(err.lines().count(), 1, "{cmd:?} {p}: {err}");
        }
        assert!(!out.exists(), "analyze {p} made {}", out.display());
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// A file given as `--out` is named as a file (it said "cannot create the output directory:
/// File exists"), before any work.
#[test]
fn a_file_as_the_output_directory_is_named_as_one() {
    let d = tmp("out-file");
    let f = d.join("plan.txt");
    std::fs::write(&f, "mine").unwrap();
    for cmd in [
        &["plan", "--reps", "1", "--out"][..],
        &["discover", "--out"],
        &["analyze", "--out"],
    ] {
        let mut args = cmd.to_vec();
        args.push(f.to_str().unwrap());
        let o = capstan(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && err.contains("that is a file"),
            "{cmd:?}: {err}"
        );
    }
    assert_eq!(std::fs::read_to_string(&f).unwrap(), "mine");
    let _ = std::fs::remove_dir_all(&d);
}

/// Provenance in every output: discover --json and discover.json, and plan.json with the
/// seed of its simulated campaigns.
#[test]
fn discover_and_plan_outputs_carry_their_provenance_and_seed() {
    let d = tmp("provenance");
    let out = d.join("disc");
    let o = capstan(&["discover", "--json", "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let printed: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let written: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("discover.json")).unwrap()).unwrap();
    for v in [&printed, &written] {
        assert!(v["provenance"]["commit"].is_string(), "{v}");
        assert_eq!(v["provenance"]["input_sha256"].as_str().unwrap().len(), 64);
        assert!(v["data"]["warnings"].is_array());
    }
    let out = d.join("plan");
    let o = capstan(&[
        "plan",
        "--reps",
        "1",
        "--seed",
        "5",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let plan: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("plan.json")).unwrap()).unwrap();
    assert_eq!(
        (plan["seed"].as_u64(), plan["reps"].as_u64()),
        (Some(5), Some(1))
    );
    let _ = std::fs::remove_dir_all(&d);
}
