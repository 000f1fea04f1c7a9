//! One output set being written: files go into a staging directory inside the output
//! directory; [`Staged::commit`] replaces the previous set with them, dropping without a
//! commit discards them, or, once the command has done work worth keeping
//! ([`Staged::keep_on_failure`]), keeps them under a visible name and tells the caller where.
//! A commit that fails keeps the set the same way. Every open set is registered, so that a process
//! about to exit at once (a second signal) can keep its work where it says ([`keep_open_sets`]).

use super::{commit, OutputDir, INCOMPLETE_PREFIX, STAGING_PREFIX};
use crate::commit::io;
use crate::{OutDirError, Result};
use std::collections::BTreeSet;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The staging directories of this process's open sets, each with where its work is kept.
static OPEN_SETS: Mutex<Vec<(PathBuf, PathBuf)>> = Mutex::new(Vec::new());

fn open_sets() -> std::sync::MutexGuard<'static, Vec<(PathBuf, PathBuf)>> {
    OPEN_SETS.lock().unwrap_or_else(|e| e.into_inner())
}

/// Keep the work of every set this process has open under its visible name
/// (`DIR/incomplete-<id>`), for a process about to exit without its destructors (a second
/// signal); returns where each went. A set being committed (its staging directory already
/// the journal) is not moved: the next run into its directory finishes the commit.
pub fn keep_open_sets() -> Vec<PathBuf> {
    keep_sets(|_| true)
}

/// [`keep_open_sets`] for the sets whose staging directory `which` selects.
pub(super) fn keep_sets(which: impl Fn(&Path) -> bool) -> Vec<PathBuf> {
    let mut kept = Vec::new();
    open_sets().retain(|(staging, to)| {
        if !which(staging) {
            return true;
        }
        if std::fs::rename(staging, to).is_ok() {
            kept.push(to.clone());
        }
        false
    });
    kept
}

/// An output set being written.
#[derive(Debug)]
pub struct Staged {
    out: OutputDir,
    path: PathBuf,
    id: String,
    files: BTreeSet<String>,
    /// Files written by streaming writers, synced at the commit.
    streamed: BTreeSet<String>,
    done: bool,
    /// Keep the work on failure, and say where with this (`None`: discard it).
    keep_on_failure: Option<fn(&Path)>,
}

impl Staged {
    pub(super) fn new(out: OutputDir) -> Result<Staged> {
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos());
        let id = format!("{}-{nanos}", std::process::id());
        let path = out.path().join(format!("{STAGING_PREFIX}{id}"));
        std::fs::create_dir(&path)
            .map_err(|source| io("write to the output directory", out.path(), source))?;
        let kept = out.path().join(format!("{INCOMPLETE_PREFIX}{id}"));
        open_sets().push((path.clone(), kept));
        Ok(Staged {
            out,
            path,
            id,
            files: BTreeSet::new(),
            streamed: BTreeSet::new(),
            done: false,
            keep_on_failure: None,
        })
    }

    /// If this set is dropped without a commit (an error), or its commit fails, keep what was
    /// written under `DIR/incomplete-<id>` instead of discarding it (a logged session is data
    /// that cannot be made again; a campaign's runs and an analysis took time to make). A set
    /// dropped is kept silently, so `say` is handed where it went (the program says it); a
    /// failed commit says it in its error.
    pub fn keep_on_failure(&mut self, say: fn(&Path)) {
        self.keep_on_failure = Some(say);
    }

    /// Where this set's work goes if it is kept.
    pub fn kept_path(&self) -> PathBuf {
        self.out
            .path()
            .join(format!("{INCOMPLETE_PREFIX}{}", self.id))
    }

    /// Keep this set under `DIR/incomplete-<id>` now, without committing it (the command
    /// decided it must not replace the previous set); returns where it went.
    pub fn keep(mut self) -> Result<PathBuf> {
        let kept = self.kept_path();
        self.done = true;
        self.forget();
        std::fs::rename(&self.path, &kept).map_err(|source| OutDirError::Keep {
            path: self.path.clone(),
            kept: kept.clone(),
            source,
        })?;
        Ok(kept)
    }

    /// Discard this set (nothing in it is worth keeping).
    pub fn discard(mut self) {
        self.done = true;
        self.forget();
        let _ = std::fs::remove_dir_all(&self.path);
    }

    /// No longer an open set of this process.
    fn forget(&self) {
        open_sets().retain(|(p, _)| p != &self.path);
    }

    /// The staging path of `rel` (a relative name such as `raw/d12.7_run1.csv`), registered as
    /// part of the set; its parent directories are created.
    pub fn path_of(&mut self, rel: &str) -> Result<PathBuf> {
        commit::check_name(rel)?;
        let p = self.path.join(rel);
        if let Some(parent) = p.parent() {
            std::fs::create_dir_all(parent).map_err(|source| io("create", parent, source))?;
        }
        self.files.insert(rel.to_string());
        Ok(p)
    }

    /// Create `rel` in the set, buffered.
    pub fn create(&mut self, rel: &str) -> Result<BufWriter<File>> {
        let p = self.path_of(rel)?;
        self.streamed.insert(rel.to_string());
        let f = File::create(&p).map_err(|source| io("write", &p, source))?;
        Ok(BufWriter::new(f))
    }

    /// Write `rel` whole.
    pub fn write(&mut self, rel: &str, bytes: &[u8]) -> Result<()> {
        let p = self.path_of(rel)?;
        self.streamed.remove(rel);
        let mut f = File::create(&p).map_err(|source| io("write", &p, source))?;
        f.write_all(bytes)
            .and_then(|()| f.sync_all())
            .map_err(|source| io("write", &p, source))
    }

    /// Whether `rel` is in the set.
    pub fn contains(&self, rel: &str) -> bool {
        self.files.contains(rel)
    }

    /// Where the final files will be: the output directory.
    pub fn target(&self) -> &Path {
        self.out.path()
    }

    /// Replace the previous set with this one (see the module's commit protocol). If that
    /// fails and the set is to be kept on failure, it is kept and the error says where.
    pub fn commit(mut self) -> Result<()> {
        let r = self.commit_with(&mut commit::NoCrash);
        match r {
            Err(e) if self.keep_on_failure.is_some() && self.path.exists() => {
                let kept = self.kept_path();
                self.done = true;
                self.forget();
                match std::fs::rename(&self.path, &kept) {
                    Ok(()) => Err(OutDirError::Kept {
                        failed: Box::new(e),
                        kept,
                    }),
                    Err(_) => Err(e),
                }
            }
            r => r,
        }
    }

    pub(super) fn commit_with(&mut self, crash: &mut dyn commit::Crash) -> Result<()> {
        let files: Vec<String> = self.files.iter().cloned().collect();
        let unsynced: Vec<String> = self.streamed.iter().cloned().collect();
        let (dir, kind) = (self.out.path(), self.out.kind());
        let r = commit::publish(&self.path, dir, kind, &files, &unsynced, crash);
        // Past the journal's rename the staging directory is gone: nothing to clean up.
        if r.is_ok() || !self.path.exists() {
            self.done = true;
            self.forget();
        }
        r.map_err(|e| OutDirError::Replace {
            dir: self.out.path().to_path_buf(),
            source: Box::new(e),
        })
    }

    /// Forget this set without touching the disk (tests: a process that died here).
    #[cfg(test)]
    pub(super) fn abandon(mut self) {
        self.done = true;
        self.forget();
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if self.done {
            return;
        }
        self.forget();
        // Nothing written yet: nothing to keep (an empty `incomplete-` directory says nothing).
        if crate::is_empty_tree(&self.path) {
            let _ = std::fs::remove_dir_all(&self.path);
            return;
        }
        if let Some(say) = self.keep_on_failure {
            let kept = self
                .out
                .path()
                .join(format!("{INCOMPLETE_PREFIX}{}", self.id));
            if std::fs::rename(&self.path, &kept).is_ok() {
                say(&kept);
            }
        } else {
            let _ = std::fs::remove_dir_all(&self.path);
        }
    }
}
