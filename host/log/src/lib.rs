//! The files a logged run leaves in its directory, written as the records arrive and flushed
//! after every chunk of the stream, so an interrupted session keeps everything decoded so far:
//!
//! | file | what |
//! |---|---|
//! | `raw.csv` | `run,seq,time_s,t1_counts,t2_counts,t1_n,t2_n,t2_target_n`: the decimated raw samples (`t2_target_n`: force control's T2 target, 0 where none) |
//! | `pairs.csv` | the conditioned pairs, in the schema of `data` (`analyze` reads it), `t2_target_n` (force control's target, 0 where none) and `boot`: 1, then one more at every restart of the board (its run numbers start again) |
//! | `pairs-incomplete.csv` | only if needed: pairs whose set-up (wrap, diameter, drive voltage) or run number is unknown, same schema with those cells empty |
//! | `faults.csv` | `run,seq,time_s,kind,channel,value` |
//! | `messages.txt` | the firmware's other log lines (`LEVEL text`), and each command reply as `REPLY seq=N sentence` |
//! | `settings.csv` | only if needed: each `settings` record (`seq,source,` then every setting by name) |
//! | `live.csv` | only if needed: setup mode's live values `seq,time_s,t1_counts,t2_counts,t1_n,t2_n,servo_deg` (time since boot) |
//! | `stream.defmt` | the bytes as received (for `capstan log --from`), unless read from a file |
//! | `summary.json` | counts, runs, sequence gaps, bad frames, why the session stopped |
//!
//! The files become the directory's set only when the session holds a complete run (or
//! [`LogOptions::allow_empty`]): a recorded session is never replaced by an empty or broken
//! one ([`Outcome`]). A complete run is one whose run-end record arrived with no fault that
//! ended it ([`completes`]): a run refused at its tare, aborted by the button or stopped by a
//! safety check is cut short, not complete.
//!
//! Times are seconds since the logger trigger's rising edge (negative before it), except in
//! `live.csv` and for a fault in setup mode (no trigger there): seconds since boot.
//!
//! The setup-mode records (`settings`, `live`, `reply`) belong to no run: they never open or
//! close one, a fault among them is a setup-mode fault (`faults.csv` with an empty run), and
//! they are counted in `summary.json` and in the sequence numbers like every record.
//!
//! [`Logger`] (`session`) keeps the session's state (the run under way, counts, the runs
//! seen) and hands its progress to the caller as [`Note`]s; `files` writes the rows;
//! [`Summary`] (`summary`) is what `summary.json` and the closing lines say. Nothing here
//! prints: `capstan log` says the notes and the summary on stderr.

#![deny(missing_docs)]

mod error;
mod files;
mod session;
mod summary;

pub use error::{LogError, Result, Source};
pub use session::{completes, Logger, Notes};
pub use summary::{RecordCounts, RunCalibration, RunSummary, Sourced, Summary, TruncatedTail};

use std::path::{Path, PathBuf};

/// File names in the output directory.
pub const RAW_CSV: &str = "raw.csv";
/// Conditioned pairs.
pub const PAIRS_CSV: &str = "pairs.csv";
/// Pairs that lack a set-up value or their run number (created only when one arrives).
pub const PAIRS_INCOMPLETE_CSV: &str = "pairs-incomplete.csv";
/// Faults.
pub const FAULTS_CSV: &str = "faults.csv";
/// Other log lines.
pub const MESSAGES_TXT: &str = "messages.txt";
/// The received bytes.
pub const STREAM_FILE: &str = "stream.defmt";
/// Settings reports (created only when one arrives).
pub const SETTINGS_CSV: &str = "settings.csv";
/// Setup mode's live values (created only when one arrives).
pub const LIVE_CSV: &str = "live.csv";
/// The summary.
pub const SUMMARY_JSON: &str = "summary.json";

/// Header of `raw.csv`.
pub const RAW_HEADER: &str = "run,seq,time_s,t1_counts,t2_counts,t1_n,t2_n,t2_target_n";
/// Header of `faults.csv`.
pub const FAULTS_HEADER: &str = "run,seq,time_s,kind,channel,value";
/// Header of `live.csv`.
pub const LIVE_HEADER: &str = "seq,time_s,t1_counts,t2_counts,t1_n,t2_n,servo_deg";

/// Rig set-up given on the command line; each overrides the run-start record's value.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SetupFlags {
    /// Capstan diameter, mm.
    pub capstan_diameter_mm: Option<f64>,
    /// Wrap angle, deg.
    pub wrap_deg: Option<f64>,
    /// Drive-motor voltage, V.
    pub drive_v: Option<f64>,
}

/// How to log.
#[derive(Clone, Debug)]
pub struct LogOptions {
    /// Output directory (created if needed).
    pub out_dir: PathBuf,
    /// Replace files of an earlier session in `out_dir` (otherwise refuse).
    pub overwrite: bool,
    /// Keep a copy of the received bytes in `stream.defmt`.
    pub save_stream: bool,
    /// Set-up values for `pairs.csv`.
    pub setup: SetupFlags,
    /// Report runs, pairs, faults and gaps as they arrive ([`Note::Session`]); without it only
    /// the warnings that the board runs nothing are noted.
    pub progress: bool,
    /// Keep a session without a complete run as the directory's set (otherwise it replaces
    /// nothing: it is kept as `incomplete-<id>`, or dropped if nothing was received).
    pub allow_empty: bool,
    /// Told where the files are kept when the session fails part-way (they are kept as
    /// `incomplete-<id>` in `out_dir`; `capstan log` says where).
    pub kept_after_failure: fn(&Path),
}

/// A message of a session for the person logging, handed to the caller as it arises.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Note {
    /// What opening the output directory found and did (an interrupted commit finished, an
    /// abandoned set kept).
    Recovered(String),
    /// What the session saw as it came: a run started or ended, a pair, a fault, lost records,
    /// a bad frame; and the warnings (set-up values unknown, a sensitivity nobody measured).
    Session(String),
}

/// What became of a session's files when it ended.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// They are the directory's set now (the previous session's, if any, replaced).
    Committed,
    /// Not committed (no complete run): kept here; the directory is as it was.
    Kept(PathBuf),
    /// Not committed, and nothing was received: nothing kept; the directory is as it was.
    Discarded,
}

/// Why a session ended.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Stop {
    /// The stream (file, pipe) ended.
    EndOfStream,
    /// A signal: Ctrl-C, SIGTERM, SIGHUP (which, in words).
    Interrupted(&'static str),
    /// The probe or the target stopped answering.
    ProbeLost(String),
    /// A limit given on the command line was reached.
    Limit(String),
}

impl std::fmt::Display for Stop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Stop::EndOfStream => f.write_str("end of stream"),
            Stop::Interrupted(why) => write!(f, "interrupted ({why})"),
            Stop::ProbeLost(e) => write!(f, "probe lost: {e}"),
            Stop::Limit(l) => write!(f, "limit reached: {l}"),
        }
    }
}
