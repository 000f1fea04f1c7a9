//! Output directories that never hold half a result: every command writes its files into a
//! staging directory inside the target and moves them into place only when the set is
//! complete, so the previous results survive any failure (a full disk, a signal, a crash).
//!
//! * [`OutputDir::open`] creates the directory, takes its lock (a second `capstan` writing into
//!   the same directory is refused, naming the process that holds it), finishes a commit that an
//!   earlier process was interrupted in, keeps an abandoned staging directory's work under a
//!   visible name, and proves the directory writable before any work is done;
//! * [`Staged`] (`staged`) is one output set being written; [`Staged::commit`] replaces the
//!   previous set.
//!
//! Commit protocol (a small write-ahead journal, `commit`): the complete set, with a manifest
//! naming its files, is renamed to `.capstan-commit` (one atomic rename: from here on the new
//! set is the truth); then each file is renamed over its old version, the previous set's files
//! that the new one lacks are removed (only files the same command's previous manifest names:
//! files it wrote), and the manifest is moved to `.capstan-manifest-<command>.json` last.
//! Before the journal's rename every move is checked (parents, a directory in the way), and a
//! set that would replace another command's files (a logged session, a campaign's pairs), or
//! any file no manifest of the same command lists (the user's own `pairs.csv`, a link), is
//! refused: capstan replaces only files it wrote. [`OutputDir::open`] makes the same checks
//! before any work, for every file the command will write. Any interruption before
//! the first rename leaves the old set; any after it is rolled forward by the next `open`.
//! Nothing is written through a symbolic link: one at a name of the set, or where a
//! sub-directory of ours should be, is refused.
//!
//! A set that cannot be committed after its work is done (a late failure) is kept as
//! `incomplete-<id>` and the error says where, as is the work of a process killed, or stopped
//! by a second signal (`cli::signal`), while it wrote.
//!
//! Why by hand: the crates for atomic files (`tempfile`'s `persist`, `atomicwrites`) replace
//! one file; the requirement here is a set of files (a report and its metrics, a campaign's
//! pairs and raw logs) replaced together, and a lock that outlives no process (`File::lock`
//! from std, released by the kernel when its holder dies).

mod commit;
mod error;
mod staged;

pub use error::{chain, OutDirError};
pub use staged::{keep_open_sets, Staged};

#[cfg(test)]
mod tests;

use commit::io;

/// A result of this crate: its error is an [`OutDirError`].
pub type Result<T, E = OutDirError> = std::result::Result<T, E>;
use std::fs::{File, OpenOptions};
use std::io::{Read, Seek, Write};
use std::path::{Path, PathBuf};

/// The lock file's name.
pub const LOCK: &str = ".capstan.lock";
/// Prefix of the manifests of the current sets, one per command (`analyze`, `simulate`, ...):
/// a command replaces and removes only what the same command wrote.
pub const MANIFEST_PREFIX: &str = ".capstan-manifest-";
/// The manifest's name inside the journal.
pub const JOURNAL_MANIFEST: &str = ".capstan-journal.json";

/// The manifest of `kind`'s current set.
pub fn manifest_name(kind: &str) -> String {
    format!("{MANIFEST_PREFIX}{kind}.json")
}
/// The set being committed (the journal).
pub const COMMIT: &str = ".capstan-commit";
/// Prefix of staging directories.
pub const STAGING_PREFIX: &str = ".capstan-staging-";
/// Prefix under which an abandoned staging directory's work is kept.
pub const INCOMPLETE_PREFIX: &str = "incomplete-";

/// A sub-directory a command writes into, with which of its files (`"sub/name"`) it writes.
pub type Subdir<'a> = (&'a str, &'a dyn Fn(&str) -> bool);

/// An output directory, locked for this process.
#[derive(Debug)]
pub struct OutputDir {
    dir: PathBuf,
    kind: &'static str,
    _lock: File,
    /// The directories this process made for it, the output directory first and then each
    /// parent it had to make (`--out a/b/c` with no `a`: c, b, a).
    made: Vec<PathBuf>,
    /// What `open` found and did (an interrupted commit finished, an abandoned set kept).
    pub recovered: Vec<String>,
}

impl OutputDir {
    /// Create `dir` if needed, lock it, recover what an earlier process left, and refuse it
    /// if a file there carries one of `names` (the files `kind`, e.g. "analyze", will write at
    /// the top of the directory) and `kind` did not write it (another command's results, the
    /// user's own file, a link) — before any work is done.
    pub fn open(dir: &Path, kind: &'static str, names: &[&str]) -> Result<OutputDir> {
        Self::open_with(dir, kind, names, &[])
    }

    /// [`OutputDir::open`], with sub-directories the command writes into: for each
    /// `(sub, writes)`, `dir/sub` must be a directory (or absent), and none of its files for
    /// which `writes("sub/name")` holds may be a file `kind` did not write.
    pub fn open_with(
        dir: &Path,
        kind: &'static str,
        names: &[&str],
        subdirs: &[Subdir<'_>],
    ) -> Result<OutputDir> {
        let existed = dir.exists();
        if existed && !dir.is_dir() {
            return Err(OutDirError::NotADirectory {
                dir: dir.to_path_buf(),
                names: names.iter().map(|n| n.to_string()).collect(),
            });
        }
        let made: Vec<PathBuf> = (dir.ancestors())
            .take_while(|d| !d.as_os_str().is_empty() && !d.exists())
            .map(Path::to_path_buf)
            .collect();
        std::fs::create_dir_all(dir)
            .map_err(|source| io("create the output directory", dir, source))?;
        let lock = take_lock(dir)?;
        let mut out = OutputDir {
            dir: dir.to_path_buf(),
            kind,
            _lock: lock,
            made,
            recovered: Vec::new(),
        };
        match out.prepare(names, subdirs) {
            Ok(()) => Ok(out),
            Err(e) => {
                // Refused: leave the directory as found, keeping what the recovery kept, and
                // say what it kept (an earlier run's work moved to `incomplete-`).
                let kept = std::mem::take(&mut out.recovered);
                out.abandon();
                if kept.is_empty() {
                    Err(e)
                } else {
                    Err(OutDirError::Refused {
                        refused: Box::new(e),
                        notes: kept,
                    })
                }
            }
        }
    }

    /// Nothing will be written (refused, or stopped before any output): leave the directory
    /// as it was found — no lock file, and no directory if this process made it and it is
    /// empty. The lock file goes while the lock is still held: a process that opened it
    /// meanwhile finds it locked and stops; one that comes later makes a new one.
    pub fn abandon(self) {
        let _ = std::fs::remove_file(self.dir.join(LOCK));
        // Drop removes the directory if this process made it and it is empty.
        drop(self);
    }

    /// Recover what an earlier process left, and refuse files of others (see [`Self::open_with`]).
    fn prepare(&mut self, names: &[&str], subdirs: &[Subdir<'_>]) -> Result<()> {
        let (dir, kind) = (self.dir.clone(), self.kind);
        let dir = dir.as_path();
        let out = self;
        if dir.join(COMMIT).exists() {
            commit::roll_forward(dir, &mut commit::NoCrash).map_err(|e| OutDirError::Recover {
                dir: dir.to_path_buf(),
                source: Box::new(e),
            })?;
            out.recovered.push(format!(
                "finished replacing the results in {} that an earlier run was interrupted in",
                dir.display()
            ));
        }
        out.keep_abandoned()?;
        let names: Vec<String> = names.iter().map(|n| n.to_string()).collect();
        commit::refuse_others(dir, kind, &names)?;
        commit::refuse_foreign(dir, kind, &names)?;
        for (sub, writes) in subdirs {
            let path = dir.join(sub);
            match std::fs::symlink_metadata(&path) {
                Err(_) => continue,
                Ok(m) if m.file_type().is_symlink() => return Err(OutDirError::Symlink { path }),
                Ok(m) if !m.is_dir() => return Err(OutDirError::FileForDirectory { path, kind }),
                Ok(_) => {}
            }
            let ours: Vec<String> = std::fs::read_dir(&path)
                .map_err(|source| io("read", &path, source))?
                .flatten()
                .map(|e| format!("{sub}/{}", e.file_name().to_string_lossy()))
                .filter(|rel| writes(rel))
                .collect();
            commit::refuse_others(dir, kind, &ours)?;
            commit::refuse_foreign(dir, kind, &ours)?;
        }
        Ok(())
    }

    /// The directory.
    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// The command writing it.
    pub fn kind(&self) -> &'static str {
        self.kind
    }

    /// Start a new output set (a staging directory, created now: an unwritable directory
    /// fails here, before any work). The set keeps the lock until it is committed or dropped.
    pub fn stage(self) -> Result<Staged> {
        Staged::new(self)
    }

    /// Staging directories of processes that died (we hold the lock, so none is live): keep
    /// any work in them under a visible name, remove empty ones.
    fn keep_abandoned(&mut self) -> Result<()> {
        let entries =
            std::fs::read_dir(&self.dir).map_err(|source| io("read", &self.dir, source))?;
        for e in entries.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            let Some(id) = name.strip_prefix(STAGING_PREFIX) else {
                continue;
            };
            let path = e.path();
            if is_empty_tree(&path) {
                let _ = std::fs::remove_dir_all(&path);
                continue;
            }
            let kept = self.dir.join(format!("{INCOMPLETE_PREFIX}{id}"));
            std::fs::rename(&path, &kept).map_err(|source| io("keep", &path, source))?;
            self.recovered.push(format!(
                "an earlier run into {} stopped without finishing (killed?): its completed work \
                 is kept in {}",
                self.dir.display(),
                kept.display()
            ));
        }
        Ok(())
    }
}

/// The lock file goes when the lock does: a finished command leaves only its results (the file
/// is removed while the lock is still held, and only if it is still the one at the path; a
/// process that opened it meanwhile finds it locked, or gone from the path, and takes the lock
/// again on a new file: [`take_lock`]).
///
/// A directory this process made (with the parents it made for it) and that is still empty when the lock goes (the command
/// failed before it wrote anything: an unreadable input, a refused option) goes too, so a
/// failed command leaves no trace. `remove_dir` removes only an empty directory: results, kept
/// work and another process's lock file all keep it.
impl Drop for OutputDir {
    fn drop(&mut self) {
        let path = self.dir.join(LOCK);
        if still_at_path(&self._lock, &path) {
            let _ = std::fs::remove_file(&path);
        }
        // Deepest first; a parent another process or the user has put something in since
        // stays, and so do the ones above it.
        for d in &self.made {
            if std::fs::remove_dir(d).is_err() {
                break;
            }
        }
    }
}

/// Lock `dir` for this process, or say who holds it. A lock file unlinked by a refused
/// process between our open and our lock is not the directory's lock any more: the lock is
/// taken again on the file at the path (a few tries), so two processes never hold locks on
/// two different files of one directory.
fn take_lock(dir: &Path) -> Result<File> {
    for _ in 0..LOCK_TRIES {
        let f = lock_file_at(dir)?;
        if still_at_path(&f, &dir.join(LOCK)) {
            return Ok(f);
        }
    }
    Err(OutDirError::LockChanging {
        dir: dir.to_path_buf(),
    })
}

/// How often [`take_lock`] tries for a lock file that stays at its path.
const LOCK_TRIES: usize = 5;

/// The locked file is the one at `path` (same device and inode).
fn still_at_path(f: &File, path: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (f.metadata(), std::fs::metadata(path)) {
            (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        let _ = (f, path);
        true
    }
}

/// Open `dir`'s lock file and lock it, or say who holds it.
fn lock_file_at(dir: &Path) -> Result<File> {
    let path = dir.join(LOCK);
    if std::fs::symlink_metadata(&path).is_ok_and(|m| !m.is_file()) {
        return Err(OutDirError::LockNotPlain { path });
    }
    let mut f = OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .open(&path)
        .map_err(|source| io("write to the output directory", dir, source))?;
    match f.try_lock() {
        Ok(()) => {}
        Err(std::fs::TryLockError::WouldBlock) => {
            let mut holder = String::new();
            let _ = f.read_to_string(&mut holder);
            return Err(OutDirError::InUse {
                dir: dir.to_path_buf(),
                holder: holder.trim().to_string(),
            });
        }
        Err(std::fs::TryLockError::Error(e)) => {
            return Err(io("lock", &path, e));
        }
    }
    let args: Vec<String> = std::env::args().collect();
    f.set_len(0)
        .and_then(|()| f.rewind())
        .and_then(|_| write!(f, "pid {}: {}", std::process::id(), args.join(" ")))
        .map_err(|source| io("write", &path, source))?;
    Ok(f)
}

/// A directory tree without a single file.
fn is_empty_tree(path: &Path) -> bool {
    let Ok(entries) = std::fs::read_dir(path) else {
        return true;
    };
    entries
        .flatten()
        .all(|e| e.file_type().is_ok_and(|t| t.is_dir()) && is_empty_tree(&e.path()))
}
