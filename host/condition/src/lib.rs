//! A raw time series (our `raw.csv`, a logger's CSV or tab-separated export, Logger Pro's text
//! export) into conditioned pairs, by the firmware's rules (`capstan_rig::Protocol`): each
//! level's window starts `window_after_change_ms` after the change into it and ends
//! `window_before_next_ms` before the next; the rest before the first level and the return to
//! rest after the last give no pair; a pair is each channel's mean over the window. Every level
//! is reported with its window and the samples in it, and a level whose window holds too few
//! samples is reported as not found, never dropped in silence. Nothing here prints: what to
//! say comes back as lines ([`output`]), what failed as an [`Error`] (`capstan condition` is
//! the command over it).
//!
//! * [`table`]: reading the file (columns, units, bad cells with file, line and column);
//! * [`levels`]: where the levels change (trigger, protocol, or found from the tensions);
//! * [`mod@run`]: one run's levels, windows, means and sds;
//! * [`settings`]: the options checked and completed with the firmware protocol's;
//! * [`output`]: `levels.csv` and the lines to say;
//! * [`error`]: why a file gave no pairs.

/// Return an [`Error::Column`] with the message formatted from the arguments.
macro_rules! column_error {
    ($($arg:tt)*) => {
        return Err($crate::error::Error::Column(format!($($arg)*)))
    };
}

pub mod error;
pub mod levels;
pub mod output;
pub mod run;
pub mod settings;
pub mod table;

pub use error::{Error, Place};
pub use levels::Placement;
pub use run::{condition_run, Level, RunResult, MIN_SAMPLES};
pub use settings::{Request, Settings};
pub use table::{Columns, Layout, ReadOptions, Series};

use capstan_data::Pair;
use std::path::Path;
use std::time::Instant;

/// What a file gave: how it was read, every run with every level, the pairs of the levels
/// found, and how long the reading and the conditioning took.
#[derive(Clone, Debug)]
pub struct Conditioned {
    /// What was read, and how.
    pub layout: Layout,
    /// Every run, each with every level, found or not.
    pub runs: Vec<RunResult>,
    /// The pairs of the levels found.
    pub pairs: Vec<Pair>,
    /// Time to read the file into series, s.
    pub read_s: f64,
    /// Time to condition the series, s.
    pub condition_s: f64,
}

impl Conditioned {
    /// Levels not found and runs with a problem: the pairs are incomplete when not 0.
    pub fn not_found(&self) -> usize {
        self.runs
            .iter()
            .map(|r| r.levels.iter().filter(|l| l.status != "ok").count() + r.problems.len())
            .sum()
    }
}

/// Condition the file `path`: read it as `opts` says, refuse a series sampled too sparsely for
/// the windows, number the runs and condition each by `set`.
pub fn condition_file(
    path: &Path,
    opts: &ReadOptions,
    set: &Settings,
) -> Result<Conditioned, Error> {
    let bytes = std::fs::read(path).map_err(|source| Error::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let text = String::from_utf8(bytes).map_err(|e| Error::NotText {
        path: path.to_path_buf(),
        byte: e.utf8_error().valid_up_to(),
    })?;
    let t_read = Instant::now();
    let (series, layout) = table::read(path, &text, opts)?;
    let read_s = t_read.elapsed().as_secs_f64();
    series.iter().try_for_each(|s| check_sampling(path, s))?;
    let t_cond = Instant::now();
    let numbers = run_numbers(&series, set.first_run);
    let runs: Vec<RunResult> = series
        .iter()
        .zip(&numbers)
        .map(|(s, &r)| condition_run(s, r, set))
        .collect();
    let pairs = pairs(&runs, set);
    Ok(Conditioned {
        layout,
        runs,
        pairs,
        read_s,
        condition_s: t_cond.elapsed().as_secs_f64(),
    })
}

/// Samples further apart than this (median), s, cannot place the firmware's windows (7 s of a
/// 10 s dwell): a logger samples at hertz or faster.
pub const MAX_SAMPLE_INTERVAL_S: f64 = 0.5;

/// A series of the file `path` sampled too sparsely for the windows ([`Error::Sparse`]: its
/// time in another unit than its header says, milliseconds read as seconds?).
pub fn check_sampling(path: &Path, s: &Series) -> Result<(), Error> {
    let mut dt: Vec<f64> = s.t_s.windows(2).map(|w| w[1] - w[0]).collect();
    if dt.is_empty() {
        return Ok(());
    }
    let n = dt.len();
    let (_, &mut median, _) = dt.select_nth_unstable_by(n / 2, f64::total_cmp);
    if median > MAX_SAMPLE_INTERVAL_S {
        return Err(Error::Sparse {
            place: Place::line(path, s.line.first().copied().unwrap_or(0)),
            run: s.label.clone(),
            median_s: median,
            span_h: (s.t_s[n] - s.t_s[0]) / 3600.0,
        });
    }
    Ok(())
}

/// The pairs of the levels found.
pub fn pairs(runs: &[RunResult], set: &Settings) -> Vec<Pair> {
    runs.iter()
        .flat_map(|r| r.levels.iter())
        .filter(|l| l.status == "ok")
        .map(|l| Pair {
            capstan_diameter_mm: set.diameter_mm,
            wrap_deg: set.wrap_deg,
            drive_v: set.drive_v,
            run: Some(l.run as f64),
            step: Some(l.step as f64),
            time_s: Some((l.window_from_s + l.window_to_s) / 2.0),
            t1_n: l.t1.0,
            t2_n: l.t2.0,
            extra: Vec::new(),
            labels: Vec::new(),
        })
        .collect()
}

/// The run numbers: the number a run's label ends with (a `run` column's `3`, Logger Pro's
/// `Run 3`), else counting up from `first`; a number two runs would share goes to the later
/// one's next free number (two files' `Run 1` concatenated stay two runs).
pub fn run_numbers(series: &[Series], first: u32) -> Vec<u32> {
    let trailing = |l: &str| -> Option<u32> {
        let digits: String = l
            .chars()
            .rev()
            .take_while(char::is_ascii_digit)
            .collect::<Vec<_>>()
            .into_iter()
            .rev()
            .collect();
        digits.parse().ok()
    };
    let wanted: Vec<Option<u32>> = series
        .iter()
        .map(|s| s.label.as_deref().map(str::trim).and_then(trailing))
        .collect();
    let mut taken: std::collections::HashSet<u32> = std::collections::HashSet::new();
    let mut out: Vec<Option<u32>> = wanted
        .iter()
        .map(|w| w.filter(|&r| taken.insert(r)))
        .collect();
    let mut next = first;
    for r in out.iter_mut().filter(|r| r.is_none()) {
        while taken.contains(&next) {
            next += 1;
        }
        taken.insert(next);
        *r = Some(next);
    }
    out.into_iter().map(|r| r.expect("numbered")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn runs_are_numbered_from_their_labels_and_never_twice() {
        let s = |l: Option<&str>| Series {
            label: l.map(String::from),
            ..Series::default()
        };
        let got = run_numbers(
            &[
                s(Some("Run 2")),
                s(Some("Latest")),
                s(Some("Run 2")),
                s(None),
                s(Some("7")),
            ],
            1,
        );
        assert_eq!(got, [2, 1, 3, 4, 7]);
    }
}
