//! `capstan condition`: a raw time series (our `raw.csv`, a logger's CSV or tab-separated
//! export, Logger Pro's text export) into conditioned pairs, by the firmware's rules
//! (`capstan_rig::Protocol`): each level's window starts `window_after_change_ms` after the change
//! into it and ends `window_before_next_ms` before the next; the rest before the first level
//! and the return to rest after the last give no pair; a pair is each channel's mean over the
//! window. Every level is reported with its window and the samples in it, and a level whose
//! window holds too few samples is reported as not found, never dropped in silence.
//!
//! * `table`: reading the file (columns, units, bad cells with file, line and column);
//! * `levels`: where the levels change (trigger, protocol, or found from the tensions).

pub mod levels;
pub mod table;

use capstan_data::Pair;
use levels::{segments, Placement};
use serde::Serialize;
use table::Series;

/// Fewest samples a window must hold for its level to give a pair.
pub const MIN_SAMPLES: usize = 3;

/// The conditioning settings.
#[derive(Clone, Debug)]
pub struct Settings {
    /// Where the levels change.
    pub placement: Placement,
    /// The window starts this long after a change, s.
    pub window_after_s: f64,
    /// The window ends this long before the next change, s.
    pub window_before_s: f64,
    /// Levels expected per run (checked when the levels are found from the tensions).
    pub levels: u32,
    /// Rig facts for the pairs.
    pub wrap_deg: f64,
    /// Capstan diameter, mm.
    pub diameter_mm: Option<f64>,
    /// Drive voltage, V.
    pub drive_v: Option<f64>,
    /// The first run's number (runs without a number in the file count up from it).
    pub first_run: u32,
}

impl Settings {
    /// The firmware's windows (the thesis's: 2 s after a change, 1 s before the next).
    pub fn firmware_windows() -> (f64, f64) {
        let p = capstan_rig::Protocol::default();
        (
            p.window_after_change_ms as f64 / 1e3,
            p.window_before_next_ms as f64 / 1e3,
        )
    }
}

/// One level as conditioned.
#[derive(Clone, Debug, Serialize)]
pub struct Level {
    /// Run number.
    pub run: u32,
    /// Step (1 = the first level after rest).
    pub step: u32,
    /// The level's segment, s.
    pub from_s: f64,
    /// End of the segment, s.
    pub to_s: f64,
    /// The window, s.
    pub window_from_s: f64,
    /// End of the window, s.
    pub window_to_s: f64,
    /// Samples in the window.
    pub samples: usize,
    /// T1 mean and sd, N.
    pub t1: (f64, f64),
    /// T2 mean and sd, N.
    pub t2: (f64, f64),
    /// `ok`, or why the level gives no pair.
    pub status: String,
}

/// What a run gave.
#[derive(Clone, Debug, Serialize)]
pub struct RunResult {
    /// Run number.
    pub run: u32,
    /// Its label in the file.
    pub label: Option<String>,
    /// Samples read.
    pub samples: usize,
    /// Every level, found or not.
    pub levels: Vec<Level>,
    /// What is wrong with the run as a whole (levels expected but not found).
    pub problems: Vec<String>,
}

fn mean_sd(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let m = x.iter().sum::<f64>() / n;
    let v = if x.len() > 1 {
        x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / (n - 1.0)
    } else {
        0.0
    };
    (m, v.sqrt())
}

/// Condition one run.
pub fn condition_run(s: &Series, run: u32, set: &Settings) -> RunResult {
    let mut problems = Vec::new();
    let segs = match segments(s, &set.placement) {
        Ok(v) => v,
        Err(e) => {
            problems.push(e);
            Vec::new()
        }
    };
    // The rest before the first change and after the last give no pair; a series that ends
    // during the last level (the firmware's raw.csv stops with the run) has no return to rest:
    // then the levels expected are all the segments after the first.
    let found_levels = segs.len() as u32 == set.levels + 1;
    let inner = match (&set.placement, segs.len()) {
        (Placement::Detect { .. }, n) if n >= 2 && found_levels => &segs[1..],
        (_, n) if n >= 2 => &segs[1..n - 1],
        _ => &[][..],
    };
    // A protocol placed by the user: the changes the tensions show, to catch a window that
    // holds one (a wrong --first-change-s or --dwell-s mixes two levels in every window).
    let shown = match &set.placement {
        Placement::Protocol { dwell_s, .. } | Placement::Trigger { dwell_s, .. } => {
            levels::detect(s, dwell_s / 3.0)
        }
        Placement::Detect { .. } => Vec::new(),
    };
    let mut levels = Vec::new();
    for (k, &(from, to)) in inner.iter().enumerate() {
        let (a, b) = (from + set.window_after_s, to - set.window_before_s);
        let lo = s.t_s.partition_point(|&t| t < a);
        let hi = s.t_s.partition_point(|&t| t < b);
        let n = hi.saturating_sub(lo);
        let status = if b <= a {
            format!(
                "not found: the level lasts {:.3} s, shorter than the window's margins",
                to - from
            )
        } else if n < MIN_SAMPLES {
            format!("not found: {n} sample(s) in its window (need {MIN_SAMPLES})")
        } else if let Some(c) = shown.iter().find(|&&c| c > a && c < b) {
            format!(
                "mixed: the tensions change inside its window, at {c:.2} s: two levels in one \
                 mean; are --first-change-s and --dwell-s the run's? (without them the changes \
                 are found from the tensions)"
            )
        } else {
            "ok".into()
        };
        let (t1, t2) = if n > 0 {
            (mean_sd(&s.t1_n[lo..hi]), mean_sd(&s.t2_n[lo..hi]))
        } else {
            ((f64::NAN, f64::NAN), (f64::NAN, f64::NAN))
        };
        levels.push(Level {
            run,
            step: k as u32 + 1,
            from_s: from,
            to_s: to,
            window_from_s: a,
            window_to_s: b,
            samples: n,
            t1,
            t2,
            status,
        });
    }
    if let Placement::Detect { .. } = &set.placement {
        let want = set.levels;
        if levels.len() as u32 != want {
            problems.push(format!(
                "{} level(s) found from the tensions, {want} expected (--levels): a level not \
                 found, or a change where there is none; give the protocol \
                 (--first-change-s, --dwell-s) or check the series",
                levels.len()
            ));
        }
    }
    if levels.is_empty() && problems.is_empty() {
        problems.push("no level found: the tensions never change".into());
    }
    RunResult {
        run,
        label: s.label.clone(),
        samples: s.t_s.len(),
        levels,
        problems,
    }
}

/// Samples further apart than this (median), s, cannot place the firmware's windows (7 s of a
/// 10 s dwell): a logger samples at hertz or faster.
pub const MAX_SAMPLE_INTERVAL_S: f64 = 0.5;

/// A series sampled too sparsely for the windows: its time in another unit than its header
/// says (milliseconds read as seconds)? The sentence, or `None`.
pub fn sampling_problem(s: &Series) -> Option<String> {
    let mut dt: Vec<f64> = s.t_s.windows(2).map(|w| w[1] - w[0]).collect();
    if dt.is_empty() {
        return None;
    }
    let n = dt.len();
    let (_, &mut median, _) = dt.select_nth_unstable_by(n / 2, f64::total_cmp);
    (median > MAX_SAMPLE_INTERVAL_S).then(|| {
        format!(
            "its samples are {median:.3} s apart (median) and it lasts {:.1} h, which no \
             logger of a capstan rig does: is the time in milliseconds? Give its unit in the \
             header (`Time (ms)`) and condition again",
            (s.t_s[n] - s.t_s[0]) / 3600.0
        )
    })
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
