//! What can go wrong in a session: a file that cannot be written, a directory that holds
//! another session, the output directory itself (its lock, staging, commit).

use std::path::PathBuf;

/// Any error of a crate below (the output directory, the pairs writer, the file system), kept
/// with its chain of causes.
pub type Source = Box<dyn std::error::Error + Send + Sync + 'static>;

/// Why a session could not go on, or could not be closed.
#[derive(Debug, thiserror::Error)]
pub enum LogError {
    /// A file of the session could not be written (`what`: the file, as the user finds it).
    #[error("cannot write {what}")]
    Write {
        /// The file.
        what: String,
        /// Why.
        #[source]
        source: Source,
    },
    /// The directory holds another session's files, and replacing them was not asked for.
    #[error(
        "{} already holds a logged session ({}): choose another --out, or pass --overwrite to \
         replace it",
        dir.display(),
        existing.join(", ")
    )]
    AlreadyLogged {
        /// The output directory.
        dir: PathBuf,
        /// The session files found in it.
        existing: Vec<&'static str>,
    },
    /// The output directory could not be opened, staged, committed or kept.
    #[error(transparent)]
    OutputDir(Source),
}

impl LogError {
    /// A failed write of `what`.
    pub(crate) fn write(what: impl Into<String>, source: impl Into<Source>) -> LogError {
        LogError::Write {
            what: what.into(),
            source: source.into(),
        }
    }

    /// A failure of the output directory.
    pub(crate) fn dir(source: impl Into<Source>) -> LogError {
        LogError::OutputDir(source.into())
    }
}

/// A session's result.
pub type Result<T> = std::result::Result<T, LogError>;
