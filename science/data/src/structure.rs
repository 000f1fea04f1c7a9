//! How a data set's rows map to cords and runs: the one structure every command uses, and how
//! each level was found — from columns, inferred, or assumed — which the commands say.
//!
//! * **Cords**: one per (capstan diameter, wrap, drive voltage) and the values of the cord
//!   label columns (`cord`, `material`). Without a `capstan_diameter_mm` column (or a cord
//!   label) the cords are *assumed*: rows at one wrap and voltage are one cord, so cords of
//!   different diameters at the same wrap would be merged.
//! * **Runs**: from the `run` column (and the session labels `session`, `date`, which keep
//!   two sessions' runs apart); without it *inferred* where `step` (or else `time_s`) does not
//!   rise from one row of a cord to its next in file order; without any of them *assumed*:
//!   each cord is one run.
//!
//! Two rows with the same run and step (or time) are refused with both lines: two sessions
//! concatenated with the same run numbers would otherwise merge without a word.

use super::error::DataError;
use super::{LabelColumn, LabelRole, Pair};
use capstan_physics::{REF_DIAMETER_MM, REF_DRIVE_V};
use serde::Serialize;
use std::collections::HashMap;

/// Where a level of the structure comes from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Basis {
    /// Columns of the file say it.
    Columns,
    /// Inferred from other columns (steps or times restarting).
    Inferred,
    /// Nothing says it: a default was taken.
    #[default]
    Assumed,
}

/// One level (cords or runs): how many, where from, by which columns, how.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Level {
    /// How many.
    pub count: usize,
    /// Where the mapping comes from.
    pub from: Basis,
    /// The columns it was read or inferred from.
    pub columns: Vec<String>,
    /// How, in words.
    pub how: String,
}

/// A cord: capstan diameter, drive voltage, wrap (the assumed values where a column is
/// missing) and its cord labels.
#[derive(Clone, Debug, PartialEq)]
pub struct CordKey {
    /// Capstan diameter, mm.
    pub diameter_mm: f64,
    /// Drive voltage, V.
    pub drive_v: f64,
    /// Wrap, deg.
    pub wrap_deg: f64,
    /// Values of the cord label columns.
    pub labels: Vec<String>,
}

/// Every row's cord and run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Structure {
    /// Cord of each row (index into `cords`).
    pub cord_of_row: Vec<usize>,
    /// Run of each row (index into `run_cord`).
    pub run_of_row: Vec<usize>,
    /// The cords, in the order they first appear.
    pub cords: Vec<CordKey>,
    /// The cord of each run; runs in the order they first appear.
    pub run_cord: Vec<usize>,
    /// How the cords were found.
    pub cord_level: Level,
    /// How the runs were found.
    pub run_level: Level,
    /// Values taken for missing columns, in words.
    pub assumed: Vec<String>,
}

/// What `data.structure` says in every JSON output.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct StructureSummary {
    /// Rows.
    pub rows: usize,
    /// The cords.
    pub cords: Level,
    /// The runs.
    pub runs: Level,
    /// Values taken for missing columns.
    pub assumed: Vec<String>,
    /// All of it in one sentence (what the terminal shows).
    pub statement: String,
}

/// How runs are told apart.
#[derive(Clone, Copy, PartialEq)]
enum RunWay {
    Column,
    Restart(usize),
    OnePerCord,
}

type Key<'a> = (usize, u64, Vec<&'a str>);

impl Structure {
    /// The structure of `pairs` (with `header` and text `labels` as read; `lines` the file line
    /// of each row, for errors).
    pub fn infer(
        pairs: &[Pair],
        header: &[String],
        labels: &[LabelColumn],
        lines: &[u64],
        path: &str,
    ) -> Result<Structure, DataError> {
        let has = |c: &str| header.iter().any(|h| h == c);
        let of_role = |r: LabelRole| -> Vec<usize> {
            (0..labels.len()).filter(|&k| labels[k].role == r).collect()
        };
        let (cord_labels, run_labels) = (of_role(LabelRole::Cord), of_role(LabelRole::Run));
        let mut s = Structure::default();
        let mut cord_ids: HashMap<([u64; 3], Vec<&str>), usize> = HashMap::new();
        for p in pairs {
            let dia = p.capstan_diameter_mm.unwrap_or(REF_DIAMETER_MM);
            let drive = p.drive_v.unwrap_or(REF_DRIVE_V);
            let lab: Vec<&str> = cord_labels.iter().map(|&k| p.labels[k].as_str()).collect();
            let key = ([dia, drive, p.wrap_deg].map(f64::to_bits), lab);
            let next = cord_ids.len();
            let c = *cord_ids.entry(key).or_insert_with(|| {
                s.cords.push(CordKey {
                    diameter_mm: dia,
                    drive_v: drive,
                    wrap_deg: p.wrap_deg,
                    labels: cord_labels.iter().map(|&k| p.labels[k].clone()).collect(),
                });
                next
            });
            s.cord_of_row.push(c);
        }
        let way = if has("run") {
            RunWay::Column
        } else if has("step") {
            RunWay::Restart(4)
        } else if has("time_s") {
            RunWay::Restart(5)
        } else {
            RunWay::OnePerCord
        };
        s.assign_runs(pairs, &run_labels, way);
        s.check_duplicates(pairs, has("step"), has("time_s"), lines, path)?;
        s.describe_levels(header, labels, way, &has);
        Ok(s)
    }

    fn assign_runs(&mut self, pairs: &[Pair], run_labels: &[usize], way: RunWay) {
        let mut run_ids: HashMap<Key<'_>, usize> = HashMap::new();
        let mut restart: HashMap<(usize, Vec<&str>), (f64, u64)> = HashMap::new();
        for (i, p) in pairs.iter().enumerate() {
            let c = self.cord_of_row[i];
            let session: Vec<&str> = run_labels.iter().map(|&k| p.labels[k].as_str()).collect();
            let n = match way {
                RunWay::Column => p.run.unwrap_or(1.0).to_bits(),
                RunWay::Restart(col) => {
                    let v = if col == 4 { p.step } else { p.time_s }.unwrap_or(0.0);
                    let e = restart
                        .entry((c, session.clone()))
                        .or_insert((f64::INFINITY, 0));
                    if v <= e.0 {
                        e.1 += 1;
                    }
                    e.0 = v;
                    e.1
                }
                RunWay::OnePerCord => 0,
            };
            let next = run_ids.len();
            let r = *run_ids.entry((c, n, session)).or_insert_with(|| {
                self.run_cord.push(c);
                next
            });
            self.run_of_row.push(r);
        }
    }

    /// Two rows with the same run and step (or, without `step`, time).
    fn check_duplicates(
        &self,
        pairs: &[Pair],
        step: bool,
        time: bool,
        lines: &[u64],
        path: &str,
    ) -> Result<(), DataError> {
        if !(step || time) {
            return Ok(());
        }
        let mut seen: HashMap<(usize, u64), usize> = HashMap::with_capacity(pairs.len());
        for (i, p) in pairs.iter().enumerate() {
            let v = if step { p.step } else { p.time_s }.unwrap_or(0.0);
            if let Some(first) = seen.insert((self.run_of_row[i], v.to_bits()), i) {
                let what = if step { "step" } else { "time_s" };
                let run = p.run.map_or(String::new(), |r| format!(" run {r}"));
                return Err(DataError::DuplicateRow {
                    path: path.to_string(),
                    line: lines.get(i).copied().unwrap_or(0),
                    first_line: lines.get(first).copied().unwrap_or(0),
                    key: format!(
                        "cord {}{run} {what} {v}",
                        self.cord_label(self.cord_of_row[i])
                    ),
                });
            }
        }
        Ok(())
    }

    fn describe_levels(
        &mut self,
        header: &[String],
        labels: &[LabelColumn],
        way: RunWay,
        has: &dyn Fn(&str) -> bool,
    ) {
        self.cord_level = cord_level(header, labels, has, self.cords.len());
        self.run_level = run_level(labels, way, self.run_cord.len());
        self.assumed.clear();
        if !has("capstan_diameter_mm") {
            self.assumed.push(format!(
                "capstan_diameter_mm: {REF_DIAMETER_MM} mm for every row (no column)"
            ));
        }
        if !has("drive_v") {
            self.assumed.push(format!(
                "drive_v: {REF_DRIVE_V} V for every row (no column)"
            ));
        }
    }

    /// A cord's label: `D12.7/270deg`, with the voltage when the data have several, and its
    /// cord labels.
    pub fn cord_label(&self, c: usize) -> String {
        let k = &self.cords[c];
        let mut s = format!("D{}/{}deg", k.diameter_mm, k.wrap_deg);
        if self.cords.iter().any(|x| x.drive_v != k.drive_v) {
            s += &format!("/{}V", k.drive_v);
        }
        for l in &k.labels {
            s += "/";
            s += l;
        }
        s
    }

    /// The JSON summary (`data.structure`).
    pub fn summary(&self) -> StructureSummary {
        StructureSummary {
            rows: self.cord_of_row.len(),
            cords: self.cord_level.clone(),
            runs: self.run_level.clone(),
            assumed: self.assumed.clone(),
            statement: self.describe(),
        }
    }

    /// One line for the terminal: how many cords and runs, and how each was found.
    pub fn describe(&self) -> String {
        let level = |l: &Level, one: &str| {
            let what = if l.count == 1 {
                one.to_string()
            } else {
                format!("{one}s")
            };
            match l.from {
                Basis::Columns => {
                    format!("{} {what} from columns ({})", l.count, l.columns.join(", "))
                }
                Basis::Inferred => format!("{} {what} INFERRED: {}", l.count, l.how),
                Basis::Assumed => format!("{} {what} ASSUMED: {}", l.count, l.how),
            }
        };
        let mut s = format!(
            "structure: {}; {}",
            level(&self.cord_level, "cord"),
            level(&self.run_level, "run")
        );
        if !self.assumed.is_empty() {
            s += &format!("; assumed {}", self.assumed.join(", "));
        }
        s
    }

    /// Is every level read from columns?
    pub fn all_from_columns(&self) -> bool {
        self.cord_level.from == Basis::Columns && self.run_level.from == Basis::Columns
    }
}

/// The label columns of `role`, by name.
fn named(labels: &[LabelColumn], role: LabelRole) -> Vec<String> {
    labels
        .iter()
        .filter(|l| l.role == role)
        .map(|l| l.name.clone())
        .collect()
}

/// How the `count` cords were found: from the cord columns present, or assumed one per wrap
/// (and drive voltage).
fn cord_level(
    header: &[String],
    labels: &[LabelColumn],
    has: &dyn Fn(&str) -> bool,
    count: usize,
) -> Level {
    let mut cord_cols: Vec<String> = ["capstan_diameter_mm", "wrap_deg", "drive_v"]
        .into_iter()
        .filter(|c| header.iter().any(|h| h == c))
        .map(String::from)
        .collect();
    cord_cols.extend(named(labels, LabelRole::Cord));
    let cords_known = has("capstan_diameter_mm") || !named(labels, LabelRole::Cord).is_empty();
    Level {
        count,
        from: if cords_known {
            Basis::Columns
        } else {
            Basis::Assumed
        },
        how: if cords_known {
            format!("one cord per distinct ({})", cord_cols.join(", "))
        } else {
            "no capstan_diameter_mm or cord column: the rows at one wrap (and drive \
             voltage) are taken as one cord, so cords of different diameters would merge"
                .into()
        },
        columns: cord_cols,
    }
}

/// How the `count` runs were found (`way`), with any session label columns.
fn run_level(labels: &[LabelColumn], way: RunWay, count: usize) -> Level {
    let sessions = named(labels, LabelRole::Run);
    let (from, mut columns, how) = match way {
        RunWay::Column => (
            Basis::Columns,
            vec!["run".to_string()],
            "from the run column",
        ),
        RunWay::Restart(4) => (
            Basis::Inferred,
            vec!["step".to_string()],
            "no run column: a new run wherever step does not rise from one row of a cord \
             to its next (file order)",
        ),
        RunWay::Restart(_) => (
            Basis::Inferred,
            vec!["time_s".to_string()],
            "no run column: a new run wherever time_s does not rise from one row of a cord \
             to its next (file order)",
        ),
        RunWay::OnePerCord => (
            Basis::Assumed,
            Vec::new(),
            "no run, step or time_s column: each cord is taken as one run, so what needs \
             runs (wear, replicate runs' pure error) is not testable",
        ),
    };
    columns.extend(sessions);
    Level {
        count,
        from,
        columns,
        how: how.to_string(),
    }
}
