//! Why an output directory could not be opened, staged or committed: each variant names the
//! path it concerns. The command line prints the error with its causes (`{:#}` in anyhow).

use std::path::PathBuf;

/// Why an output directory could not be opened, staged or committed.
#[derive(Debug, thiserror::Error)]
pub enum OutDirError {
    /// A file-system operation failed: `cannot {action} {path}`.
    #[error("cannot {action} {}", path.display())]
    Io {
        /// What was being done ("write", "create the output directory", "lock" ...).
        action: &'static str,
        /// The file or directory it was done to.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// A file or directory could not be moved to its final place.
    #[error("cannot move {} into place", path.display())]
    Move {
        /// The final place.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// A staging directory could not be kept under its `incomplete-` name.
    #[error("cannot keep {} as {}", path.display(), kept.display())]
    Keep {
        /// The staging directory.
        path: PathBuf,
        /// The name it was to be kept under.
        kept: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// `--out` names a file.
    #[error(
        "--out {}: that is a file; the output is a directory (created if missing) that will \
         hold {}: give a directory's name",
        dir.display(),
        names.join(", ")
    )]
    NotADirectory {
        /// The path given.
        dir: PathBuf,
        /// The files the command would write there.
        names: Vec<String>,
    },
    /// A symbolic link where capstan would write (it never writes through one).
    #[error(
        "{} is a symbolic link: capstan does not write through it (remove it, or choose \
         another output directory)",
        path.display()
    )]
    Symlink {
        /// The link.
        path: PathBuf,
    },
    /// A file where the command writes a directory.
    #[error(
        "{} is a file where capstan {kind} writes a directory: move it away, or choose another \
         output directory",
        path.display()
    )]
    FileForDirectory {
        /// The file.
        path: PathBuf,
        /// The command.
        kind: &'static str,
    },
    /// A file where a parent directory of an output file is needed.
    #[error("{} is a file where a directory is needed", path.display())]
    FileForParent {
        /// The file.
        path: PathBuf,
    },
    /// A directory where an output file goes.
    #[error("{} is a directory: it cannot be replaced by a file", path.display())]
    DirectoryForFile {
        /// The directory.
        path: PathBuf,
    },
    /// A name an output set may not hold (absolute, `..`, a control file).
    #[error("`{0}` is not a file name an output set may hold")]
    BadName(String),
    /// The lock file is not a plain file.
    #[error(
        "{} is not a plain file (a symbolic link?): capstan does not write through it",
        path.display()
    )]
    LockNotPlain {
        /// The lock file.
        path: PathBuf,
    },
    /// Another process holds the directory's lock.
    #[error(
        "{} is in use by another capstan process ({holder}): wait for it, or choose another \
         output directory",
        dir.display()
    )]
    InUse {
        /// The output directory.
        dir: PathBuf,
        /// What the lock file says of its holder (`pid N: command line`).
        holder: String,
    },
    /// The lock file was replaced under us at every try.
    #[error(
        "{}: its lock file keeps changing under capstan (another capstan process opening and \
         leaving it?): try again",
        dir.display()
    )]
    LockChanging {
        /// The output directory.
        dir: PathBuf,
    },
    /// Another command's results would be replaced.
    #[error(
        "{} holds the results of `capstan {other}` ({first}{}): `capstan {kind}` would replace \
         them; choose another output directory",
        dir.display(),
        if *more { ", ..." } else { "" }
    )]
    OthersResults {
        /// The output directory.
        dir: PathBuf,
        /// The command whose results they are.
        other: String,
        /// The first file that would be replaced.
        first: String,
        /// More than one would be.
        more: bool,
        /// The command writing now.
        kind: String,
    },
    /// A file no manifest of the command lists (the user's own, a link they made).
    #[error(
        "{} is {what} that `capstan {kind}` did not write (no manifest of it lists it): capstan \
         never replaces what it did not write; move it away, or choose another output directory",
        path.display()
    )]
    Foreign {
        /// The file.
        path: PathBuf,
        /// "a file", "a directory" or "a symbolic link".
        what: &'static str,
        /// The command writing now.
        kind: String,
    },
    /// The commit manifest could not be made.
    #[error("cannot write the commit manifest")]
    Manifest(#[from] serde_json::Error),
    /// A commit an earlier process left half done could not be finished.
    #[error("finishing an interrupted commit in {}", dir.display())]
    Recover {
        /// The output directory.
        dir: PathBuf,
        /// Why.
        source: Box<OutDirError>,
    },
    /// The new results could not replace the previous ones.
    #[error("replacing the results in {}", dir.display())]
    Replace {
        /// The output directory.
        dir: PathBuf,
        /// Why.
        source: Box<OutDirError>,
    },
    /// Refused, after recovering an earlier run's work: the refusal with its causes, then
    /// one `note:` line for each thing recovered.
    #[error("{}\nnote: {}", chain(refused), notes.join("\nnote: "))]
    Refused {
        /// Why the directory is refused.
        refused: Box<OutDirError>,
        /// What the recovery did (an earlier run's work kept, a commit finished).
        notes: Vec<String>,
    },
    /// The commit failed and the results were kept: the failure with its causes, then where.
    #[error("{}; the results are kept in {}", chain(failed), kept.display())]
    Kept {
        /// Why the commit failed.
        failed: Box<OutDirError>,
        /// Where the results are.
        kept: PathBuf,
    },
    /// A simulated crash (tests of the commit protocol).
    #[error("{0}")]
    Crash(std::io::Error),
}

/// An error and its causes on one line, `a: b: c`, as anyhow's `{:#}` prints them.
pub fn chain(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut cur = e.source();
    while let Some(c) = cur {
        s.push_str(": ");
        s.push_str(&c.to_string());
        cur = c.source();
    }
    s
}
