//! The commit journal: publish a staged set, and roll an interrupted commit forward.

use super::{manifest_name, COMMIT, JOURNAL_MANIFEST, MANIFEST_PREFIX};
use anyhow::{bail, Context};
use serde::{Deserialize, Serialize};
use std::collections::BTreeSet;
use std::io;
use std::path::{Component, Path};

/// A point where the process may die (tests inject one; the real commit never does).
pub(crate) trait Crash {
    /// Called before every change to the disk.
    fn step(&mut self) -> io::Result<()>;
}

/// The real commit.
pub(crate) struct NoCrash;

impl Crash for NoCrash {
    fn step(&mut self) -> io::Result<()> {
        Ok(())
    }
}

/// What a set holds, and which command wrote it.
#[derive(Serialize, Deserialize, Debug, Default)]
struct Manifest {
    #[serde(default)]
    kind: String,
    written_by: String,
    files: Vec<String>,
}

/// A name we write: relative, plain components, not one of our own control files.
pub(crate) fn check_name(rel: &str) -> anyhow::Result<()> {
    let p = Path::new(rel);
    let plain = p.components().all(|c| matches!(c, Component::Normal(_)));
    if rel.is_empty() || !plain || rel.starts_with(".capstan") {
        bail!("`{rel}` is not a file name an output set may hold");
    }
    Ok(())
}

/// The set `files` of command `kind`: make it durable, check that every file can be moved
/// into place, write the manifest, turn the staging directory into the journal, and roll it
/// forward. `unsynced`: files written by streaming writers (the others were synced whole).
pub(crate) fn publish(
    staging: &Path,
    dir: &Path,
    kind: &str,
    files: &[String],
    unsynced: &[String],
    crash: &mut dyn Crash,
) -> anyhow::Result<()> {
    refuse_others(dir, kind, files)?;
    refuse_foreign(dir, kind, files)?;
    for f in unsynced {
        sync(&staging.join(f))?;
    }
    let mut dirs: BTreeSet<&Path> = files.iter().filter_map(|f| Path::new(f).parent()).collect();
    dirs.insert(Path::new(""));
    for d in dirs {
        sync_dir(&staging.join(d));
    }
    // Everything that could stop the moves is checked before the point of no return.
    for f in files {
        ensure_parents(dir, f)?;
        let target = dir.join(f);
        if std::fs::symlink_metadata(&target).is_ok_and(|m| m.is_dir()) {
            bail!(
                "{} is a directory: it cannot be replaced by a file",
                target.display()
            );
        }
    }
    let m = Manifest {
        kind: kind.to_string(),
        written_by: std::env::args().collect::<Vec<_>>().join(" "),
        files: files.to_vec(),
    };
    crash.step()?;
    let mpath = staging.join(JOURNAL_MANIFEST);
    std::fs::write(&mpath, serde_json::to_string_pretty(&m)? + "\n")
        .with_context(|| format!("cannot write {}", mpath.display()))?;
    sync(&mpath)?;
    crash.step()?;
    std::fs::rename(staging, dir.join(COMMIT))
        .with_context(|| format!("cannot move {} into place", staging.display()))?;
    sync_dir(dir);
    roll_forward(dir, crash)
}

/// Finish the commit journalled in `dir/.capstan-commit`: idempotent, so a commit
/// interrupted at any step is finished by running this again.
pub(crate) fn roll_forward(dir: &Path, crash: &mut dyn Crash) -> anyhow::Result<()> {
    let journal = dir.join(COMMIT);
    let new = match read_manifest(&journal.join(JOURNAL_MANIFEST)) {
        Some(m) => m,
        None => {
            // The manifest was moved: only (empty) directories are left.
            crash.step()?;
            std::fs::remove_dir_all(&journal)
                .with_context(|| format!("cannot remove {}", journal.display()))?;
            return Ok(());
        }
    };
    let current = dir.join(manifest_name(&new.kind));
    let old = read_manifest(&current).unwrap_or_default();
    for f in &new.files {
        let src = journal.join(f);
        if std::fs::symlink_metadata(&src).is_err() {
            continue; // moved already
        }
        ensure_parents(dir, f)?;
        crash.step()?;
        std::fs::rename(&src, dir.join(f))
            .with_context(|| format!("cannot move {} into place", dir.join(f).display()))?;
    }
    let keep: BTreeSet<&String> = new.files.iter().collect();
    for f in old.files.iter().filter(|f| !keep.contains(f)) {
        let p = dir.join(f);
        // Only a regular file is ours: a link or directory someone put there is theirs.
        if std::fs::symlink_metadata(&p).is_ok_and(|m| m.is_file()) {
            crash.step()?;
            std::fs::remove_file(&p).with_context(|| format!("cannot remove {}", p.display()))?;
        }
    }
    crash.step()?;
    std::fs::rename(journal.join(JOURNAL_MANIFEST), &current)
        .with_context(|| format!("cannot write {}", current.display()))?;
    sync_dir(dir);
    crash.step()?;
    std::fs::remove_dir_all(&journal)
        .with_context(|| format!("cannot remove {}", journal.display()))?;
    Ok(())
}

/// Another command's results in `dir` that this set would replace: refused, naming them (a
/// logged session cannot be made again; a campaign's pairs are another command's input).
pub(crate) fn refuse_others(dir: &Path, kind: &str, names: &[String]) -> anyhow::Result<()> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Ok(());
    };
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if !name.starts_with(MANIFEST_PREFIX) || name == manifest_name(kind) {
            continue;
        }
        let Some(m) = read_manifest(&e.path()) else {
            continue;
        };
        let clash: Vec<&String> = names.iter().filter(|n| m.files.contains(n)).collect();
        if let Some(first) = clash.first() {
            bail!(
                "{} holds the results of `capstan {}` ({first}{}): `capstan {kind}` would replace \
                 them; choose another output directory",
                dir.display(),
                m.kind,
                if clash.len() > 1 { ", ..." } else { "" }
            );
        }
    }
    Ok(())
}

/// A file of `names` that is in `dir` but that no manifest of `kind` lists: the user's own (a
/// `pairs.csv` of their own, a link they made), or one written without a manifest. Refused:
/// capstan replaces only what it wrote.
pub(crate) fn refuse_foreign(dir: &Path, kind: &str, names: &[String]) -> anyhow::Result<()> {
    let ours = read_manifest(&dir.join(manifest_name(kind))).unwrap_or_default();
    for n in names {
        let p = dir.join(n);
        let Ok(m) = std::fs::symlink_metadata(&p) else {
            continue;
        };
        if ours.files.contains(n) && m.is_file() {
            continue;
        }
        let what = if m.file_type().is_symlink() {
            "a symbolic link"
        } else if m.is_dir() {
            "a directory"
        } else {
            "a file"
        };
        bail!(
            "{} is {what} that `capstan {kind}` did not write (no manifest of it lists it): \
             capstan never replaces what it did not write; move it away, or choose another \
             output directory",
            p.display()
        );
    }
    Ok(())
}

/// A manifest, if it is there and readable; names that are not ours are dropped.
fn read_manifest(path: &Path) -> Option<Manifest> {
    let text = std::fs::read_to_string(path).ok()?;
    let mut m: Manifest = serde_json::from_str(&text).ok()?;
    m.files.retain(|f| check_name(f).is_ok());
    Some(m)
}

/// The parent directories of `rel` inside `dir`: created if missing, refused if one is a
/// symbolic link (writing through it would write outside the output directory).
fn ensure_parents(dir: &Path, rel: &str) -> anyhow::Result<()> {
    let mut p = dir.to_path_buf();
    let comps: Vec<_> = Path::new(rel).components().collect();
    for c in &comps[..comps.len().saturating_sub(1)] {
        p.push(c);
        match std::fs::symlink_metadata(&p) {
            Ok(m) if m.file_type().is_symlink() => bail!(
                "{} is a symbolic link: capstan does not write through it (remove it, or \
                 choose another output directory)",
                p.display()
            ),
            Ok(m) if m.is_dir() => {}
            Ok(_) => bail!("{} is a file where a directory is needed", p.display()),
            Err(_) => {
                std::fs::create_dir(&p).with_context(|| format!("cannot create {}", p.display()))?
            }
        }
    }
    Ok(())
}

fn sync(path: &Path) -> anyhow::Result<()> {
    std::fs::File::open(path)
        .and_then(|f| f.sync_all())
        .with_context(|| format!("cannot write {}", path.display()))
}

/// Make the renames in `dir` durable (best effort: not every file system allows it).
fn sync_dir(dir: &Path) {
    if let Ok(f) = std::fs::File::open(dir) {
        let _ = f.sync_all();
    }
}
