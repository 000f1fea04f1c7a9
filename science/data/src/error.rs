//! Why a pairs CSV could not be read, each with the file, line and column an editor shows, the
//! value found (at most [`QUOTE_CHARS`] characters of it) and what to do.

use super::records::MAX_RECORD_BYTES;
use std::fmt;

/// The most characters of a cell an error quotes.
pub const QUOTE_CHARS: usize = 80;

/// Why a CSV could not be read. Lines and columns are 1-based, as an editor shows them.
#[derive(Debug)]
pub enum DataError {
    /// The file could not be opened or read.
    Io {
        /// The file, as the user named it.
        path: String,
        /// 1-based line where reading failed (`None`: opening it failed).
        line: Option<u64>,
        /// What the system said.
        source: std::io::Error,
    },
    /// A required column is missing from the header.
    MissingColumn {
        /// The file, as the user named it.
        path: String,
        /// The column's name.
        column: &'static str,
        /// The header looks like a raw time series (a time and forces): `capstan condition`
        /// makes pairs of it.
        raw: bool,
    },
    /// A header names a column twice.
    DuplicateColumn {
        /// The file, as the user named it.
        path: String,
        /// The column's name.
        column: String,
        /// 1-based column of its first occurrence.
        first: usize,
        /// 1-based column of its second occurrence.
        second: usize,
    },
    /// A header cell is empty.
    UnnamedColumn {
        /// The file, as the user named it.
        path: String,
        /// 1-based column of the header.
        column: usize,
    },
    /// A cell is not what its column needs.
    BadCell {
        /// The file, as the user named it.
        path: String,
        /// 1-based line of the file.
        line: u64,
        /// 1-based column (cell) of the line.
        column: usize,
        /// The column's name in the header.
        name: String,
        /// The cell as found (the message quotes at most [`QUOTE_CHARS`] characters of it).
        value: String,
        /// What is wrong with it.
        reason: String,
    },
    /// A row has another number of cells than the header.
    CellCount {
        /// The file, as the user named it.
        path: String,
        /// 1-based line of the file.
        line: u64,
        /// Cells in the row.
        found: usize,
        /// Cells in the header.
        expected: usize,
        /// Why, when it shows: a trailing comma, a stray carriage return.
        why: Option<&'static str>,
    },
    /// The file has a header but no rows.
    Empty {
        /// The file, as the user named it.
        path: String,
    },
    /// The file is empty: not even a header.
    NoHeader {
        /// The file, as the user named it.
        path: String,
    },
    /// The first line is a comment (`# ...`).
    Comment {
        /// The file, as the user named it.
        path: String,
        /// 1-based line of the file.
        line: u64,
    },
    /// The header has one column that looks like several joined by another separator.
    Separator {
        /// The file, as the user named it.
        path: String,
        /// The header line as read.
        header: String,
        /// The separator the header seems to use.
        separator: char,
        /// The rows write decimals with a comma (`1,5`).
        decimal_comma: bool,
        /// The header looks like a raw time series (Logger Pro's, a logger's).
        raw: bool,
    },
    /// A record is longer than any pairs CSV line can be (a binary file, or a quote never
    /// closed).
    TooLong {
        /// The file, as the user named it.
        path: String,
        /// 1-based line of the file.
        line: u64,
        /// 1-based column (cell) of the line.
        column: usize,
        /// The record is inside a quoted cell.
        quoted: bool,
    },
    /// The file ends inside a quoted cell.
    UnclosedQuote {
        /// The file, as the user named it.
        path: String,
        /// 1-based line of the file.
        line: u64,
        /// 1-based column (cell) of the line.
        column: usize,
    },
    /// A cell is not UTF-8 text.
    NotText {
        /// The file, as the user named it.
        path: String,
        /// 1-based line of the file.
        line: u64,
        /// 1-based column (cell) of the line.
        column: usize,
    },
    /// Two rows have the same cord, run and step.
    DuplicateRow {
        /// The file, as the user named it.
        path: String,
        /// 1-based line of the file.
        line: u64,
        /// 1-based line of the first such row.
        first_line: u64,
        /// The cord, run and step, in words.
        key: String,
    },
    /// The data cannot come from a capstan: no row has T2 above T1.
    NoFriction {
        /// The file, as the user named it.
        path: String,
        /// Rows in the file (none has T2 above T1).
        rows: usize,
    },
    /// T2 is below T1 in most rows: the columns look swapped.
    Swapped {
        /// The file, as the user named it.
        path: String,
        /// Rows in the file.
        rows: usize,
        /// Rows with T2 below T1.
        below: usize,
    },
    /// One run's readings of a channel are all at or below zero, down to below
    /// [`crate::REVERSED_BELOW_N`]: that run's sensor reads reversed.
    ReversedRun {
        /// The file, as the user named it.
        path: String,
        /// 1-based line of the run's lowest reading.
        line: u64,
        /// 1-based column (cell) of the line.
        column: usize,
        /// The channel's column (`t1_n` or `t2_n`).
        name: &'static str,
        /// The run's lowest reading, N.
        value: f64,
        /// The run in words (its cord and run number).
        run: String,
    },
    /// A column in a unit no capstan rig's data are in (tensions in grams, wraps in radians).
    UnitMistake {
        /// The file, as the user named it.
        path: String,
        /// 1-based line of the file.
        line: u64,
        /// 1-based column (cell) of the line.
        column: usize,
        /// The whole message: the unit the values look like (e.g. grams, radians) and what to do.
        why: String,
    },
    /// More rows than [`crate::plausible::MAX_SUSPECT_SHARE`] cannot be capstan data
    /// (swapped, negated, time going back, a run copied): each kind named with its lines.
    SuspectRows {
        /// The file, as the user named it.
        path: String,
        /// Rows in the file.
        rows: usize,
        /// Rows that cannot be capstan data.
        suspect: usize,
        /// Each kind of suspect row, with its lines.
        kinds: Vec<String>,
    },
    /// Most rows have a tension at or below zero: not tensions as a rig reads them.
    NotPositive {
        /// The file, as the user named it.
        path: String,
        /// Rows in the file.
        rows: usize,
        /// Rows with both tensions above zero (under half of them).
        positive: usize,
        /// 1-based line of the first row with a tension at or below zero.
        first_line: u64,
    },
}

/// At most [`QUOTE_CHARS`] characters of `s`, control characters escaped, with how long it
/// was if cut.
pub fn quote(s: &str) -> String {
    let n = s.chars().count();
    let shown: String = s
        .chars()
        .take(QUOTE_CHARS)
        .flat_map(|c| {
            if c.is_control() {
                c.escape_default().collect::<Vec<_>>()
            } else {
                vec![c]
            }
        })
        .collect();
    if n > QUOTE_CHARS {
        format!("{shown}… ({n} characters)")
    } else {
        shown
    }
}

/// How a message names `separator`: "tabs", or the character in backticks.
fn separator_name(separator: char) -> String {
    match separator {
        '\t' => "tabs".to_string(),
        c => format!("`{c}`"),
    }
}

/// The command that turns `path`, separated by `separator`, into comma-separated values (its
/// decimal commas into points first, when it has them).
fn separator_fix(path: &str, separator: char, decimal_comma: bool) -> String {
    let e = separator.escape_default();
    if decimal_comma {
        format!(
            "its decimals are written with commas, so turn them into points first: \
             `sed -e 's/,/./g' -e 's/{e}/,/g' {path} > fixed.csv`"
        )
    } else {
        format!("e.g. `tr '{e}' ',' < {path} > fixed.csv`")
    }
}

/// What to do with a raw time series: `capstan condition`.
fn to_condition(path: &str) -> String {
    format!(
        "turn it into pairs by the firmware's windows with `capstan condition {path} --out DIR \
         --wrap-deg DEG` (it reads loggers' CSV and Logger Pro's exports, decimal commas \
         included), then give DIR/pairs.csv"
    )
}

impl fmt::Display for DataError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use DataError::*;
        match self {
            Io {
                path,
                line: Some(l),
                source,
            } => write!(f, "{path}:{l}: cannot read: {source}"),
            Io { path, source, .. } => write!(f, "{path}: {source}"),
            MissingColumn {
                path,
                column,
                raw: false,
            } => write!(
                f,
                "{path}:1: missing required column `{column}` (a pairs CSV needs wrap_deg, \
                 t1_n and t2_n)"
            ),
            MissingColumn {
                path, raw: true, ..
            } => write!(
                f,
                "{path}:1: a raw time series, not pairs (a pairs CSV has one row per level: \
                 wrap_deg, t1_n, t2_n); {}",
                to_condition(path)
            ),
            DuplicateColumn {
                path,
                column,
                first,
                second,
            } => write!(
                f,
                "{path}:1:{second}: column `{column}` appears twice (also column {first}): \
                 rename or remove one"
            ),
            UnnamedColumn { path, column } => write!(
                f,
                "{path}:1:{column}: header column {column} has no name (a trailing comma?): \
                 name it or remove it"
            ),
            BadCell {
                path,
                line,
                column,
                name,
                value,
                reason,
            } => write!(
                f,
                "{path}:{line}:{column}: column `{name}`: {reason} (found `{}`)",
                quote(value)
            ),
            CellCount {
                path,
                line,
                found,
                expected,
                why,
            } => write!(
                f,
                "{path}:{line}: {found} cells where the header has {expected}{}",
                why.map_or(String::new(), |w| format!(": {w}"))
            ),
            Empty { path } => write!(f, "{path}: no data rows (a header and nothing else)"),
            NoHeader { path } => {
                write!(
                    f,
                    "{path}: the file is empty (expected a CSV header and rows)"
                )
            }
            Comment { path, line } => write!(
                f,
                "{path}:{line}: a comment line (`#`) before the header: a pairs CSV starts with \
                 its header; remove the comment lines (e.g. `grep -v '^#' {path} > clean.csv`)"
            ),
            Separator {
                path,
                header,
                separator,
                raw: true,
                ..
            } => write!(
                f,
                "{path}:1: the header `{}` is that of a raw time series, separated by {} (a \
                 logger's or Logger Pro's export), not pairs; {}",
                quote(header),
                separator_name(*separator),
                to_condition(path)
            ),
            Separator {
                path,
                header,
                separator,
                decimal_comma,
                raw: false,
            } => write!(
                f,
                "{path}:1: the header `{}` is one column: the file looks separated by {}; \
                 capstan reads comma-separated values ({})",
                quote(header),
                separator_name(*separator),
                separator_fix(path, *separator, *decimal_comma)
            ),
            TooLong {
                path,
                line,
                column,
                quoted: false,
            } => write!(
                f,
                "{path}:{line}:{column}: a line longer than {MAX_RECORD_BYTES} bytes: not a \
                 pairs CSV (a binary file?)"
            ),
            TooLong {
                path,
                line,
                column,
                quoted: true,
            } => write!(
                f,
                "{path}:{line}:{column}: a quoted cell that runs over {MAX_RECORD_BYTES} bytes \
                 (a `\"` never closed?)"
            ),
            UnclosedQuote { path, line, column } => write!(
                f,
                "{path}:{line}:{column}: a quoted cell opened here is never closed (a stray `\"`?)"
            ),
            NotText { path, line, column } => write!(
                f,
                "{path}:{line}:{column}: not UTF-8 text (a binary file, or another encoding: \
                 save it as UTF-8 CSV)"
            ),
            DuplicateRow {
                path,
                line,
                first_line,
                key,
            } => write!(
                f,
                "{path}:{line}: {key} again (first on line {first_line}): two sessions \
                 concatenated with the same run numbers, or two cords no column tells apart? \
                 Give each its own run numbers, a `session` column, or the column that \
                 separates the cords (capstan_diameter_mm, or a `cord` label)"
            ),
            NoFriction { path, rows } => write!(
                f,
                "{path}: T2 is at most T1 in all {rows} rows: a capstan amplifies tension \
                 (T2 > T1), so these are not capstan data (are the t1_n and t2_n columns \
                 swapped, or the drive off?)"
            ),
            Swapped { path, rows, below } => write!(
                f,
                "{path}: T2 is below T1 in {below} of {rows} rows: a capstan amplifies tension \
                 (T2 > T1), so the t1_n and t2_n columns look swapped; t1_n is the servo (low) \
                 side: swap the two names in the header"
            ),
            ReversedRun {
                path,
                line,
                column,
                name,
                value,
                run,
            } => write!(
                f,
                "{path}:{line}:{column}: {name} = {value} N, and every {name} reading of {run} \
                 is at or below zero: a cord under load cannot push, so that run's sensor reads \
                 reversed (or its zero is far off: a rig's negative-force check stops at \
                 {below} N); fix the run's sign or leave the run out",
                below = -crate::REVERSED_BELOW_N
            ),
            UnitMistake {
                path,
                line,
                column,
                why,
            } => write!(f, "{path}:{line}:{column}: {why}"),
            SuspectRows {
                path,
                rows,
                suspect,
                kinds,
            } => write!(
                f,
                "{path}: {suspect} of {rows} rows ({:.1} %) cannot be capstan data, more than \
                 the {:.0} % a data set may hold with a warning: {}; fix or remove them",
                100.0 * *suspect as f64 / (*rows).max(1) as f64,
                100.0 * crate::plausible::MAX_SUSPECT_SHARE,
                kinds.join("; ")
            ),
            NotPositive {
                path,
                rows,
                positive,
                first_line,
            } => write!(
                f,
                "{path}: only {positive} of {rows} rows have both tensions above zero (the \
                 first without is line {first_line}): a loaded cord reads above zero, so these \
                 are not tensions as a rig measures them (negated, or another sign convention?)"
            ),
        }
    }
}

// The I/O error's text is already part of the message (`path: error`), so it is not repeated
// as a `source()` (which `{:#}` would print a second time).
impl std::error::Error for DataError {}

#[cfg(test)]
mod tests {
    use super::quote;

    #[test]
    fn quotes_are_short_and_on_one_line() {
        assert_eq!(quote("abc"), "abc");
        assert_eq!(quote("a\nb\r"), "a\\nb\\r");
        let long = "x".repeat(1_000_000);
        let q = quote(&long);
        assert!(q.len() < 120 && q.ends_with("(1000000 characters)"), "{q}");
    }
}
