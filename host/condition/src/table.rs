//! A raw time series as labs export it: a logger's CSV or tab-separated text (a metadata block
//! above the header found or skipped, decimal commas and semicolons, a byte-order mark, any
//! line ending), Logger Pro's "Export as CSV" with runs side by side (`Run 1: Time (s)`, `Run
//! 2: Time (s)`, …: each block its own run), or Logger Pro's text export ("Vernier Format"
//! blocks: long names, short names, units, a blank line, the rows; one block per run). Units
//! in the header are converted (s, ms, min; N, mN, kN, g, kg, lbf, …) or refused by name
//! (volts, counts). Every bad cell is an error with its file, line and column.
//!
//! * `text`: lines, separator, decimal mark, where the header and the rows are;
//! * `columns`: a header cell's run, name and unit, and which column plays which role.

mod columns;
mod logger_pro;
mod rows;
mod text;

use crate::error::{Error, Place};
use columns::{Ask, Col, Role, Unit};
use std::path::Path;
use text::{Grid, Sep};

/// One run's series: time (s) and both tensions (N), with each sample's line in the file.
#[derive(Clone, Debug, Default)]
pub struct Series {
    /// The run's label in the file (a Logger Pro data set, a `Run N:` block, a `run` column
    /// value), if any.
    pub label: Option<String>,
    /// Seconds.
    pub t_s: Vec<f64>,
    /// T1, N.
    pub t1_n: Vec<f64>,
    /// T2, N.
    pub t2_n: Vec<f64>,
    /// The trigger column, if one was named.
    pub trigger: Vec<f64>,
    /// The line of each sample.
    pub line: Vec<u64>,
}

/// Which columns to use (`None`: found by name): a name as in the header (with or without its
/// unit; with `Run N:` for one run's column), or a 1-based column number.
#[derive(Clone, Debug, Default)]
pub struct Columns {
    /// Time.
    pub time: Option<String>,
    /// T1.
    pub t1: Option<String>,
    /// T2.
    pub t2: Option<String>,
    /// The logger trigger.
    pub trigger: Option<String>,
    /// The run number.
    pub run: Option<String>,
}

/// How to read the file.
#[derive(Clone, Debug, Default)]
pub struct ReadOptions {
    /// The columns.
    pub columns: Columns,
    /// Lines to pass before the header.
    pub skip_rows: Option<usize>,
    /// The header's line (1-based).
    pub header_row: Option<usize>,
}

/// One column used: its role, header text, number (1-based) and the factor to s or N.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Used {
    /// `time`, `t1`, `t2`, `trigger`, `run`.
    pub role: String,
    /// As in the header.
    pub header: String,
    /// 1-based.
    pub column: usize,
    /// To s (time) or N (forces).
    pub scale: f64,
    /// How the unit was read, in words.
    pub unit: String,
}

/// What was read, and how.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct Layout {
    /// `logger-pro`, `csv`, `tsv`, `ssv` (semicolons) or `text` (blanks).
    pub format: String,
    /// The separator, in words.
    pub separator: String,
    /// Decimal commas.
    pub decimal_comma: bool,
    /// Lines passed above the header (a metadata block), 1-based, inclusive.
    pub skipped_lines: Option<(usize, usize)>,
    /// The header's line (1-based), if there is one.
    pub header_line: Option<usize>,
    /// The run blocks side by side (`Run 1`, `Run 2`), if any.
    pub run_blocks: Vec<String>,
    /// The columns used (the first block's, when there are several).
    pub used: Vec<Used>,
    /// What a user should know (a unit assumed, a mass read as its weight, blocks left out).
    pub notes: Vec<String>,
}

/// Read `text` (the file `path`) into one series per run.
pub fn read(path: &Path, text: &str, opts: &ReadOptions) -> Result<(Vec<Series>, Layout), Error> {
    let lines = text::lines(text);
    let first = lines.iter().position(|l| !l.trim().is_empty());
    let Some(first) = first else {
        return Err(Error::Shape {
            place: Place::file(path),
            why: "the file is empty".into(),
        });
    };
    if lines[first].starts_with("Vernier Format") {
        return logger_pro::read(path, &lines, &opts.columns);
    }
    let g = text::grid(path, &lines, opts.skip_rows, opts.header_row)?;
    let mut cols = header(&lines, &g);
    // Rows ending in a separator: the header has a cell fewer.
    while cols.len() < g.width {
        cols.push(Col::parse(&format!("column {}", cols.len() + 1), None));
    }
    let mut layout = Layout {
        format: match g.sep {
            Sep::Char('\t') => "tsv",
            Sep::Char(';') => "ssv",
            Sep::Char(_) => "csv",
            Sep::Blanks => "text",
        }
        .to_string(),
        separator: g.sep.name().to_string(),
        decimal_comma: g.comma,
        header_line: g.header.map(|h| h + 1),
        skipped_lines: g
            .header
            .or(Some(g.first_row))
            .filter(|&h| h > first)
            .map(|h| (first + 1, h)),
        ..Layout::default()
    };
    let blocks = blocks(&cols, &opts.columns, &mut layout)?;
    let picks = blocks
        .iter()
        .map(|b| Picked::of(&cols, b, &opts.columns, g.header.is_some()))
        .collect::<Result<Vec<_>, _>>()?;
    layout.used = picks[0].used(&cols);
    layout.notes.extend(unit_notes(&cols, &picks[0]));
    let mut all = Vec::new();
    for (b, p) in blocks.iter().zip(&picks) {
        let mut runs = rows::rows(path, (&lines, &g), &cols, p)?;
        if runs.is_empty() {
            return Err(Error::Shape {
                place: Place::file(path),
                why: format!(
                    "no rows{} after the header",
                    b.label
                        .as_deref()
                        .map_or(String::new(), |l| format!(" of {l}"))
                ),
            });
        }
        for r in runs.iter_mut() {
            r.label = match (&b.label, &r.label) {
                (Some(block), Some(run)) => Some(format!("{block}, run {run}")),
                (Some(block), None) => Some(block.clone()),
                (None, run) => run.clone(),
            };
        }
        all.extend(runs);
    }
    Ok((all, layout))
}

/// The header's cells (with the units line's units, if any), or `column N` without one.
fn header(lines: &[&str], g: &Grid) -> Vec<Col> {
    let Some(h) = g.header else {
        return (1..=g.width)
            .map(|i| Col::parse(&format!("column {i}"), None))
            .collect();
    };
    let names = text::cells(lines[h], g.sep);
    let units = g.units.map(|u| text::cells(lines[u], g.sep));
    names
        .iter()
        .enumerate()
        .map(|(i, n)| {
            let unit = units.as_ref().and_then(|u| u.get(i)).map(|u| {
                u.trim_matches(|c| c == '(' || c == ')' || c == '[' || c == ']')
                    .to_string()
            });
            Col::parse(n, unit.as_deref())
        })
        .collect()
}

/// One run block: the columns of one `Run N:` prefix (or all of them).
pub(super) struct Block {
    pub(super) label: Option<String>,
    pub(super) idx: Vec<usize>,
}

/// The run blocks of the header: one per `Run N:` prefix, in order, or the whole header.
/// With a column asked for exactly (a number, or `Run 2: Time`), only its block.
fn blocks(cols: &[Col], want: &Columns, layout: &mut Layout) -> Result<Vec<Block>, Error> {
    let mut labels: Vec<String> = Vec::new();
    for c in cols {
        if let Some(r) = c.run.as_ref().filter(|r| !labels.contains(r)) {
            labels.push(r.clone());
        }
    }
    let mut out: Vec<Block> = if labels.is_empty() {
        vec![Block {
            label: None,
            idx: (0..cols.len()).collect(),
        }]
    } else {
        labels
            .iter()
            .map(|l| Block {
                label: Some(l.clone()),
                idx: (0..cols.len())
                    .filter(|&i| cols[i].run.as_ref() == Some(l))
                    .collect(),
            })
            .collect()
    };
    layout.run_blocks = labels.clone();
    let exact: Vec<(String, usize)> = [
        ("--time-column", &want.time),
        ("--t1-column", &want.t1),
        ("--t2-column", &want.t2),
    ]
    .into_iter()
    .filter_map(|(flag, g)| match Ask::of(g.as_deref(), cols, flag) {
        Ok(Ask::Exact(i)) => Some(Ok((flag.to_string(), i))),
        Ok(_) => None,
        Err(e) => Some(Err(e)),
    })
    .collect::<Result<_, Error>>()?;
    if let Some((flag, i)) = exact.first() {
        let home = |i: usize| out.iter().position(|b| b.idx.contains(&i));
        if let Some((other, j)) = exact.iter().find(|(_, j)| home(*j) != home(*i)) {
            column_error!(
                "{flag} and {other} name columns of different runs (`{}` and `{}`): one run's \
                 columns, or names without the run to convert every run",
                cols[*i].text,
                cols[*j].text
            );
        }
        if out.len() > 1 {
            let keep = home(*i).expect("every column is in a block");
            let b = out.swap_remove(keep);
            layout.notes.push(format!(
                "only {} converted ({flag} names one of its columns); the file has {}",
                b.label.as_deref().unwrap_or("one run"),
                labels.join(", ")
            ));
            out = vec![b];
        }
    }
    Ok(out)
}

/// The columns a block is read from (indices into the header).
pub(super) struct Picked {
    pub(super) time: usize,
    pub(super) t1: usize,
    pub(super) t2: usize,
    pub(super) trigger: Option<usize>,
    pub(super) run: Option<usize>,
}

const TIME: Role = Role {
    name: "time",
    flag: "--time-column",
    names: &columns::TIME_NAMES,
    refuse: Unit::not_a_time,
};
const T1: Role = Role {
    name: "T1",
    flag: "--t1-column",
    names: &columns::T1_NAMES,
    refuse: Unit::not_a_force,
};
const T2: Role = Role {
    name: "T2",
    flag: "--t2-column",
    names: &columns::T2_NAMES,
    refuse: Unit::not_a_force,
};

fn any_unit(_: &Unit) -> Option<String> {
    None
}

impl Picked {
    /// The block's columns, as the options say or found by their names and units.
    pub(super) fn of(
        cols: &[Col],
        b: &Block,
        want: &Columns,
        has_header: bool,
    ) -> Result<Picked, Error> {
        let ask = |g: &Option<String>, flag: &str| Ask::of(g.as_deref(), cols, flag);
        let pick = |g: &Option<String>, role: &Role| -> Result<usize, Error> {
            let a = ask(g, role.flag)?;
            if a == Ask::Auto && !has_header {
                column_error!(
                    "the file has no header line: give the columns by number ({} N; columns 1 \
                     to {}), or the header's line (--header-row N)",
                    role.flag,
                    cols.len()
                );
            }
            columns::pick(cols, &b.idx, &a, role)
        };
        let time = pick(&want.time, &TIME)?;
        let t1 = pick(&want.t1, &T1)?;
        let t2 = pick(&want.t2, &T2)?;
        if t1 == t2 {
            column_error!(
                "T1 and T2 would both be column {} `{}`: give --t1-column and --t2-column",
                t1 + 1,
                cols[t1].text
            );
        }
        let other = |g: &Option<String>, name, flag| -> Result<Option<usize>, Error> {
            if g.is_none() {
                return Ok(None);
            }
            let role = Role {
                name,
                flag,
                names: &[],
                refuse: any_unit,
            };
            columns::pick(cols, &b.idx, &ask(g, flag)?, &role).map(Some)
        };
        let trigger = other(&want.trigger, "the trigger", "--trigger-column")?;
        let run = match other(&want.run, "the run", "--run-column")? {
            Some(r) => Some(r),
            None => b
                .idx
                .iter()
                .copied()
                .find(|&i| cols[i].base == "run" && cols[i].unit == Unit::None),
        };
        Ok(Picked {
            time,
            t1,
            t2,
            trigger,
            run,
        })
    }

    pub(super) fn used(&self, cols: &[Col]) -> Vec<Used> {
        let one = |role: &str, i: usize, scale: f64| Used {
            role: role.to_string(),
            header: cols[i].text.clone(),
            column: i + 1,
            scale,
            unit: unit_words(&cols[i].unit, role),
        };
        let mut v = vec![
            one(
                "time",
                self.time,
                cols[self.time].unit.to_s().unwrap_or(1.0),
            ),
            one("t1", self.t1, cols[self.t1].unit.to_n().unwrap_or(1.0)),
            one("t2", self.t2, cols[self.t2].unit.to_n().unwrap_or(1.0)),
        ];
        if let Some(i) = self.trigger {
            v.push(one("trigger", i, 1.0));
        }
        if let Some(i) = self.run {
            v.push(one("run", i, 1.0));
        }
        v
    }
}

fn unit_words(u: &Unit, role: &str) -> String {
    match (u, role) {
        (Unit::None, "time") => "none given: read as s".into(),
        (Unit::None, "t1" | "t2") => "none given: read as N".into(),
        (Unit::None, _) => "none".into(),
        (Unit::Time(k), _) => format!("time, ×{k} to s"),
        (Unit::Force(k), _) => format!("force, ×{k} to N"),
        (Unit::Mass(k), _) => format!("mass read as its weight, ×{k} to N"),
        (Unit::Voltage, _) => "volts".into(),
        (Unit::Counts, _) => "counts".into(),
        (Unit::Other(o), _) => o.clone(),
    }
}

/// What a user should know about the units: a force or time without one, a mass read as its
/// weight.
pub(super) fn unit_notes(cols: &[Col], p: &Picked) -> Vec<String> {
    let mut out = Vec::new();
    for (role, i) in [("time", p.time), ("T1", p.t1), ("T2", p.t2)] {
        let c = &cols[i];
        match &c.unit {
            Unit::None => out.push(format!(
                "{role} column `{}` has no unit in its header: read as {}",
                c.text,
                if role == "time" { "seconds" } else { "newtons" }
            )),
            Unit::Mass(k) => out.push(format!(
                "{role} column `{}` is a mass: read as its weight (×{k} N)",
                c.text
            )),
            _ => {}
        }
    }
    out
}
