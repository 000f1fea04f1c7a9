//! Why a raw series could not be conditioned: a typed error whose message names what to give or
//! fix, and, where the file is at fault, its path, line and column ([`Place`]).

use std::fmt;
use std::path::{Path, PathBuf};

/// Where in the file: its path, and the line and column (1-based) when one is at fault.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Place {
    /// The file.
    pub path: PathBuf,
    /// The line, 1-based.
    pub line: Option<u64>,
    /// The column (a cell), 1-based.
    pub column: Option<usize>,
}

impl Place {
    /// The file as a whole.
    pub fn file(path: &Path) -> Place {
        Place {
            path: path.to_path_buf(),
            line: None,
            column: None,
        }
    }

    /// One line of the file.
    pub fn line(path: &Path, line: u64) -> Place {
        Place {
            line: Some(line),
            ..Place::file(path)
        }
    }

    /// One cell of the file.
    pub fn cell(path: &Path, line: u64, column: usize) -> Place {
        Place {
            column: Some(column),
            ..Place::line(path, line)
        }
    }
}

/// `path`, `path:line` or `path:line:column`.
impl fmt::Display for Place {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.path.display())?;
        if let Some(l) = self.line {
            write!(f, ":{l}")?;
            if let Some(c) = self.column {
                write!(f, ":{c}")?;
            }
        }
        Ok(())
    }
}

/// Why a raw series gave no pairs at all. (A level not found is no error: it is reported in
/// its [`crate::RunResult`], with why.)
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The file could not be read.
    #[error("cannot read {}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// The file is not UTF-8 text.
    #[error("{}: not UTF-8 text (at byte {byte})", path.display())]
    NotText {
        /// The file.
        path: PathBuf,
        /// The first byte that is not.
        byte: usize,
    },
    /// An option out of its range, or options that contradict each other.
    #[error("{message}")]
    Option {
        /// The option at fault (`--dwell-s`), as the user typed it.
        flag: &'static str,
        /// What is wrong, naming the option.
        message: String,
    },
    /// Which column plays which role cannot be told: none fits, several do, one has the wrong
    /// unit, or a column asked for is not in the header. The message says what to give.
    #[error("{0}")]
    Column(String),
    /// The file's shape: empty, no rows of numbers, a row longer than the header, a Logger
    /// Pro block without its header lines or rows.
    #[error("{place}: {why}")]
    Shape {
        /// Where.
        place: Place,
        /// What is wrong.
        why: String,
    },
    /// A cell that is not a number, or outside its physical range.
    #[error("{place}: column `{column}`: {why}")]
    Cell {
        /// The cell.
        place: Place,
        /// Its column's header.
        column: String,
        /// What is wrong.
        why: String,
    },
    /// A time that does not follow the row before within a run.
    #[error(
        "{place}: time {t_s} s does not follow the row before ({before_s} s, line {before_line}){}: \
         rows must be in time order within a run",
        .run.as_deref().map_or(String::new(), |l| format!(" of run `{l}`"))
    )]
    Order {
        /// The cell.
        place: Place,
        /// Its time, s.
        t_s: f64,
        /// The time of the run's row before, s.
        before_s: f64,
        /// That row's line.
        before_line: u64,
        /// The run's label, if it has one.
        run: Option<String>,
    },
    /// Samples too far apart for the firmware's windows (a time in milliseconds read as
    /// seconds?).
    #[error(
        "{place}: {}its samples are {median_s:.3} s apart (median) and it lasts {span_h:.1} h, \
         which no logger of a capstan rig does: is the time in milliseconds? Give its unit in \
         the header (`Time (ms)`) and condition again",
        .run.as_deref().map_or(String::new(), |l| format!("run `{l}`: "))
    )]
    Sparse {
        /// The run's first sample.
        place: Place,
        /// The run's label, if it has one.
        run: Option<String>,
        /// The median interval between samples, s.
        median_s: f64,
        /// The run's length, h.
        span_h: f64,
    },
}

/// An option's error.
pub(crate) fn option(flag: &'static str, message: String) -> Error {
    Error::Option { flag, message }
}

/// A value of `flag` checked against its physical range (`--wrap-deg 0: must be ...`).
pub(crate) fn in_range(
    range: &capstan_data::ranges::Range,
    flag: &'static str,
    v: f64,
) -> Result<f64, Error> {
    range.check(v).map_err(|why| {
        let shown = capstan_data::ranges::shown(v);
        option(flag, format!("{flag} {shown}: {why}"))
    })
}
