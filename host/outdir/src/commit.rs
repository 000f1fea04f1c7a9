//! The commit journal: publish a staged set, and roll an interrupted commit forward.

use super::{manifest_name, COMMIT, JOURNAL_MANIFEST, MANIFEST_PREFIX};
use crate::OutDirError;
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
pub(crate) fn check_name(rel: &str) -> Result<(), OutDirError> {
    let p = Path::new(rel);
    let plain = p.components().all(|c| matches!(c, Component::Normal(_)));
    if rel.is_empty() || !plain || rel.starts_with(".capstan") {
        return Err(OutDirError::BadName(rel.to_string()));
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
) -> Result<(), OutDirError> {
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
            return Err(OutDirError::DirectoryForFile { path: target });
        }
    }
    let m = Manifest {
        kind: kind.to_string(),
        written_by: std::env::args().collect::<Vec<_>>().join(" "),
        files: files.to_vec(),
    };
    crash.step().map_err(OutDirError::Crash)?;
    let mpath = staging.join(JOURNAL_MANIFEST);
    std::fs::write(&mpath, serde_json::to_string_pretty(&m)? + "\n")
        .map_err(|source| io("write", &mpath, source))?;
    sync(&mpath)?;
    crash.step().map_err(OutDirError::Crash)?;
    std::fs::rename(staging, dir.join(COMMIT)).map_err(|source| OutDirError::Move {
        path: staging.to_path_buf(),
        source,
    })?;
    sync_dir(dir);
    roll_forward(dir, crash)
}

/// Finish the commit journalled in `dir/.capstan-commit`: idempotent, so a commit
/// interrupted at any step is finished by running this again.
pub(crate) fn roll_forward(dir: &Path, crash: &mut dyn Crash) -> Result<(), OutDirError> {
    let journal = dir.join(COMMIT);
    let new = match read_manifest(&journal.join(JOURNAL_MANIFEST)) {
        Some(m) => m,
        None => {
            // The manifest was moved: only (empty) directories are left.
            crash.step().map_err(OutDirError::Crash)?;
            std::fs::remove_dir_all(&journal).map_err(|source| io("remove", &journal, source))?;
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
        crash.step().map_err(OutDirError::Crash)?;
        std::fs::rename(&src, dir.join(f)).map_err(|source| OutDirError::Move {
            path: dir.join(f),
            source,
        })?;
    }
    let keep: BTreeSet<&String> = new.files.iter().collect();
    for f in old.files.iter().filter(|f| !keep.contains(f)) {
        let p = dir.join(f);
        // Only a regular file is ours: a link or directory someone put there is theirs.
        if std::fs::symlink_metadata(&p).is_ok_and(|m| m.is_file()) {
            crash.step().map_err(OutDirError::Crash)?;
            std::fs::remove_file(&p).map_err(|source| io("remove", &p, source))?;
        }
    }
    crash.step().map_err(OutDirError::Crash)?;
    std::fs::rename(journal.join(JOURNAL_MANIFEST), &current)
        .map_err(|source| io("write", &current, source))?;
    sync_dir(dir);
    crash.step().map_err(OutDirError::Crash)?;
    std::fs::remove_dir_all(&journal).map_err(|source| io("remove", &journal, source))?;
    Ok(())
}

/// Another command's results in `dir` that this set would replace: refused, naming them (a
/// logged session cannot be made again; a campaign's pairs are another command's input).
pub(crate) fn refuse_others(dir: &Path, kind: &str, names: &[String]) -> Result<(), OutDirError> {
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
            return Err(OutDirError::OthersResults {
                dir: dir.to_path_buf(),
                other: m.kind,
                first: first.to_string(),
                more: clash.len() > 1,
                kind: kind.to_string(),
            });
        }
    }
    Ok(())
}

/// A file of `names` that is in `dir` but that no manifest of `kind` lists: the user's own (a
/// `pairs.csv` of their own, a link they made), or one written without a manifest. Refused:
/// capstan replaces only what it wrote.
pub(crate) fn refuse_foreign(dir: &Path, kind: &str, names: &[String]) -> Result<(), OutDirError> {
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
        return Err(OutDirError::Foreign {
            path: p,
            what,
            kind: kind.to_string(),
        });
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
fn ensure_parents(dir: &Path, rel: &str) -> Result<(), OutDirError> {
    let mut p = dir.to_path_buf();
    let comps: Vec<_> = Path::new(rel).components().collect();
    for c in &comps[..comps.len().saturating_sub(1)] {
        p.push(c);
        match std::fs::symlink_metadata(&p) {
            Ok(m) if m.file_type().is_symlink() => return Err(OutDirError::Symlink { path: p }),
            Ok(m) if m.is_dir() => {}
            Ok(_) => return Err(OutDirError::FileForParent { path: p }),
            Err(_) => std::fs::create_dir(&p).map_err(|source| io("create", &p, source))?,
        }
    }
    Ok(())
}

fn sync(path: &Path) -> Result<(), OutDirError> {
    std::fs::File::open(path)
        .and_then(|f| f.sync_all())
        .map_err(|source| io("write", path, source))
}

/// `cannot {action} {path}`.
pub(crate) fn io(action: &'static str, path: &Path, source: std::io::Error) -> OutDirError {
    OutDirError::Io {
        action,
        path: path.to_path_buf(),
        source,
    }
}

/// Make the renames in `dir` durable (best effort: not every file system allows it).
fn sync_dir(dir: &Path) {
    if let Ok(f) = std::fs::File::open(dir) {
        let _ = f.sync_all();
    }
}
