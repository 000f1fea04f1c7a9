//! One run conditioned: its segments between the level changes, each inner segment's window
//! (the firmware's margins after and before the changes), and each channel's mean and sd over
//! the window; a level whose window is too short, too sparse or spans a change is reported
//! with why, never dropped.

use crate::levels::{self, segments, Placement};
use crate::settings::Settings;
use crate::table::Series;
use serde::Serialize;

/// Fewest samples a window must hold for its level to give a pair.
pub const MIN_SAMPLES: usize = 3;

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

/// Mean and sample sd (0 for one value).
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
            problems.push(e.to_string());
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
    let levels: Vec<Level> = inner
        .iter()
        .enumerate()
        .map(|(k, &segment)| level(s, (run, k as u32 + 1), segment, set, &shown))
        .collect();
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

/// The level of segment `(from, to)` of `s`: its window, the means and sds in it, and its
/// status (`shown`: the changes the tensions show, none of which may fall in a window).
fn level(
    s: &Series,
    (run, step): (u32, u32),
    (from, to): (f64, f64),
    set: &Settings,
    shown: &[f64],
) -> Level {
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
    Level {
        run,
        step,
        from_s: from,
        to_s: to,
        window_from_s: a,
        window_to_s: b,
        samples: n,
        t1,
        t2,
        status,
    }
}
