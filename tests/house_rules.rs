//! The house's layout rules (issue 40), checked on the source tree so a change that breaks one
//! fails `cargo test` rather than a later review:
//!
//! * the root crate (`src/`, the CLI) is at most 8 % of the workspace's Rust lines;
//! * no library crate depends on `anyhow` (typed errors at every library boundary; `anyhow` only
//!   in the CLI and in examples, tests and benches);
//! * no library returns `Result<_, String>`;
//! * no public function of `capstan-report` takes or returns a `serde_json::Value`;
//! * every workspace member takes the workspace lints (`missing_docs`);
//! * the README is a landing page (at most 200 lines) and `ARCHITECTURE.md` exists.
//!
//! Hand-written walking rather than a crate: the rules are a few lines of text matching over
//! our own tree, and `cargo metadata` would only add a subprocess.

use std::fs;
use std::path::{Path, PathBuf};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// Every `.rs` file under `dir`, skipping build output and npm's folder.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        let name = e.file_name();
        let name = name.to_string_lossy();
        if p.is_dir() {
            if !matches!(name.as_ref(), "target" | "node_modules" | ".git") {
                rust_files(&p, out);
            }
        } else if name.ends_with(".rs") {
            out.push(p);
        }
    }
}

fn lines(files: &[PathBuf]) -> usize {
    files
        .iter()
        .map(|f| fs::read_to_string(f).map_or(0, |s| s.lines().count()))
        .sum()
}

/// The workspace members' folders (relative), read from the root `Cargo.toml`'s `members`.
fn members() -> Vec<String> {
    let toml = fs::read_to_string(Path::new(ROOT).join("Cargo.toml")).unwrap();
    let line = toml
        .lines()
        .find(|l| l.trim_start().starts_with("members"))
        .expect("a members line");
    line.split('"')
        .skip(1)
        .step_by(2)
        .map(str::to_string)
        .collect()
}

/// The library members: every member but the CLI (`.`) and the binaries whose `anyhow` use is
/// their own `main` (none today besides the CLI).
fn libraries() -> Vec<String> {
    members().into_iter().filter(|m| m != ".").collect()
}

/// The `[dependencies]` table of a manifest (not dev- or build-dependencies).
fn dependencies_table(manifest: &str) -> String {
    let mut out = String::new();
    let mut inside = false;
    for l in manifest.lines() {
        let t = l.trim();
        if t.starts_with('[') {
            inside =
                t == "[dependencies]" || t.starts_with("[target.") && t.ends_with(".dependencies]");
            continue;
        }
        if inside {
            out.push_str(t);
            out.push('\n');
        }
    }
    out
}

#[test]
fn the_root_crate_is_thin() {
    let mut all = Vec::new();
    rust_files(Path::new(ROOT), &mut all);
    let mut root = Vec::new();
    rust_files(&Path::new(ROOT).join("src"), &mut root);
    let (all, root) = (lines(&all), lines(&root));
    let share = root as f64 / all as f64;
    assert!(
        share <= 0.08,
        "src/ (the CLI) has {root} of the workspace's {all} Rust lines ({:.1} %): at most 8 %; \
         library logic belongs in a crate under wire/, physics/, support/, firmware/, sim/, \
         science/ or host/",
        share * 100.0
    );
}

#[test]
fn no_library_depends_on_anyhow() {
    let offenders: Vec<_> = libraries()
        .into_iter()
        .filter(|m| {
            let manifest = fs::read_to_string(Path::new(ROOT).join(m).join("Cargo.toml")).unwrap();
            dependencies_table(&manifest)
                .lines()
                .any(|l| l.starts_with("anyhow"))
        })
        .collect();
    assert!(
        offenders.is_empty(),
        "anyhow in a library's [dependencies] (typed errors at library boundaries): {offenders:?}"
    );
}

#[test]
fn no_library_returns_a_string_error() {
    let mut hits = Vec::new();
    for m in libraries() {
        let mut files = Vec::new();
        rust_files(&Path::new(ROOT).join(&m).join("src"), &mut files);
        for f in files {
            let text = fs::read_to_string(&f).unwrap();
            // Joined so a signature split over lines is one string.
            let flat: String = text.split_whitespace().collect::<Vec<_>>().join(" ");
            let mut rest = flat.as_str();
            while let Some(i) = rest.find("Result<") {
                let tail = &rest[i + 7..];
                // The generic arguments up to the matching '>'.
                let mut depth = 1;
                let mut end = tail.len();
                for (j, c) in tail.char_indices() {
                    match c {
                        '<' => depth += 1,
                        '>' => {
                            depth -= 1;
                            if depth == 0 {
                                end = j;
                                break;
                            }
                        }
                        _ => {}
                    }
                }
                let args = &tail[..end];
                if args.ends_with(", String") || args.ends_with(",String") {
                    hits.push(format!("{}: Result<{args}>", f.display()));
                }
                rest = &tail[end.min(tail.len())..];
            }
        }
    }
    assert!(hits.is_empty(), "Result<_, String> in a library: {hits:#?}");
}

#[test]
fn the_report_api_takes_no_json_values() {
    let mut files = Vec::new();
    rust_files(&Path::new(ROOT).join("science/report/src"), &mut files);
    let mut hits = Vec::new();
    for f in files {
        let text = fs::read_to_string(&f).unwrap();
        let mut rest = text.as_str();
        while let Some(i) = rest.find("pub fn ") {
            let sig_end = rest[i..].find('{').map_or(rest.len(), |j| i + j);
            let sig = &rest[i..sig_end];
            if sig.contains("Value") {
                hits.push(format!(
                    "{}: {}",
                    f.display(),
                    sig.split_whitespace().collect::<Vec<_>>().join(" ")
                ));
            }
            rest = &rest[sig_end..];
        }
    }
    assert!(
        hits.is_empty(),
        "serde_json::Value in capstan-report's public functions: {hits:#?}"
    );
}

#[test]
fn every_member_takes_the_workspace_lints() {
    let root = fs::read_to_string(Path::new(ROOT).join("Cargo.toml")).unwrap();
    assert!(
        root.contains("missing_docs"),
        "[workspace.lints.rust] missing_docs"
    );
    let missing: Vec<_> = members()
        .into_iter()
        .filter(|m| {
            let manifest = fs::read_to_string(Path::new(ROOT).join(m).join("Cargo.toml")).unwrap();
            let lints = manifest.split("[lints]").nth(1).unwrap_or("");
            !lints
                .lines()
                .take_while(|l| {
                    !l.starts_with("[[") && !l.trim_start().starts_with("[") || l.trim().is_empty()
                })
                .any(|l| l.trim().replace(' ', "") == "workspace=true")
        })
        .collect();
    assert!(
        missing.is_empty(),
        "members without `[lints] workspace = true`: {missing:?}"
    );
}

#[test]
fn the_readme_is_a_landing_page() {
    let readme = fs::read_to_string(Path::new(ROOT).join("README.md")).unwrap();
    let n = readme.lines().count();
    assert!(
        n <= 200,
        "README.md has {n} lines: at most 200 (the manual is the book, docs/book)"
    );
    assert!(
        Path::new(ROOT).join("ARCHITECTURE.md").is_file(),
        "ARCHITECTURE.md"
    );
}
