//! Reading a pairs CSV: the header's columns, then every row's cells checked against their
//! column's physical range ([`super::ranges`]), each error at its file, line and column.

use super::error::DataError;
use super::ranges::{self, Range, RangeError};
use super::records::{Record, RecordError, Records};
use super::structure::Structure;
use super::{Dataset, LabelColumn, LabelRole, Pair, PAIRS_HEADER};
use std::io::Read;

/// Text columns that name the cord: rows that differ in one are on different cords.
pub const CORD_LABELS: [&str; 2] = ["cord", "material"];
/// Text columns that name the session: rows that differ in one are in different runs (two
/// sessions with the same run numbers stay apart). `boot` is written by `capstan log`: the
/// board's start a run belongs to (its run numbers start again after a reset).
pub const RUN_LABELS: [&str; 3] = ["session", "date", "boot"];
/// Free-text columns, kept but not used.
pub const NOTE_COLUMNS: [&str; 2] = ["note", "comment"];

/// What a column of the file is.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Col {
    /// Column `i` of [`PAIRS_HEADER`].
    Known(usize),
    /// Text column `k` of the data set's labels.
    Label(usize),
    /// Numeric column `k` of the data set's extras.
    Extra(usize),
}

/// The header's columns.
struct Header {
    names: Vec<String>,
    cols: Vec<Col>,
    labels: Vec<LabelColumn>,
    extras: Vec<String>,
    known: [Option<usize>; 8],
}

fn role_of(name: &str) -> Option<LabelRole> {
    if CORD_LABELS.contains(&name) {
        Some(LabelRole::Cord)
    } else if RUN_LABELS.contains(&name) {
        Some(LabelRole::Run)
    } else if NOTE_COLUMNS.contains(&name) {
        Some(LabelRole::Note)
    } else {
        None
    }
}

fn record_error(e: RecordError, path: &str) -> DataError {
    let path = path.to_string();
    match e {
        RecordError::Io { line, source } => DataError::Io {
            path,
            line: Some(line),
            source,
        },
        RecordError::TooLong {
            line,
            column,
            quoted,
        } => DataError::TooLong {
            path,
            line,
            column,
            quoted,
        },
        RecordError::NotText { line, column } => DataError::NotText { path, line, column },
        RecordError::UnclosedQuote { line, column } => {
            DataError::UnclosedQuote { path, line, column }
        }
    }
}

/// Read a pairs CSV from any reader; `path` names it in errors.
pub fn read(reader: impl Read, path: &str) -> Result<Dataset, DataError> {
    let mut records = Records::new(reader);
    let next = |r: &mut Records<_>| r.next_record().map_err(|e| record_error(e, path));
    let Some(first) = next(&mut records)? else {
        return Err(DataError::NoHeader { path: path.into() });
    };
    let header = header(&first, path, &mut records)?;
    let mut pairs = Vec::new();
    let mut lines = Vec::new();
    while let Some(rec) = next(&mut records)? {
        pairs.push(row(&rec, &header, path)?);
        lines.push(rec.line);
    }
    if pairs.is_empty() {
        return Err(DataError::Empty { path: path.into() });
    }
    let structure = Structure::infer(&pairs, &header.names, &header.labels, &lines, path)?;
    Ok(Dataset {
        source: path.to_string(),
        header: header.names,
        extra_columns: header.extras,
        label_columns: header.labels,
        pairs,
        lines,
        structure,
    })
}

/// The header: required columns there, none twice or unnamed, one column that looks like
/// another separator refused with the way to convert it.
fn header<R: Read>(
    rec: &Record,
    path: &str,
    records: &mut Records<R>,
) -> Result<Header, DataError> {
    let p = || path.to_string();
    let names: Vec<String> = rec.cells.iter().map(|c| c.text.clone()).collect();
    if names.first().is_some_and(|n| n.starts_with('#')) {
        return Err(DataError::Comment {
            path: p(),
            line: rec.line,
        });
    }
    if let [only] = names.as_slice() {
        if let Some(sep) = [';', '\t', '|', ' ']
            .into_iter()
            .find(|&c| only.contains(c))
        {
            // Decimal commas: the next line split at the commas has digits on both sides.
            let next = records.next_record().ok().flatten();
            let decimal_comma = next.is_some_and(|r| {
                r.cells.len() > 1
                    && r.cells.windows(2).any(|w| {
                        w[0].text.ends_with(|c: char| c.is_ascii_digit())
                            && w[1].text.starts_with(|c: char| c.is_ascii_digit())
                    })
            });
            return Err(DataError::Separator {
                path: p(),
                header: only.clone(),
                separator: sep,
                decimal_comma,
                raw: looks_raw(&only.split(sep).map(String::from).collect::<Vec<_>>())
                    || looks_raw(std::slice::from_ref(only)),
            });
        }
    }
    let mut seen = std::collections::HashMap::with_capacity(names.len());
    let (mut cols, mut labels, mut extras) = (Vec::new(), Vec::new(), Vec::new());
    let mut known = [None; 8];
    for (i, name) in names.iter().enumerate() {
        if name.is_empty() {
            return Err(DataError::UnnamedColumn {
                path: p(),
                column: i + 1,
            });
        }
        if let Some(first) = seen.insert(name.as_str(), i + 1) {
            return Err(DataError::DuplicateColumn {
                path: p(),
                column: name.clone(),
                first,
                second: i + 1,
            });
        }
        if let Some(k) = PAIRS_HEADER.iter().position(|h| h == name) {
            known[k] = Some(i);
            cols.push(Col::Known(k));
        } else if let Some(role) = role_of(name) {
            cols.push(Col::Label(labels.len()));
            labels.push(LabelColumn {
                name: name.clone(),
                role,
            });
        } else {
            cols.push(Col::Extra(extras.len()));
            extras.push(name.clone());
        }
    }
    for (k, column) in [(1, "wrap_deg"), (6, "t1_n"), (7, "t2_n")] {
        if known[k].is_none() {
            return Err(DataError::MissingColumn {
                path: p(),
                column,
                raw: looks_raw(&names),
            });
        }
    }
    Ok(Header {
        names,
        cols,
        labels,
        extras,
        known,
    })
}

/// A header of a raw time series, not of pairs: Logger Pro's text export, or a time column
/// beside force columns (`t_s`, `time_s`, `Time (s)`; `t1_n`, `Force (N)`, `t1_counts`) and no
/// wrap.
fn looks_raw(names: &[String]) -> bool {
    let norm: Vec<String> = names
        .iter()
        .map(|n| {
            n.chars()
                .filter(|c| c.is_alphanumeric())
                .flat_map(char::to_lowercase)
                .collect()
        })
        .collect();
    if norm.iter().any(|n| n.starts_with("vernierformat")) {
        return true;
    }
    let time = norm.iter().any(|n| {
        ["ts", "times", "time", "t", "xvalue"].contains(&n.as_str()) || n.starts_with("time")
    });
    let force = norm
        .iter()
        .any(|n| n.starts_with("force") || n.ends_with("counts") || n == "t1n" || n == "t2n");
    time && force && !norm.iter().any(|n| n == "wrapdeg")
}

/// The range of column `k` of [`PAIRS_HEADER`].
fn range_of(k: usize) -> &'static Range {
    match k {
        0 => &ranges::DIAMETER_MM,
        1 => &ranges::WRAP_DEG,
        2 => &ranges::DRIVE_V,
        3 => &ranges::RUN,
        4 => &ranges::STEP,
        5 => &ranges::TIME_S,
        _ => &ranges::TENSION_N,
    }
}

fn number(raw: &str, range: &Range) -> Result<f64, CellError> {
    if raw.is_empty() {
        return Err(CellError::Empty);
    }
    let v: f64 = raw.parse().map_err(|_| {
        let decimal_comma = raw.split_once(',').is_some_and(|(a, b)| {
            let digits = |s: &str| !s.is_empty() && s.bytes().all(|c| c.is_ascii_digit());
            digits(a.trim_start_matches('-')) && digits(b)
        });
        if raw.starts_with('#') {
            CellError::NotANumber(" (a comment line? a pairs CSV has none)")
        } else if decimal_comma {
            CellError::NotANumber(" (write decimals with a point: 1.5)")
        } else {
            CellError::NotANumber("")
        }
    })?;
    if !v.is_finite() {
        return Err(CellError::NotFinite);
    }
    Ok(range.check(v)?)
}

/// Why a numeric cell is refused (the `reason` of [`DataError::BadCell`]).
#[derive(Debug, thiserror::Error)]
enum CellError {
    #[error("empty cell")]
    Empty,
    /// Not a number; with a hint (" (write decimals with a point: 1.5)") or "".
    #[error("not a number{0}")]
    NotANumber(&'static str),
    #[error("not a finite number")]
    NotFinite,
    #[error(transparent)]
    Range(#[from] RangeError),
}

/// One row's pair.
fn row(rec: &Record, h: &Header, path: &str) -> Result<Pair, DataError> {
    if rec.cells.len() != h.cols.len() {
        let n = rec.cells.len();
        let why = if rec.cut_by_cr {
            Some(
                "the line is cut by a carriage return (\\r) inside it, in a file whose lines end \
                 in line feeds: a stray \\r (save the file with one kind of line ending)",
            )
        } else if n == h.cols.len() + 1 && rec.cells[n - 1].text.is_empty() {
            Some("a trailing comma at the end of the line (an empty last cell): remove it")
        } else {
            None
        };
        return Err(DataError::CellCount {
            path: path.to_string(),
            line: rec.line,
            found: n,
            expected: h.cols.len(),
            why,
        });
    }
    let mut pair = Pair {
        capstan_diameter_mm: None,
        wrap_deg: f64::NAN,
        drive_v: None,
        run: None,
        step: None,
        time_s: None,
        t1_n: f64::NAN,
        t2_n: f64::NAN,
        extra: vec![f64::NAN; h.extras.len()],
        labels: vec![String::new(); h.labels.len()],
    };
    for (i, (cell, col)) in rec.cells.iter().zip(&h.cols).enumerate() {
        let bad = |reason: String| DataError::BadCell {
            path: path.to_string(),
            line: cell.line,
            column: i + 1,
            name: h.names[i].clone(),
            value: cell.text.clone(),
            reason,
        };
        match *col {
            Col::Label(k) => pair.labels[k] = cell.text.clone(),
            Col::Extra(k) => {
                let text_hint = |r: CellError| {
                    let r = r.to_string();
                    if r.starts_with("not a number") {
                        format!(
                            "{r}; a text column is read only under a label name ({}, {}, {})",
                            CORD_LABELS.join(", "),
                            RUN_LABELS.join(", "),
                            NOTE_COLUMNS.join(", ")
                        )
                    } else {
                        r
                    }
                };
                pair.extra[k] =
                    number(&cell.text, &ranges::EXTRA).map_err(|r| bad(text_hint(r)))?;
            }
            Col::Known(k) => {
                let v = number(&cell.text, range_of(k)).map_err(|r| bad(r.to_string()))?;
                match k {
                    0 => pair.capstan_diameter_mm = Some(v),
                    1 => pair.wrap_deg = v,
                    2 => pair.drive_v = Some(v),
                    3 => pair.run = Some(v),
                    4 => pair.step = Some(v),
                    5 => pair.time_s = Some(v),
                    6 => pair.t1_n = v,
                    _ => pair.t2_n = v,
                }
            }
        }
    }
    debug_assert!(h.known[1].is_some());
    Ok(pair)
}
