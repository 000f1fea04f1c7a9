//! A raw time series as a logger exports it: CSV or tab-separated text, a header naming the
//! columns (units in it honoured), or Logger Pro's text export ("Vernier Format" blocks: long
//! names, short names, units, a blank line, then the rows; one block per run). Every bad cell
//! is an error with its file, line and column.

use anyhow::bail;
use capstan_data::ranges::{Range, TENSION_N};
use std::path::Path;

/// One run's series: time (s) and both tensions (N), with each sample's line in the file.
#[derive(Clone, Debug, Default)]
pub struct Series {
    /// The run's label in the file (a Logger Pro data set, a `run` column value), if any.
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

/// Which columns to use (names as in the header, without units; `None`: detect).
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

/// What was read, and how.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Layout {
    /// `logger-pro` or `csv`/`tsv`.
    pub format: String,
    /// The columns used: (role, header text, scale to s or N).
    pub used: Vec<(String, String, f64)>,
}

/// A column's name and the factor its unit needs (to s for time, to N for force; `None`:
/// a unit that is not a time or a force, e.g. counts).
#[derive(Clone, Debug)]
struct Col {
    text: String,
    base: String,
    time_scale: Option<f64>,
    force_scale: Option<f64>,
    unit_given: bool,
}

fn unit_scales(unit: &str) -> (Option<f64>, Option<f64>) {
    let u = unit.trim().to_ascii_lowercase();
    let time = match u.as_str() {
        "s" | "sec" | "secs" | "second" | "seconds" => Some(1.0),
        "ms" => Some(1e-3),
        "us" | "µs" => Some(1e-6),
        "min" => Some(60.0),
        _ => None,
    };
    let force = match u.as_str() {
        "n" | "newton" | "newtons" => Some(1.0),
        "mn" => Some(1e-3),
        "kn" => Some(1e3),
        "kgf" | "kg" => Some(9.80665),
        "gf" | "g" => Some(9.80665e-3),
        "lbf" | "lb" => Some(4.448_221_615_260_5),
        _ => None,
    };
    (time, force)
}

fn normalise(s: &str) -> String {
    s.chars()
        .filter(|c| c.is_alphanumeric())
        .flat_map(char::to_lowercase)
        .collect()
}

/// A header cell: `Name (unit)`, `Name [unit]`, `name_unit` (t1_n, time_s), or a name with
/// the unit on its own line (Logger Pro).
fn column(text: &str, unit_line: Option<&str>) -> Col {
    let t = text.trim();
    let (name, unit) = if let Some(u) = unit_line.filter(|u| !u.trim().is_empty()) {
        (t.to_string(), Some(u.trim().to_string()))
    } else if let Some(open) = t.rfind(['(', '[']).filter(|_| t.ends_with([')', ']'])) {
        (
            t[..open].trim().to_string(),
            Some(t[open + 1..t.len() - 1].to_string()),
        )
    } else if let Some((n, u)) = t.rsplit_once('_').filter(|(_, u)| {
        let (a, b) = unit_scales(u);
        a.is_some() || b.is_some() || *u == "counts"
    }) {
        (n.to_string(), Some(u.to_string()))
    } else {
        (t.to_string(), None)
    };
    // Logger Pro prefixes a data set's name: "Run 1: Force".
    let name = name
        .rsplit_once(':')
        .map_or(name.clone(), |(_, n)| n.trim().to_string());
    let (time_scale, force_scale) = match &unit {
        Some(u) => unit_scales(u),
        None => (Some(1.0), Some(1.0)),
    };
    Col {
        text: t.to_string(),
        base: normalise(&name),
        time_scale,
        force_scale,
        unit_given: unit.is_some(),
    }
}

const TIME_NAMES: [&str; 4] = ["time", "t", "times", "timestamp"];
const T1_NAMES: [&str; 5] = ["t1", "tension1", "force1", "f1", "force"];
const T2_NAMES: [&str; 4] = ["t2", "tension2", "force2", "f2"];

/// The index of the column `role` uses: the one named, or the one header name that fits.
fn pick(
    cols: &[Col],
    named: &Option<String>,
    names: &[&str],
    role: &str,
    flag: &str,
    ok: impl Fn(&Col) -> bool,
) -> anyhow::Result<usize> {
    let list = || {
        cols.iter()
            .map(|c| format!("`{}`", c.text))
            .collect::<Vec<_>>()
            .join(", ")
    };
    if let Some(n) = named {
        let want = normalise(column(n, None).base.as_str());
        let hits: Vec<usize> = (0..cols.len())
            .filter(|&i| cols[i].base == want || normalise(&cols[i].text) == normalise(n))
            .collect();
        return match hits.as_slice() {
            [i] if ok(&cols[*i]) => Ok(*i),
            [i] => bail!(
                "{flag} {n}: the column `{}` is not in a {role} unit",
                cols[*i].text
            ),
            [] => bail!("{flag} {n}: no such column (the header has {})", list()),
            _ => bail!("{flag} {n}: more than one column has that name"),
        };
    }
    let hits: Vec<usize> = (0..cols.len())
        .filter(|&i| names.contains(&cols[i].base.as_str()) && ok(&cols[i]))
        .collect();
    match hits.as_slice() {
        [i] => Ok(*i),
        [] => bail!(
            "which column is {role}? none is named so: give {flag} NAME (the header has {})",
            list()
        ),
        _ => bail!(
            "which column is {role}? several could be: give {flag} NAME (the header has {})",
            list()
        ),
    }
}

fn delimiter(line: &str) -> char {
    if line.contains('\t') {
        '\t'
    } else if line.contains(',') {
        ','
    } else if line.contains(';') {
        ';'
    } else {
        '\t'
    }
}

fn cells(line: &str, d: char) -> Vec<&str> {
    line.split(d)
        .map(|c| c.trim().trim_matches('"').trim())
        .collect()
}

/// Read `text` (the file `path`) into one series per run.
pub fn read(path: &Path, text: &str, want: &Columns) -> anyhow::Result<(Vec<Series>, Layout)> {
    let lines: Vec<&str> = text.lines().collect();
    if lines.first().is_some_and(|l| {
        l.trim_start_matches('\u{feff}')
            .starts_with("Vernier Format")
    }) {
        return logger_pro(path, &lines, want);
    }
    let first = lines
        .iter()
        .position(|l| !l.trim().is_empty())
        .ok_or_else(|| anyhow::anyhow!("{}: the file is empty", path.display()))?;
    let d = delimiter(lines[first]);
    let cols: Vec<Col> = cells(lines[first], d)
        .iter()
        .map(|c| column(c, None))
        .collect();
    let format = if d == '\t' { "tsv" } else { "csv" };
    block(path, &lines, first + 1, d, cols, want, format)
}

/// Logger Pro's text export: one "Vernier Format" block per data set (run).
fn logger_pro(
    path: &Path,
    lines: &[&str],
    want: &Columns,
) -> anyhow::Result<(Vec<Series>, Layout)> {
    let starts: Vec<usize> = (0..lines.len())
        .filter(|&i| {
            lines[i]
                .trim_start_matches('\u{feff}')
                .starts_with("Vernier Format")
        })
        .collect();
    let mut all = Vec::new();
    let mut layout = None;
    for (k, &s) in starts.iter().enumerate() {
        let end = starts.get(k + 1).copied().unwrap_or(lines.len());
        if end < s + 7 {
            bail!(
                "{}:{}:1: a Logger Pro block needs 6 header lines (format, source, data set, \
                 names, short names, units) and a blank line",
                path.display(),
                s + 1
            );
        }
        let d = '\t';
        let names = cells(lines[s + 3], d);
        let units = cells(lines[s + 5], d);
        let cols: Vec<Col> = names
            .iter()
            .enumerate()
            .map(|(i, n)| column(n, units.get(i).copied()))
            .collect();
        let (mut series, l) = block(path, &lines[..end], s + 7, d, cols, want, "logger-pro")?;
        for x in series.iter_mut() {
            x.label = Some(lines[s + 2].trim().to_string());
        }
        all.extend(series);
        layout = Some(l);
    }
    Ok((all, layout.expect("a block")))
}

/// The rows from line index `from` on, with the header `cols`.
fn block(
    path: &Path,
    lines: &[&str],
    from: usize,
    d: char,
    cols: Vec<Col>,
    want: &Columns,
    format: &str,
) -> anyhow::Result<(Vec<Series>, Layout)> {
    let picked = Picked::of(&cols, want)?;
    let used = picked.used(&cols);
    let runs = rows(path, (lines, from, d), &cols, &picked, &used)?;
    if runs.is_empty() {
        bail!("{}: no rows after the header", path.display());
    }
    Ok((
        runs,
        Layout {
            format: format.to_string(),
            used,
        },
    ))
}

/// The columns a block is read from (indices into its header).
struct Picked {
    time: usize,
    t1: usize,
    t2: usize,
    trigger: Option<usize>,
    run: Option<usize>,
}

impl Picked {
    /// The columns named by the options, or found by their names and units.
    fn of(cols: &[Col], want: &Columns) -> anyhow::Result<Picked> {
        let time = pick(
            cols,
            &want.time,
            &TIME_NAMES,
            "time",
            "--time-column",
            |c| c.time_scale.is_some(),
        )?;
        let force = |c: &Col| c.force_scale.is_some();
        let t1 = pick(cols, &want.t1, &T1_NAMES, "T1", "--t1-column", force)?;
        let t2 = pick(cols, &want.t2, &T2_NAMES, "T2", "--t2-column", force)?;
        let trigger = match &want.trigger {
            Some(_) => Some(pick(
                cols,
                &want.trigger,
                &[],
                "the trigger",
                "--trigger-column",
                |_| true,
            )?),
            None => None,
        };
        let run = match &want.run {
            Some(_) => Some(pick(
                cols,
                &want.run,
                &[],
                "the run",
                "--run-column",
                |_| true,
            )?),
            None => cols.iter().position(|c| c.base == "run" && !c.unit_given),
        };
        Ok(Picked {
            time,
            t1,
            t2,
            trigger,
            run,
        })
    }

    /// (role, header text, scale to s or N) of each column used, time, T1, T2 first.
    fn used(&self, cols: &[Col]) -> Vec<(String, String, f64)> {
        let (time, t1, t2) = (self.time, self.t1, self.t2);
        let mut used = vec![
            (
                "time".to_string(),
                cols[time].text.clone(),
                cols[time].time_scale.unwrap_or(1.0),
            ),
            (
                "t1".to_string(),
                cols[t1].text.clone(),
                cols[t1].force_scale.unwrap_or(1.0),
            ),
            (
                "t2".to_string(),
                cols[t2].text.clone(),
                cols[t2].force_scale.unwrap_or(1.0),
            ),
        ];
        if let Some(i) = self.trigger {
            used.push(("trigger".into(), cols[i].text.clone(), 1.0));
        }
        if let Some(i) = self.run {
            used.push(("run".into(), cols[i].text.clone(), 1.0));
        }
        used
    }
}

/// The series of the lines from `from` on (delimiter `d`), a new one whenever the run column
/// changes; times must rise within a series. Blank lines are skipped.
fn rows(
    path: &Path,
    (lines, from, d): (&[&str], usize, char),
    cols: &[Col],
    p: &Picked,
    used: &[(String, String, f64)],
) -> anyhow::Result<Vec<Series>> {
    let mut runs: Vec<Series> = Vec::new();
    for (i, line) in lines.iter().enumerate().skip(from) {
        if line.trim().is_empty() {
            continue;
        }
        let row = cells(line, d);
        let lineno = i as u64 + 1;
        let num = |c: usize, scale: f64, range: Option<&Range>| {
            cell_value(
                path,
                lineno,
                c,
                &cols[c].text,
                row.get(c).copied(),
                scale,
                range,
            )
        };
        let label = p.run.map(|c| row.get(c).copied().unwrap_or("").to_string());
        if runs.last().is_none_or(|r| r.label != label) {
            runs.push(Series {
                label: label.clone(),
                ..Series::default()
            });
        }
        let s = runs.last_mut().expect("pushed");
        let t = num(p.time, used[0].2, None)?;
        if s.t_s.last().is_some_and(|&prev| t <= prev) {
            bail!(
                "{}:{lineno}:{}: time {t} s does not follow the row before ({} s): rows must be in \
                 time order",
                path.display(),
                p.time + 1,
                s.t_s.last().expect("checked")
            );
        }
        let v1 = num(p.t1, used[1].2, Some(&TENSION_N))?;
        let v2 = num(p.t2, used[2].2, Some(&TENSION_N))?;
        s.t_s.push(t);
        s.t1_n.push(v1);
        s.t2_n.push(v2);
        if let Some(c) = p.trigger {
            s.trigger.push(num(c, 1.0, None)?);
        }
        s.line.push(lineno);
    }
    Ok(runs)
}

/// One cell as a number in the column's unit times `scale`, checked against `range` (the
/// physical ranges every pairs CSV is read with); an error names file, line and column.
fn cell_value(
    path: &Path,
    line: u64,
    c: usize,
    name: &str,
    cell: Option<&str>,
    scale: f64,
    range: Option<&Range>,
) -> anyhow::Result<f64> {
    let cell = cell.unwrap_or("");
    let at = format!("{}:{line}:{}", path.display(), c + 1);
    let v = cell
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| anyhow::anyhow!("{at}: `{cell}` in column `{name}` is not a number"))?
        * scale;
    match range {
        Some(r) => r
            .check(v)
            .map_err(|why| anyhow::anyhow!("{at}: column `{name}`: {why}")),
        None => Ok(v),
    }
}
