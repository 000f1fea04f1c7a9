//! Conditioned pairs on disk: the CSV schema shared by `simulate`, `log`, `analyze` and
//! `diagnose`, read with errors that name the file, line and column.
//!
//! Schema: `capstan_diameter_mm,wrap_deg,drive_v,run,step,time_s,t1_n,t2_n`. Reading needs
//! only `wrap_deg,t1_n,t2_n`; the other known columns are optional, and any further column
//! must be numeric and is kept (by name) for the analysis.
//!
//! Tensions may be zero or negative: a sensor with a zero offset reads a slack or lightly
//! loaded cord below zero, and those readings are what tells the offset. Values no force sensor
//! on a capstan rig produces (|T| over [`MAX_TENSION_N`]), wraps over [`MAX_WRAP_DEG`] and
//! diameters over [`MAX_DIAMETER_MM`] are refused with their file, line and column.

use serde::Serialize;
use std::fmt;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

/// Largest tension magnitude accepted, N: ten kilonewtons is far beyond any bench capstan rig
/// (the thesis rig's sensors end at about 55 N) and keeps every sum of squares finite.
pub const MAX_TENSION_N: f64 = 1.0e4;
/// Largest wrap accepted, deg (ten turns).
pub const MAX_WRAP_DEG: f64 = 3600.0;
/// Largest capstan diameter accepted, mm.
pub const MAX_DIAMETER_MM: f64 = 1000.0;

/// The columns `simulate` and `log` write, in order.
pub const PAIRS_HEADER: [&str; 8] = [
    "capstan_diameter_mm",
    "wrap_deg",
    "drive_v",
    "run",
    "step",
    "time_s",
    "t1_n",
    "t2_n",
];

/// One conditioned pair.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Pair {
    /// Capstan diameter, mm.
    pub capstan_diameter_mm: Option<f64>,
    /// Wrap angle, deg.
    pub wrap_deg: f64,
    /// Drive voltage, V.
    pub drive_v: Option<f64>,
    /// Repeat run, 1-based.
    pub run: Option<f64>,
    /// Step within the run (time order).
    pub step: Option<f64>,
    /// Middle of the conditioning window, s since the trigger.
    pub time_s: Option<f64>,
    /// Low-side tension, N.
    pub t1_n: f64,
    /// High-side tension, N.
    pub t2_n: f64,
    /// Further numeric columns, in the order of [`Dataset::extra_columns`].
    #[serde(skip)]
    pub extra: Vec<f64>,
}

impl Pair {
    /// Wrap angle, rad.
    pub fn wrap_rad(&self) -> f64 {
        self.wrap_deg.to_radians()
    }

    /// Amplification T2/T1.
    pub fn amplification(&self) -> f64 {
        self.t2_n / self.t1_n
    }
}

/// A loaded CSV of pairs.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Dataset {
    /// Where it came from (for messages).
    pub source: String,
    /// The header as read.
    pub header: Vec<String>,
    /// Names of the extra numeric columns.
    pub extra_columns: Vec<String>,
    /// The rows, in file order.
    pub pairs: Vec<Pair>,
}

impl Dataset {
    /// True if every row has the optional column `name`.
    pub fn has_column(&self, name: &str) -> bool {
        self.header.iter().any(|h| h == name)
    }
}

/// Why a CSV could not be read. Lines and columns are 1-based, as an editor shows them.
#[derive(Debug)]
pub enum DataError {
    /// The file could not be opened or read.
    Io {
        path: String,
        source: std::io::Error,
    },
    /// The CSV is malformed at a place.
    Csv {
        path: String,
        line: u64,
        message: String,
    },
    /// A required column is missing from the header.
    MissingColumn { path: String, column: &'static str },
    /// A header names a column twice.
    DuplicateColumn { path: String, column: String },
    /// A cell is not what its column needs.
    BadCell {
        path: String,
        line: u64,
        column: usize,
        name: String,
        value: String,
        reason: &'static str,
    },
    /// The file has a header but no rows.
    Empty { path: String },
    /// The file is empty: not even a header.
    NoHeader { path: String },
    /// The header has one column that looks like several joined by another separator.
    Separator {
        path: String,
        header: String,
        separator: char,
    },
    /// A line is longer than any pairs CSV line can be (e.g. a binary file).
    LineTooLong { path: String, line: u64 },
    /// The data cannot come from a capstan: no row has T2 above T1.
    NoFriction { path: String, rows: usize },
}

impl fmt::Display for DataError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DataError::Io { path, source } => write!(f, "{path}: {source}"),
            DataError::Csv {
                path,
                line,
                message,
            } => write!(f, "{path}:{line}: {message}"),
            DataError::MissingColumn { path, column } => {
                write!(f, "{path}:1: missing required column `{column}`")
            }
            DataError::DuplicateColumn { path, column } => {
                write!(f, "{path}:1: column `{column}` appears twice")
            }
            DataError::BadCell {
                path,
                line,
                column,
                name,
                value,
                reason,
            } => write!(
                f,
                "{path}:{line}:{column}: column `{name}`: {reason} (found `{value}`)"
            ),
            DataError::Empty { path } => write!(f, "{path}: no data rows"),
            DataError::NoHeader { path } => {
                write!(
                    f,
                    "{path}: the file is empty (expected a CSV header and rows)"
                )
            }
            DataError::Separator {
                path,
                header,
                separator,
            } => write!(
                f,
                "{path}:1: the header `{header}` is one column: the file looks separated by \
                 {}; capstan reads comma-separated values (e.g. `tr '{}' ','`)",
                match separator {
                    '\t' => "tabs".to_string(),
                    c => format!("`{c}`"),
                },
                separator.escape_default()
            ),
            DataError::LineTooLong { path, line } => write!(
                f,
                "{path}:{line}: a line longer than {} bytes: not a pairs CSV (a binary file?)",
                MAX_LINE_BYTES
            ),
            DataError::NoFriction { path, rows } => write!(
                f,
                "{path}: T2 is at most T1 in all {rows} rows: a capstan amplifies tension \
                 (T2 > T1), so these are not capstan data (are the t1_n and t2_n columns \
                 swapped, or the drive off?)"
            ),
        }
    }
}

// The I/O error's text is already part of the message (`path: error`), so it is not repeated
// as a `source()` (which `{:#}` would print a second time).
impl std::error::Error for DataError {}

/// Read a pairs CSV from a file.
pub fn load_pairs(path: &Path) -> Result<Dataset, DataError> {
    let name = path.display().to_string();
    let file = std::fs::File::open(path).map_err(|source| DataError::Io {
        path: name.clone(),
        source,
    })?;
    read_pairs(file, &name)
}

/// Read a pairs CSV from any reader; `source` names it in errors.
pub fn read_pairs(reader: impl Read, source: &str) -> Result<Dataset, DataError> {
    let path = source.to_string();
    let mut rdr = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_reader(LineLimit::new(reader));
    let header: Vec<String> = rdr
        .headers()
        .map_err(|e| line_error(e, &path))?
        .iter()
        .map(str::to_string)
        .collect();
    check_header(&header, &path)?;
    let find = |name: &str| header.iter().position(|h| h == name);
    let required = |column: &'static str| {
        find(column).ok_or(DataError::MissingColumn {
            path: path.clone(),
            column,
        })
    };
    let (wrap, t1, t2) = (required("wrap_deg")?, required("t1_n")?, required("t2_n")?);
    let optional = ["capstan_diameter_mm", "drive_v", "run", "step", "time_s"].map(find);
    let extra_idx: Vec<usize> = (0..header.len())
        .filter(|i| !PAIRS_HEADER.contains(&header[*i].as_str()))
        .collect();
    let mut pairs = Vec::new();
    for record in rdr.records() {
        let record = record.map_err(|e| line_error(e, &path))?;
        let line = record.position().map_or(0, |p| p.line());
        let cell = |i: usize, rule: Rule| -> Result<f64, DataError> {
            let raw = record.get(i).unwrap_or("");
            parse_cell(raw, rule).map_err(|reason| DataError::BadCell {
                path: path.clone(),
                line,
                column: i + 1,
                name: header[i].clone(),
                value: raw.to_string(),
                reason,
            })
        };
        let opt = |i: Option<usize>, rule: Rule| i.map(|i| cell(i, rule)).transpose();
        pairs.push(Pair {
            capstan_diameter_mm: opt(optional[0], Rule::Positive(MAX_DIAMETER_MM))?,
            wrap_deg: cell(wrap, Rule::Positive(MAX_WRAP_DEG))?,
            drive_v: opt(optional[1], Rule::Bounded(MAX_DRIVE_V))?,
            run: opt(optional[2], Rule::Bounded(MAX_INDEX))?,
            step: opt(optional[3], Rule::Bounded(MAX_INDEX))?,
            time_s: opt(optional[4], Rule::Bounded(MAX_TIME_S))?,
            t1_n: cell(t1, Rule::Tension)?,
            t2_n: cell(t2, Rule::Tension)?,
            extra: extra_idx
                .iter()
                .map(|&i| cell(i, Rule::Finite))
                .collect::<Result<_, _>>()?,
        });
    }
    if pairs.is_empty() {
        return Err(DataError::Empty { path });
    }
    Ok(Dataset {
        source: path,
        extra_columns: extra_idx.iter().map(|&i| header[i].clone()).collect(),
        header,
        pairs,
    })
}

/// The longest line a pairs CSV may have (a header of a few hundred columns fits many times).
pub const MAX_LINE_BYTES: usize = 1 << 20;
/// |drive_v| at most this, V.
const MAX_DRIVE_V: f64 = 1000.0;
/// |run|, |step| at most this.
const MAX_INDEX: f64 = 1e9;
/// |time_s| at most this (beyond Unix-epoch timestamps for centuries), s.
const MAX_TIME_S: f64 = 1e10;

/// A CSV error with the line it is at; a line over [`MAX_LINE_BYTES`] is named as such.
fn line_error(e: csv::Error, path: &str) -> DataError {
    let line = e.position().map_or(0, |p| p.line());
    if let csv::ErrorKind::Io(io) = e.kind() {
        if io.kind() == std::io::ErrorKind::InvalidData && io.to_string() == LINE_TOO_LONG {
            return DataError::LineTooLong {
                path: path.to_string(),
                line: line.max(1),
            };
        }
    }
    DataError::Csv {
        path: path.to_string(),
        line,
        message: e.to_string(),
    }
}

/// An empty file, another separator, a column named twice (checked in linear time).
fn check_header(header: &[String], path: &str) -> Result<(), DataError> {
    let path = path.to_string();
    if header.is_empty() || header.iter().all(|h| h.is_empty()) {
        return Err(DataError::NoHeader { path });
    }
    if let [only] = header {
        if let Some(sep) = [';', '\t', '|', ' ']
            .into_iter()
            .find(|&c| only.contains(c))
        {
            return Err(DataError::Separator {
                path,
                header: only.chars().take(80).collect(),
                separator: sep,
            });
        }
    }
    let mut seen = std::collections::HashSet::with_capacity(header.len());
    for h in header {
        if !seen.insert(h.as_str()) {
            return Err(DataError::DuplicateColumn {
                path,
                column: h.clone(),
            });
        }
    }
    Ok(())
}

const LINE_TOO_LONG: &str = "line too long";

/// A reader that fails on a line over [`MAX_LINE_BYTES`] (so `/dev/zero` or a binary file
/// given as a CSV ends in an error, not in unbounded memory).
struct LineLimit<R> {
    inner: R,
    since_newline: usize,
}

impl<R: Read> LineLimit<R> {
    fn new(inner: R) -> Self {
        LineLimit {
            inner,
            since_newline: 0,
        }
    }
}

impl<R: Read> Read for LineLimit<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        for &b in &buf[..n] {
            if b == b'\n' || b == b'\r' {
                self.since_newline = 0;
            } else {
                self.since_newline += 1;
                if self.since_newline > MAX_LINE_BYTES {
                    return Err(std::io::Error::new(
                        std::io::ErrorKind::InvalidData,
                        LINE_TOO_LONG,
                    ));
                }
            }
        }
        Ok(n)
    }
}

/// Data that cannot come from a capstan: no row with T2 above T1 (e.g. the columns swapped,
/// or T2 = T1 throughout: no friction to analyse).
pub fn check_capstan_data(ds: &Dataset) -> Result<(), DataError> {
    if ds.pairs.iter().any(|p| p.t2_n > p.t1_n) {
        return Ok(());
    }
    Err(DataError::NoFriction {
        path: ds.source.clone(),
        rows: ds.pairs.len(),
    })
}

#[derive(Clone, Copy)]
enum Rule {
    Finite,
    /// |v| at most the bound.
    Bounded(f64),
    /// Greater than zero and at most the bound.
    Positive(f64),
    /// A force reading: |v| ≤ [`MAX_TENSION_N`].
    Tension,
}

fn parse_cell(raw: &str, rule: Rule) -> Result<f64, &'static str> {
    if raw.is_empty() {
        return Err("empty cell");
    }
    let v: f64 = raw.parse().map_err(|_| "not a number")?;
    if !v.is_finite() {
        return Err("not a finite number");
    }
    match rule {
        Rule::Positive(_) if v <= 0.0 => Err("must be greater than zero"),
        Rule::Positive(max) if v > max => Err(match max {
            MAX_WRAP_DEG => "must be at most 3600 (ten turns)",
            _ => "must be at most 1000",
        }),
        Rule::Bounded(max) if v.abs() > max => Err(match max {
            MAX_DRIVE_V => "must be within ±1000 V",
            MAX_TIME_S => "must be within ±1e10 s",
            _ => "must be within ±1e9",
        }),
        Rule::Tension if v.abs() > MAX_TENSION_N => {
            Err("is beyond any force sensor of a capstan rig (|T| must be at most 10000 N)")
        }
        _ => Ok(v),
    }
}

/// Write pairs to a file (see [`write_pairs_to`]).
pub fn write_pairs(path: &Path, pairs: &[Pair]) -> anyhow::Result<()> {
    let file =
        std::fs::File::create(path).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    let mut w = std::io::BufWriter::new(file);
    write_pairs_to(&mut w, pairs)?;
    w.flush()?;
    Ok(())
}

/// The value of column `i` of [`PAIRS_HEADER`] in a pair (`None` when unknown).
fn column_value(p: &Pair, i: usize) -> Option<f64> {
    match i {
        0 => p.capstan_diameter_mm,
        1 => Some(p.wrap_deg).filter(|w| w.is_finite()),
        2 => p.drive_v,
        3 => p.run,
        4 => p.step,
        5 => p.time_s,
        6 => Some(p.t1_n),
        _ => Some(p.t2_n),
    }
}

/// Write pairs to any writer: the standard header ([`PAIRS_HEADER`]) minus any optional column
/// that the pairs do not all carry (so what is written reads back as it was).
pub fn write_pairs_to(w: &mut impl Write, pairs: &[Pair]) -> std::io::Result<()> {
    let columns = (0..PAIRS_HEADER.len())
        .filter(|&i| pairs.iter().all(|p| column_value(p, i).is_some()))
        .collect();
    let mut out = PairsWriter::with_columns(w, columns)?;
    pairs.iter().try_for_each(|p| out.write(p))
}

/// Writes pairs one at a time, as they come (`capstan log` writes each step's pair when the rig
/// reports it): the header first, then one row per [`PairsWriter::write`]. With
/// [`PairsWriter::new`] every column of [`PAIRS_HEADER`] is written, since later pairs are not
/// known yet: a `None`, or a wrap angle that is not finite (unknown), is an empty cell. A row
/// with an empty cell does not read back with [`read_pairs`]; `capstan log` keeps such rows in a
/// file of their own.
pub struct PairsWriter<W: Write> {
    inner: W,
    /// Indices into [`PAIRS_HEADER`], in order.
    columns: Vec<usize>,
}

impl<W: Write> PairsWriter<W> {
    /// Start the CSV with every column: write the header.
    pub fn new(inner: W) -> std::io::Result<Self> {
        Self::with_columns(inner, (0..PAIRS_HEADER.len()).collect())
    }

    /// Start the CSV with these columns of [`PAIRS_HEADER`] (indices, in order).
    fn with_columns(mut inner: W, columns: Vec<usize>) -> std::io::Result<Self> {
        let names: Vec<&str> = columns.iter().map(|&i| PAIRS_HEADER[i]).collect();
        writeln!(inner, "{}", names.join(","))?;
        Ok(PairsWriter { inner, columns })
    }

    /// Write one pair (not flushed).
    pub fn write(&mut self, p: &Pair) -> std::io::Result<()> {
        let cells: Vec<String> = self
            .columns
            .iter()
            .map(|&i| column_value(p, i).map_or(String::new(), |v| v.to_string()))
            .collect();
        writeln!(self.inner, "{}", cells.join(","))
    }

    /// Flush what was written to the underlying writer.
    pub fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// The bundled thesis data (720 pairs), compiled into the binary so no path is needed.
pub const THESIS_CSV: &str = include_str!("../data/thesis-conditioned.csv");

/// The bundled thesis data, parsed.
pub fn thesis_dataset() -> Dataset {
    read_pairs(THESIS_CSV.as_bytes(), "thesis-conditioned.csv (bundled)")
        .expect("bundled data is valid")
}

/// A path for messages about the bundled data set.
pub fn bundled_path() -> PathBuf {
    PathBuf::from("data/thesis-conditioned.csv")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pairs_written_one_at_a_time_read_back_and_unknowns_are_empty_cells() {
        let pair = |wrap_deg: f64, run: Option<f64>| Pair {
            capstan_diameter_mm: Some(12.7),
            wrap_deg,
            drive_v: Some(10.0),
            run,
            step: Some(2.0),
            time_s: Some(1.65),
            t1_n: 1.5469999,
            t2_n: 3.1938002,
            extra: Vec::new(),
        };
        let mut w = PairsWriter::new(Vec::new()).unwrap();
        w.write(&pair(360.0, Some(1.0))).unwrap();
        w.write(&pair(450.0, Some(2.0))).unwrap();
        let csv = String::from_utf8(w.inner).unwrap();
        let back = read_pairs(csv.as_bytes(), "test").unwrap();
        assert_eq!(back.header.join(","), PAIRS_HEADER.join(","));
        assert_eq!(back.pairs, [pair(360.0, Some(1.0)), pair(450.0, Some(2.0))]);
        let mut w = PairsWriter::new(Vec::new()).unwrap();
        w.write(&pair(f64::NAN, None)).unwrap();
        let csv = String::from_utf8(w.inner).unwrap();
        assert_eq!(
            csv.lines().nth(1),
            Some("12.7,,10,,2,1.65,1.5469999,3.1938002")
        );
    }

    #[test]
    fn bundled_thesis_data_has_720_rows_and_the_time_column_is_absent() {
        let d = thesis_dataset();
        assert_eq!(d.pairs.len(), 720);
        assert!(!d.has_column("time_s"));
        assert_eq!(d.pairs[1].t1_n, 1.157991);
        assert_eq!(d.pairs[1].run, Some(1.0));
    }

    fn err(csv: &str) -> String {
        read_pairs(csv.as_bytes(), "x.csv").unwrap_err().to_string()
    }

    #[test]
    fn bad_input_names_file_line_and_column() {
        assert_eq!(
            err("wrap_deg,t1_n\n270,1\n"),
            "x.csv:1: missing required column `t2_n`"
        );
        assert_eq!(
            err("wrap_deg,t1_n,t2_n\n270,1,2\n270,abc,2\n"),
            "x.csv:3:2: column `t1_n`: not a number (found `abc`)"
        );
        assert_eq!(
            err("wrap_deg,t1_n,t2_n\n0,1,2\n"),
            "x.csv:2:1: column `wrap_deg`: must be greater than zero (found `0`)"
        );
        assert_eq!(
            err("wrap_deg,t1_n,t2_n\n270,1e154,2\n"),
            "x.csv:2:2: column `t1_n`: is beyond any force sensor of a capstan rig (|T| must be at most 10000 N) (found `1e154`)"
        );
        // A reading at or below zero is data (a zero offset makes it real).
        let d = read_pairs(
            "wrap_deg,t1_n,t2_n\n270,0,2\n270,-0.16,0.3\n".as_bytes(),
            "x",
        )
        .unwrap();
        assert_eq!(d.pairs[1].t1_n, -0.16);
        assert_eq!(
            err("wrap_deg,t1_n,t2_n\n270,1,NaN\n"),
            "x.csv:2:3: column `t2_n`: not a finite number (found `NaN`)"
        );
        assert_eq!(
            err("wrap_deg,t1_n,t2_n\n270,1,\n"),
            "x.csv:2:3: column `t2_n`: empty cell (found ``)"
        );
        assert!(
            err("wrap_deg,t1_n,t2_n\n270,1\n").starts_with("x.csv:2:"),
            "{}",
            err("wrap_deg,t1_n,t2_n\n270,1\n")
        );
        assert_eq!(err("wrap_deg,t1_n,t2_n\n"), "x.csv: no data rows");
        assert_eq!(
            err("wrap_deg,t1_n,t1_n,t2_n\n"),
            "x.csv:1: column `t1_n` appears twice"
        );
        assert_eq!(
            err("wrap_deg,t1_n,t2_n,humidity\n270,1,2,wet\n"),
            "x.csv:2:4: column `humidity`: not a number (found `wet`)"
        );
    }

    #[test]
    fn columns_in_any_order_extras_kept_and_round_trip() {
        let d = read_pairs(
            "t2_n,humidity,t1_n,wrap_deg\n3.5,40,1.5,360\n".as_bytes(),
            "y",
        )
        .unwrap();
        assert_eq!(d.extra_columns, ["humidity"]);
        assert_eq!(
            (d.pairs[0].t1_n, d.pairs[0].t2_n, d.pairs[0].extra[0]),
            (1.5, 3.5, 40.0)
        );
        let mut out = Vec::new();
        write_pairs_to(&mut out, &d.pairs).unwrap();
        let back = read_pairs(out.as_slice(), "z").unwrap();
        assert_eq!(back.pairs[0].t1_n, 1.5);
        assert_eq!(back.pairs[0].run, None);
    }
}
