//! Conditioned pairs on disk: the CSV schema shared by `simulate`, `log`, `analyze` and
//! `diagnose`, read once into one data set whose structure (every row's cord and run, and how
//! each was found) every command uses alike.
//!
//! Schema: `capstan_diameter_mm,wrap_deg,drive_v,run,step,time_s,t1_n,t2_n`. Reading needs
//! only `wrap_deg,t1_n,t2_n`; the other known columns are optional. Text columns are read as
//! labels under the names of [`read::CORD_LABELS`] (they separate cords), [`read::RUN_LABELS`]
//! (they separate runs: two sessions, or two boots of the board, with the same run numbers)
//! and [`read::NOTE_COLUMNS`]
//! (kept, not used); any further column must be numeric and is kept (by name).
//!
//! * `records`: the CSV records, each cell with its exact line (LF, CRLF, CR, blank lines),
//!   bounded in size;
//! * `read`: the header and the cells against their physical ranges ([`ranges`]);
//! * `structure`: cords and runs, from columns, inferred or assumed ([`Structure`]);
//! * `error`: what can be wrong, with file, line, column, value and what to do;
//! * `write`: the same schema written.
//!
//! Tensions may be zero or negative: a sensor with a zero offset reads a slack or lightly
//! loaded cord below zero, and those readings are what tells the offset. Values no force sensor
//! on a capstan rig produces, wraps over ten turns and the like are refused with their file,
//! line and column; so are data that cannot be capstan pairs ([`check_capstan_data`]).

mod error;
pub mod plausible;
pub mod provenance;
pub mod ranges;
pub mod read;
mod records;
pub mod structure;
mod write;

pub use error::{quote, DataError, QUOTE_CHARS};
pub use provenance::Provenance;
pub use records::MAX_RECORD_BYTES;
pub use structure::{Basis, Structure};
pub use write::{text_cell, write_pairs, write_pairs_to, PairsWriter, WriteError};

use serde::Serialize;
use std::io::Read;
use std::path::{Path, PathBuf};

/// Largest tension magnitude accepted, N ([`ranges::TENSION_N`]).
pub const MAX_TENSION_N: f64 = ranges::TENSION_N.max;
/// Largest wrap accepted, deg ([`ranges::WRAP_DEG`]).
pub const MAX_WRAP_DEG: f64 = ranges::WRAP_DEG.max;
/// Largest capstan diameter accepted, mm ([`ranges::DIAMETER_MM`]).
pub const MAX_DIAMETER_MM: f64 = ranges::DIAMETER_MM.max;
/// The longest line a pairs CSV may have.
pub const MAX_LINE_BYTES: usize = MAX_RECORD_BYTES;

/// The columns a pairs CSV has, for the help of every command that reads one.
pub const COLUMNS_HELP: &str = "\
INPUT: a pairs CSV, one row per level (as capstan log, simulate and condition write it)
  required  wrap_deg (deg), t1_n (N, the servo side), t2_n (N, the fixed side)
  optional  capstan_diameter_mm (mm), drive_v (V): with wrap_deg they tell the cords apart;
            run, step, time_s (s from the trigger to the window's centre): the runs and the
            order within them (without run, a new run where step, or else time_s, restarts)
  labels    cord, material (tell cords apart); session, date, boot (tell runs apart);
            note, comment (kept, not used); any other column must be numeric (kept)
  A raw time series (a logger's or Logger Pro's export, our raw.csv) is not pairs:
  capstan condition RAW --out DIR --wrap-deg DEG makes them.";

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
    /// Text columns, in the order of [`Dataset::label_columns`].
    #[serde(skip)]
    pub labels: Vec<String>,
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

/// What a text column does.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum LabelRole {
    /// Separates cords (`cord`, `material`).
    Cord,
    /// Separates runs (`session`, `date`).
    Run,
    /// Kept, not used (`note`, `comment`).
    Note,
}

/// A text column.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LabelColumn {
    /// Its name in the header.
    pub name: String,
    /// What it does.
    pub role: LabelRole,
}

/// A loaded CSV of pairs, with its structure.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Dataset {
    /// Where it came from (for messages).
    pub source: String,
    /// The header as read.
    pub header: Vec<String>,
    /// Names of the extra numeric columns.
    pub extra_columns: Vec<String>,
    /// The text columns.
    pub label_columns: Vec<LabelColumn>,
    /// The rows, in file order.
    pub pairs: Vec<Pair>,
    /// The file line of each row.
    pub lines: Vec<u64>,
    /// Every row's cord and run, and how they were found.
    pub structure: Structure,
}

impl Dataset {
    /// True if the data set has the column `name`.
    pub fn has_column(&self, name: &str) -> bool {
        self.header.iter().any(|h| h == name)
    }

    /// A data set made in memory from `pairs` (no text columns, no extra columns): the header
    /// is every column of [`PAIRS_HEADER`] that all pairs carry, as [`write_pairs_to`] writes
    /// it; the structure is inferred as for a file (rows numbered as lines 2, 3, ...).
    pub fn from_pairs(source: &str, pairs: Vec<Pair>) -> Result<Dataset, DataError> {
        let header = write::columns_of(&pairs)
            .into_iter()
            .map(|i| PAIRS_HEADER[i].to_string())
            .collect::<Vec<_>>();
        let lines: Vec<u64> = (0..pairs.len() as u64).map(|i| i + 2).collect();
        let structure = Structure::infer(&pairs, &header, &[], &lines, source)?;
        Ok(Dataset {
            source: source.to_string(),
            header,
            extra_columns: Vec::new(),
            label_columns: Vec::new(),
            pairs,
            lines,
            structure,
        })
    }
}

/// Read a pairs CSV from a file.
pub fn load_pairs(path: &Path) -> Result<Dataset, DataError> {
    let name = path.display().to_string();
    let io = |source| DataError::Io {
        path: name.clone(),
        line: None,
        source,
    };
    if path.is_dir() {
        return Err(io(std::io::Error::new(
            std::io::ErrorKind::IsADirectory,
            "is a directory, not a pairs CSV",
        )));
    }
    let file = std::fs::File::open(path).map_err(io)?;
    read_pairs(file, &name)
}

/// Read a pairs CSV from any reader; `source` names it in errors.
pub fn read_pairs(reader: impl Read, source: &str) -> Result<Dataset, DataError> {
    read::read(reader, source)
}

/// Data that cannot be capstan pairs: most rows without both tensions above zero (negated
/// readings), no row with T2 above T1 (no friction), or T2 below T1 in most rows (the columns
/// swapped); a run whose sensor reads reversed; a column in a unit no rig's data are in
/// (tensions in grams, wraps in radians: [`plausible::unit_mistake`]); more than
/// [`plausible::MAX_SUSPECT_SHARE`] of rows that no rig produces ([`plausible`]). A few rows at
/// or below zero, or with T2 below T1, are data (a zero offset, a slack cord). What passes
/// comes back with the suspect rows it holds (at most that share) and the columns that look
/// unusual: the caller warns about them ([`plausible::Plausibility::warnings`]).
pub fn check_capstan_data(ds: &Dataset) -> Result<plausible::Plausibility, DataError> {
    let path = ds.source.clone();
    let rows = ds.pairs.len();
    let positive = ds
        .pairs
        .iter()
        .filter(|p| p.t1_n > 0.0 && p.t2_n > 0.0)
        .count();
    if 2 * positive < rows {
        let first = ds
            .pairs
            .iter()
            .position(|p| !(p.t1_n > 0.0 && p.t2_n > 0.0))
            .unwrap_or(0);
        return Err(DataError::NotPositive {
            path,
            rows,
            positive,
            first_line: ds.lines.get(first).copied().unwrap_or(0),
        });
    }
    if !ds.pairs.iter().any(|p| p.t2_n > p.t1_n) {
        return Err(DataError::NoFriction { path, rows });
    }
    let below = ds.pairs.iter().filter(|p| p.t2_n < p.t1_n).count();
    if 2 * below > rows {
        return Err(DataError::Swapped { path, rows, below });
    }
    reversed_run(ds)?;
    if let Some((line, column, why)) = plausible::unit_mistake(ds) {
        return Err(DataError::UnitMistake {
            path,
            line,
            column,
            why,
        });
    }
    let found = plausible::plausibility(ds);
    let suspect = found.suspect_rows();
    if suspect as f64 > plausible::MAX_SUSPECT_SHARE * rows as f64 {
        let kinds = found
            .suspects
            .iter()
            .map(|s| {
                format!(
                    "{} row(s): {} ({})",
                    s.lines.len(),
                    s.kind.describe(),
                    plausible::lines_text(&s.lines)
                )
            })
            .collect();
        return Err(DataError::SuspectRows {
            path,
            rows,
            suspect,
            kinds,
        });
    }
    Ok(found)
}

/// A reading below minus this, N, in a run whose readings of that channel are all at or below
/// zero is a reversed sensor, not a zero offset (the firmware's `negative_force` check stops a
/// run at −3 N; the catalogue's zero offsets stay within it).
pub const REVERSED_BELOW_N: f64 = 3.0;

/// A tension column's name and its reading in a pair.
type ChannelOf = (&'static str, fn(&Pair) -> f64);

/// The first run whose T1 (or T2) readings are all at or below zero and reach below
/// −[`REVERSED_BELOW_N`]: refused, naming its lowest reading's line and column.
fn reversed_run(ds: &Dataset) -> Result<(), DataError> {
    let st = &ds.structure;
    let channels: [ChannelOf; 2] = [("t1_n", |p| p.t1_n), ("t2_n", |p| p.t2_n)];
    for (name, read) in channels {
        // Per run: any reading above zero, and the lowest reading's row.
        let mut runs: Vec<(bool, Option<usize>)> = vec![(false, None); st.run_cord.len()];
        for (i, p) in ds.pairs.iter().enumerate() {
            let Some(r) = st.run_of_row.get(i).and_then(|&r| runs.get_mut(r)) else {
                continue;
            };
            r.0 |= read(p) > 0.0;
            if r.1.is_none_or(|j| read(p) < read(&ds.pairs[j])) {
                r.1 = Some(i);
            }
        }
        let hit = runs
            .iter()
            .enumerate()
            .find_map(|(run, &(positive, lowest))| {
                lowest
                    .filter(|&i| !positive && read(&ds.pairs[i]) < -REVERSED_BELOW_N)
                    .map(|i| (run, i))
            });
        if let Some((run, i)) = hit {
            let p = &ds.pairs[i];
            let cord = st.cord_label(st.run_cord[run]);
            return Err(DataError::ReversedRun {
                path: ds.source.clone(),
                line: ds.lines.get(i).copied().unwrap_or(0),
                column: ds
                    .header
                    .iter()
                    .position(|h| h == name)
                    .map_or(0, |c| c + 1),
                name,
                value: read(p),
                run: match p.run {
                    Some(n) => format!("cord {cord} run {n}"),
                    None => format!("cord {cord}"),
                },
            });
        }
    }
    Ok(())
}

/// The bundled thesis data (720 pairs), compiled into the binary so no path is needed.
pub const THESIS_CSV: &str = include_str!("../../../data/thesis-conditioned.csv");

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
mod tests;
