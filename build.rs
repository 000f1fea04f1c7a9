//! Embeds the git commit the `capstan` binary is built from (`CAPSTAN_GIT_COMMIT`, for the
//! provenance every output carries), or "unknown" outside a git checkout or without git; with
//! "-dirty" after it (as `git describe --dirty` marks it) when tracked files differ from that
//! commit, so an output made by a binary built from modified sources does not name a commit
//! that never held them. Runs git at build time only; nothing runs at run time.

use std::process::Command;

fn git(args: &[&str]) -> Option<String> {
    let out = Command::new("git").args(args).output().ok()?;
    if !out.status.success() {
        return None;
    }
    let s = String::from_utf8(out.stdout).ok()?.trim().to_string();
    (!s.is_empty()).then_some(s)
}

fn main() {
    let commit = match git(&["rev-parse", "HEAD"]) {
        None => "unknown".to_string(),
        Some(c) => match git(&["status", "--porcelain", "--untracked-files=no"]) {
            Some(_) => format!("{c}-dirty"),
            None => c,
        },
    };
    println!("cargo:rustc-env=CAPSTAN_GIT_COMMIT={commit}");
    // Rebuild when HEAD moves (a commit, a checkout): HEAD itself and the branch it names.
    if let Some(head) = git(&["rev-parse", "--git-path", "HEAD"]) {
        println!("cargo:rerun-if-changed={head}");
    }
    if let Some(r) = git(&["symbolic-ref", "-q", "HEAD"]) {
        if let Some(p) = git(&["rev-parse", "--git-path", &r]) {
            println!("cargo:rerun-if-changed={p}");
        }
    }
    if let Some(p) = git(&["rev-parse", "--git-path", "packed-refs"]) {
        println!("cargo:rerun-if-changed={p}");
    }
    // And when a tracked file may have changed: the index, and the sources the binary is
    // built from (cargo scans a directory's files; sim/emu holds node_modules, not them).
    if let Some(p) = git(&["rev-parse", "--git-path", "index"]) {
        println!("cargo:rerun-if-changed={p}");
    }
    for dir in [
        "src",
        "science",
        "host",
        "physics",
        "wire",
        "support",
        "firmware",
        "sim/host",
        "sim/plant",
        "sim/board",
        "sim/qemu",
        "data",
        "Cargo.toml",
        "Cargo.lock",
    ] {
        println!("cargo:rerun-if-changed={dir}");
    }
    println!("cargo:rerun-if-changed=build.rs");
}
