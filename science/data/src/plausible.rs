//! Rows and columns that no capstan rig produces: a data set may hold a few (a pair typed in
//! by hand with its tensions swapped, a run pasted twice), and each changes a verdict without
//! a word. They are counted and named here, and the caller warns about them; above
//! [`MAX_SUSPECT_SHARE`] of the rows the data set is refused. A column in the wrong unit
//! (tensions in grams, wraps in radians) is refused with the unit it looks like; one that is
//! only unusual (tensions all below 0.1 N, pairs hours apart) is a warning.
//!
//! What counts, and why it cannot be a zero offset, a gain error or noise:
//!
//! * **swapped**: T2 below T1 by more than the catalogue's zero offsets can make it (T1's
//!   largest offset up, T2's down: [`SWAP_MARGIN_N`]), on a cord whose other rows amplify
//!   (median log(T2/T1) at least [`MIN_CORD_LOG_GAIN`]), at a ratio below the square root of
//!   the cord's inverse gain — where the row would sit with T1 and T2 exchanged. A sensor
//!   gain below one acts on every row of the cord and moves its median with it;
//! * **negative**: a tension below −[`crate::REVERSED_BELOW_N`], which the firmware's
//!   negative-force check never lets a run record (a zero offset stays above it);
//! * **time_not_rising**: within a run read from the `run` column, a row whose `time_s` is not
//!   after the row before it (in step order when there is a `step` column);
//! * **copied_run**: a run whose every pair equals, bit for bit, another run's of the same
//!   cord (no two runs of a rig give the same means to the last digit).

mod units;

use units::column_warnings;
pub use units::unit_mistake;

use super::{Dataset, Pair};
use capstan_physics::catalogue::EffectKind;
use std::collections::HashMap;

/// Above this share of suspect rows a data set is refused (below it, a warning names them).
pub const MAX_SUSPECT_SHARE: f64 = 0.02;

/// A row's T1 − T2 beyond which no zero offset explains T2 below T1, N: T1's largest offset
/// in the catalogue up and T2's largest down (+3 N and −3 N).
pub fn swap_margin_n() -> f64 {
    EffectKind::T1Offset.entry().physical.1 - EffectKind::T2Offset.entry().physical.0
}

/// The margin as a constant for the documentation ([`swap_margin_n`] computes it).
pub const SWAP_MARGIN_N: f64 = 6.0;

/// A cord's median log(T2/T1) at least this (an amplification of 1.1) for a swapped row to
/// be told from the cord's own.
pub const MIN_CORD_LOG_GAIN: f64 = 0.1;

/// Tensions above this, N, come from no bench capstan rig (the thesis rig's sensors end at
/// ~55 N, its safety limit is 45 N; 1000 N is a 100 kg load on a cord over a bench drum).
pub const RIG_TENSION_MAX_N: f64 = 1000.0;

/// Every tension below this, N, is unusual for a rig whose sensors resolve ~0.015 N (a tare
/// at 0.1 N): kilonewtons read as newtons?
pub const RIG_TENSION_SMALL_N: f64 = 0.1;

/// A friction coefficient above this, from the median row's ln(T2/T1)/wrap, is no cord on a
/// drum (rubber on steel is about 1): the wraps are in another unit than degrees.
pub const MU_MAX: f64 = 2.0;

/// Pairs of a run further apart than this (median), s, are no protocol (dwells are seconds).
pub const PAIR_INTERVAL_MAX_S: f64 = 600.0;

/// What kind of suspect row.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SuspectKind {
    /// T2 below T1 beyond any zero offset, on a cord that amplifies.
    Swapped,
    /// A tension below the firmware's negative-force limit.
    Negative,
    /// `time_s` not after the row before, within a run.
    TimeNotRising,
    /// A run identical to another run of the same cord.
    CopiedRun,
}

impl SuspectKind {
    /// What the rows are, in words.
    pub fn describe(self) -> String {
        match self {
            SuspectKind::Swapped => format!(
                "T2 below T1 by more than any zero offset makes it ({SWAP_MARGIN_N} N) on a cord \
                 that amplifies: T1 and T2 swapped?"
            ),
            SuspectKind::Negative => format!(
                "a tension below −{} N, which the rig's negative-force check never records: \
                 negated?",
                crate::REVERSED_BELOW_N
            ),
            SuspectKind::TimeNotRising => {
                "time_s not after the row before it within its run: the time column or the run \
                 numbers are wrong?"
                    .to_string()
            }
            SuspectKind::CopiedRun => {
                "a run equal, pair for pair, to an earlier run of the same cord: pasted twice \
                 under a new number?"
                    .to_string()
            }
        }
    }
}

/// Rows of one kind.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Suspects {
    /// The kind.
    pub kind: SuspectKind,
    /// The file line of each row.
    pub lines: Vec<u64>,
    /// For copied runs: which run repeats which (in words).
    pub detail: Vec<String>,
}

/// What the plausibility checks found.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Plausibility {
    /// Rows in the data set.
    pub rows: usize,
    /// Suspect rows, by kind.
    pub suspects: Vec<Suspects>,
    /// Warnings about whole columns (units), in words.
    pub column_warnings: Vec<String>,
}

impl Plausibility {
    /// Distinct rows that are suspect of any kind.
    pub fn suspect_rows(&self) -> usize {
        let mut all: Vec<u64> = self
            .suspects
            .iter()
            .flat_map(|s| s.lines.iter().copied())
            .collect();
        all.sort_unstable();
        all.dedup();
        all.len()
    }

    /// Every warning as a sentence (`path` names the file).
    pub fn warnings(&self, path: &str) -> Vec<String> {
        let mut out: Vec<String> = self
            .suspects
            .iter()
            .map(|s| {
                let detail = if s.detail.is_empty() {
                    String::new()
                } else {
                    format!(" ({})", s.detail.join("; "))
                };
                format!(
                    "{path}: {} row(s) of {}: {}{detail}; {}",
                    s.lines.len(),
                    self.rows,
                    s.kind.describe(),
                    lines_text(&s.lines)
                )
            })
            .collect();
        out.extend(self.column_warnings.iter().map(|w| format!("{path}: {w}")));
        out
    }
}

/// "line 14", "lines 14, 27 and 98", "lines 14, 27, 98, … (12 in all)".
pub fn lines_text(lines: &[u64]) -> String {
    const SHOWN: usize = 5;
    let first: Vec<String> = lines.iter().take(SHOWN).map(u64::to_string).collect();
    match lines.len() {
        0 => "no line".into(),
        1 => format!("line {}", first[0]),
        n if n <= SHOWN => format!("lines {} and {}", first[..n - 1].join(", "), first[n - 1]),
        n => format!("lines {}, … ({n} in all)", first.join(", ")),
    }
}

/// The suspect rows and column warnings of `ds`.
pub fn plausibility(ds: &Dataset) -> Plausibility {
    let mut suspects = Vec::new();
    let mut push = |kind, lines: Vec<u64>, detail: Vec<String>| {
        if !lines.is_empty() {
            suspects.push(Suspects {
                kind,
                lines,
                detail,
            });
        }
    };
    push(SuspectKind::Swapped, swapped(ds), Vec::new());
    push(SuspectKind::Negative, negative(ds), Vec::new());
    push(SuspectKind::TimeNotRising, time_not_rising(ds), Vec::new());
    let (copied, detail) = copied_runs(ds);
    push(SuspectKind::CopiedRun, copied, detail);
    Plausibility {
        rows: ds.pairs.len(),
        suspects,
        column_warnings: column_warnings(ds),
    }
}

pub(super) fn line_of_row(ds: &Dataset, i: usize) -> u64 {
    line_of(ds, i)
}

fn line_of(ds: &Dataset, i: usize) -> u64 {
    ds.lines.get(i).copied().unwrap_or(i as u64 + 2)
}

pub(super) fn median(mut v: Vec<f64>) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    let n = v.len();
    let (_, m, _) = v.select_nth_unstable_by(n / 2, f64::total_cmp);
    Some(*m)
}

pub(super) fn log_gain(p: &Pair) -> Option<f64> {
    (p.t1_n > 0.0 && p.t2_n > 0.0).then(|| (p.t2_n / p.t1_n).ln())
}

/// Rows with T2 below T1 beyond any zero offset, on a cord that amplifies.
fn swapped(ds: &Dataset) -> Vec<u64> {
    let st = &ds.structure;
    let mut per_cord: Vec<Vec<f64>> = vec![Vec::new(); st.cords.len()];
    for (i, p) in ds.pairs.iter().enumerate() {
        if let (Some(g), Some(&c)) = (log_gain(p), st.cord_of_row.get(i)) {
            per_cord[c].push(g);
        }
    }
    let gain: Vec<Option<f64>> = per_cord.into_iter().map(median).collect();
    let margin = swap_margin_n();
    (0..ds.pairs.len())
        .filter(|&i| {
            let p = &ds.pairs[i];
            let Some(m) = st.cord_of_row.get(i).and_then(|&c| gain[c]) else {
                return false;
            };
            m >= MIN_CORD_LOG_GAIN
                && p.t1_n - p.t2_n > margin
                && log_gain(p).is_some_and(|g| g < -m / 2.0)
        })
        .map(|i| line_of(ds, i))
        .collect()
}

/// Rows with a tension below the firmware's negative-force limit.
fn negative(ds: &Dataset) -> Vec<u64> {
    let floor = -crate::REVERSED_BELOW_N;
    (0..ds.pairs.len())
        .filter(|&i| ds.pairs[i].t1_n < floor || ds.pairs[i].t2_n < floor)
        .map(|i| line_of(ds, i))
        .collect()
}

/// Rows of each run (from the `run` column) whose time is not after the row before, in step
/// order where there is a step column.
fn time_not_rising(ds: &Dataset) -> Vec<u64> {
    if !(ds.has_column("time_s") && ds.has_column("run")) {
        return Vec::new();
    }
    let st = &ds.structure;
    let mut runs: Vec<Vec<usize>> = vec![Vec::new(); st.run_cord.len()];
    for (i, &r) in st.run_of_row.iter().enumerate() {
        runs[r].push(i);
    }
    let mut out = Vec::new();
    for rows in runs.iter_mut() {
        if ds.has_column("step") {
            rows.sort_by(|&a, &b| {
                let s = |i: usize| ds.pairs[i].step.unwrap_or(0.0);
                s(a).total_cmp(&s(b)).then(a.cmp(&b))
            });
        }
        for w in rows.windows(2) {
            let t = |i: usize| ds.pairs[i].time_s.unwrap_or(0.0);
            if t(w[1]) <= t(w[0]) {
                out.push(line_of(ds, w[1]));
            }
        }
    }
    out.sort_unstable();
    out
}

/// Runs whose pairs equal an earlier run's of the same cord, bit for bit: their rows, and
/// which run repeats which.
fn copied_runs(ds: &Dataset) -> (Vec<u64>, Vec<String>) {
    let st = &ds.structure;
    let mut runs: Vec<Vec<usize>> = vec![Vec::new(); st.run_cord.len()];
    for (i, &r) in st.run_of_row.iter().enumerate() {
        runs[r].push(i);
    }
    let key = |rows: &[usize]| -> Vec<(u64, u64)> {
        rows.iter()
            .map(|&i| (ds.pairs[i].t1_n.to_bits(), ds.pairs[i].t2_n.to_bits()))
            .collect()
    };
    let name = |r: usize, rows: &[usize]| {
        let first = rows[0];
        let run = ds.pairs[first]
            .run
            .map_or(String::new(), |n| format!(" run {n}"));
        format!(
            "cord {}{run} (from line {})",
            st.cord_label(st.run_cord[r]),
            line_of(ds, first)
        )
    };
    let mut seen: HashMap<(usize, Vec<(u64, u64)>), usize> = HashMap::new();
    let (mut lines, mut detail) = (Vec::new(), Vec::new());
    for (r, rows) in runs.iter().enumerate() {
        // One pair is too little to call a copy (two runs can share a level by chance).
        if rows.len() < 3 {
            continue;
        }
        match seen.entry((st.run_cord[r], key(rows))) {
            std::collections::hash_map::Entry::Occupied(e) => {
                let first = *e.get();
                detail.push(format!(
                    "{} repeats {}",
                    name(r, rows),
                    name(first, &runs[first])
                ));
                lines.extend(rows.iter().map(|&i| line_of(ds, i)));
            }
            std::collections::hash_map::Entry::Vacant(v) => {
                v.insert(r);
            }
        }
    }
    lines.sort_unstable();
    (lines, detail)
}
