//! What can go wrong with a simulated board: options that describe no rig (or another rig than
//! the board's), a directory that is not a board or is in use, a damaged or edited board, a
//! board that does not answer, and the bench actions' words.

use std::path::PathBuf;

/// Why a simulated board could not be made, opened or run. The option names are those of
/// `capstan rig` and `capstan log`, which describe a board.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// No directory was given.
    #[error("--sim DIR is needed")]
    NoDir,
    /// A friction coefficient outside 0 to 2.
    #[error("--sim-mu {0}: must be 0 to 2")]
    Mu(f64),
    /// A wrap outside (0, 1800] degrees.
    #[error("--sim-wrap-deg {0}: must be above 0 and at most 1800")]
    WrapDeg(f64),
    /// An effect that is not `NAME=VALUE` of the catalogue.
    #[error(
        "effect {effect} of the simulated board (given with --sim-effect, or stored with the \
         board when it was made): {reason}"
    )]
    Effect {
        /// The effect as given.
        effect: String,
        /// Why it is refused.
        reason: String,
    },
    /// The same effect twice.
    #[error("--sim-effect {effect}: {kind} is given twice")]
    EffectTwice {
        /// The second one, as given.
        effect: String,
        /// Its kind.
        kind: String,
    },
    /// A noise profile that is not one.
    #[error("--sim-noise {0}")]
    Noise(capstan_sim::noise::UnknownNoiseProfile),
    /// Options that describe another rig than the board's.
    #[error(
        "--sim: this board was made with other --sim-* options ({0}); they are fixed when a board \
         is made: give a new directory for another rig"
    )]
    OtherRig(String),
    /// The plant refused the rig.
    #[error("--sim: the simulated rig cannot be built: {0}")]
    Build(String),
    /// The session refused the rig.
    #[error("the simulated rig cannot be set up: {0}")]
    Setup(String),
    /// A directory that holds something else.
    #[error(
        "--sim {}: the directory is not a simulated board (no {}) and is not empty; give a new \
         directory (it is created)",
        .0.display(),
        crate::SIM_JSON
    )]
    NotABoard(PathBuf),
    /// A file where the board's directory should be.
    #[error(
        "--sim {}: a file, not a directory; give a directory (a new one is created)",
        .0.display()
    )]
    NotADirectory(PathBuf),
    /// Another command holds the board.
    #[error(
        "the simulated board in {} is in use by another capstan command: one command at a time \
         talks to a board",
        .0.display()
    )]
    InUse(PathBuf),
    /// The replay did not make the records the board made before.
    #[error(
        "the simulated board in {} no longer replays as it ran (its journal was edited, or this \
         capstan's simulator differs from the one that made it): start a new board in a new \
         directory",
        .0.display()
    )]
    Diverged(PathBuf),
    /// A journal line that is not a step.
    #[error(
        "{}:{line}:1: not a bench step: `{text}` (the journal is written by capstan; start a new \
         board in a new directory)",
        path.display()
    )]
    Journal {
        /// The journal.
        path: PathBuf,
        /// Its line number (from 1).
        line: usize,
        /// The line.
        text: String,
    },
    /// A file of the board that could not be read.
    #[error("{} is damaged", path.display())]
    Damaged {
        /// The file.
        path: PathBuf,
        /// Why it does not read.
        #[source]
        source: serde_json::Error,
    },
    /// A file or directory of the board that could not be created, opened, read or written.
    #[error("cannot {action} {}", path.display())]
    File {
        /// `create`, `open`, `read` or `write`.
        action: &'static str,
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// Another failure of the file system.
    #[error(transparent)]
    Io(#[from] std::io::Error),
    /// A command line the board did not answer.
    #[error(
        "the simulated board did not answer `{line}` within {seconds} s of its time (its \
         firmware loop is stuck?)"
    )]
    NoAnswer {
        /// The command line.
        line: String,
        /// How long it was given, s of the board's time.
        seconds: u64,
    },
}

impl SimError {
    /// A file that could not be `action`ed.
    pub(crate) fn file(
        action: &'static str,
        path: &std::path::Path,
        source: std::io::Error,
    ) -> Self {
        SimError::File {
            action,
            path: path.to_path_buf(),
            source,
        }
    }
}

/// A bench action that is not one (`capstan rig --sim DIR bench ...`).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum BenchError {
    /// `load` with a sensor that is not t1 or t2.
    #[error("bench load: `{0}` is not t1 or t2")]
    Channel(String),
    /// `load` with a weight that is not 0 to 200 N.
    #[error("bench load: `{0}` is not a weight in newtons (0 to 200)")]
    Weight(String),
    /// `press` with a time that is not 1 to 60000 ms.
    #[error("bench press: `{0}` is not 1 to 60000 ms")]
    Press(String),
    /// `wait` with a time that is not 0 to 3600 s.
    #[error("bench wait: `{0}` is not 0 to 3600 seconds")]
    Wait(String),
    /// Words that are no bench action.
    #[error("bench takes: {}", crate::steps::BENCH_USAGE)]
    Usage,
}

/// A simulated board's result.
pub type Result<T> = std::result::Result<T, SimError>;
