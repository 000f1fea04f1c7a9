//! What a conditioning gives a user besides the pairs: `levels.csv` (every level, found or
//! not, with why) and the lines that say what was read and found.

use crate::run::RunResult;
use crate::table::Layout;
use std::path::Path;

/// The columns of `levels.csv`.
pub const LEVELS_HEADER: &str = "run,step,from_s,to_s,window_from_s,window_to_s,samples,\
                                 t1_mean_n,t1_sd_n,t2_mean_n,t2_sd_n,status";

/// A value to six decimals; empty when there is none (a level without samples).
fn f(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.6}")
    } else {
        String::new()
    }
}

/// `levels.csv`: every level of every run, its segment and window (s), samples, means and
/// sds (N), and its status (`ok`, or why it gives no pair).
pub fn levels_csv(runs: &[RunResult]) -> String {
    let mut s = format!("{LEVELS_HEADER}\n");
    for l in runs.iter().flat_map(|r| &r.levels) {
        s += &format!(
            "{},{},{},{},{},{},{},{},{},{},{},{}\n",
            l.run,
            l.step,
            f(l.from_s),
            f(l.to_s),
            f(l.window_from_s),
            f(l.window_to_s),
            l.samples,
            f(l.t1.0),
            f(l.t1.1),
            f(l.t2.0),
            f(l.t2.1),
            capstan_data::text_cell(&l.status)
        );
    }
    s
}

/// How the file `raw` was read: its format and columns, the lines passed, decimal commas, the
/// runs side by side, and the notes.
pub fn read_lines(raw: &Path, layout: &Layout) -> Vec<String> {
    let cols: Vec<String> = layout
        .used
        .iter()
        .map(|u| {
            format!(
                "{} = column {} `{}` (x{})",
                u.role, u.column, u.header, u.scale
            )
        })
        .collect();
    let mut out = vec![format!(
        "read {} as {}: {}",
        raw.display(),
        layout.format,
        cols.join(", ")
    )];
    if let Some((from, to)) = layout.skipped_lines {
        out.push(format!(
            "  lines {from}-{to} passed: a header block above the column names"
        ));
    }
    if layout.decimal_comma {
        out.push(format!(
            "  decimal commas (1,5 read as 1.5), {}-separated",
            layout.separator
        ));
    }
    if !layout.run_blocks.is_empty() {
        out.push(format!(
            "  runs side by side: {} (each its own run)",
            layout.run_blocks.join(", ")
        ));
    }
    out.extend(layout.notes.iter().map(|n| format!("  note: {n}")));
    out
}

/// Each run in words: its samples and levels, each level's window, samples and means (and
/// why it gives no pair), and what is wrong with the run as a whole.
pub fn run_lines(runs: &[RunResult]) -> Vec<String> {
    // A level without samples has no mean: said, not printed as NaN.
    let force = |v: f64| {
        if v.is_finite() {
            format!("{v:.4} N")
        } else {
            "none".to_string()
        }
    };
    let mut out = Vec::new();
    for r in runs {
        out.push(format!(
            "run {}{}: {} samples, {} level(s)",
            r.run,
            r.label
                .as_deref()
                .map_or(String::new(), |l| format!(" ({l})")),
            r.samples,
            r.levels.len()
        ));
        for l in &r.levels {
            out.push(format!(
                "  step {:>2}: window {:.3}..{:.3} s, {} samples: T1 {}, T2 {}{}",
                l.step,
                l.window_from_s,
                l.window_to_s,
                l.samples,
                force(l.t1.0),
                force(l.t2.0),
                if l.status == "ok" {
                    String::new()
                } else {
                    format!("  ({})", l.status)
                }
            ));
        }
        out.extend(r.problems.iter().map(|p| format!("  run {}: {p}", r.run)));
    }
    out
}
