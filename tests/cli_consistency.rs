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

fn git_head() -> Option<String> {
    let o = Command::new("git")
        .args(["rev-parse", "HEAD"])
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
