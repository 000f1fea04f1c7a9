//! The rows of a block as series: a sample per row, runs gathered by the run column, every
//! cell a number in its unit, each error at its file, line and column.

use super::columns::Col;
use super::text::{self, Grid};
use super::{Picked, Series};
use crate::error::{Error, Place};
use capstan_data::ranges::TENSION_N;
use std::collections::HashMap;
use std::path::Path;

/// The series of the rows (a new one for every value of the run column, which need not be
/// contiguous: a time-sorted file of interleaved runs keeps each run whole); times must rise
/// within a series. Blank lines are skipped; a row where the block's cells are all empty (its
/// run ended before a longer one beside it) gives no sample.
pub(super) fn rows(
    path: &Path,
    (lines, g): (&[&str], &Grid),
    cols: &[Col],
    p: &Picked,
) -> Result<Vec<Series>, Error> {
    let mut runs: Vec<Series> = Vec::new();
    let mut by_label: HashMap<Option<String>, usize> = HashMap::new();
    let mut last = 0;
    let used = p.used(cols);
    let mine: Vec<usize> = [Some(p.time), Some(p.t1), Some(p.t2), p.trigger, p.run]
        .into_iter()
        .flatten()
        .collect();
    for (i, line) in lines.iter().enumerate().skip(g.first_row) {
        if line.trim().is_empty() {
            continue;
        }
        let row = text::cells(line, g.sep);
        let lineno = i as u64 + 1;
        if row.len() > cols.len() && row[cols.len()..].iter().any(|c| !c.is_empty()) {
            return Err(Error::Shape {
                place: Place::line(path, lineno),
                why: format!("{} cells where the header has {}", row.len(), cols.len()),
            });
        }
        if mine
            .iter()
            .all(|&c| row.get(c).is_none_or(|v| v.is_empty()))
        {
            continue;
        }
        let num = |c: usize, scale: f64, tension: bool| {
            cell_value(
                path,
                lineno,
                c,
                &cols[c].text,
                row.get(c).map(|v| &**v),
                (scale, g.comma),
                tension,
            )
        };
        let label = p.run.map(|c| row.get(c).map_or("", |v| &**v));
        // The run of the row before, most often; else looked up (or a new one).
        let k = match runs.get(last) {
            Some(r) if r.label.as_deref() == label => last,
            _ => {
                let next = runs.len();
                let owned = label.map(String::from);
                let k = *by_label.entry(owned.clone()).or_insert(next);
                if k == next {
                    runs.push(Series {
                        label: owned,
                        ..Series::default()
                    });
                }
                k
            }
        };
        last = k;
        let s = &mut runs[k];
        let t = num(p.time, used[0].scale, false)?;
        if let Some(&prev) = s.t_s.last().filter(|&&prev| t <= prev) {
            return Err(Error::Order {
                place: Place::cell(path, lineno, p.time + 1),
                t_s: t,
                before_s: prev,
                before_line: *s.line.last().expect("a row before"),
                run: s.label.clone(),
            });
        }
        let v1 = num(p.t1, used[1].scale, true)?;
        let v2 = num(p.t2, used[2].scale, true)?;
        s.t_s.push(t);
        s.t1_n.push(v1);
        s.t2_n.push(v2);
        if let Some(c) = p.trigger {
            s.trigger.push(num(c, 1.0, false)?);
        }
        s.line.push(lineno);
    }
    Ok(runs)
}

/// One cell as a number times `scale`, a tension checked against the physical range every
/// pairs CSV is read with; an error names file, line and column, and a stray carriage return.
fn cell_value(
    path: &Path,
    line: u64,
    c: usize,
    name: &str,
    cell: Option<&str>,
    (scale, comma): (f64, bool),
    tension: bool,
) -> Result<f64, Error> {
    let cell = cell.unwrap_or("");
    let at = || Place::cell(path, line, c + 1);
    let error = |why: String| Error::Cell {
        place: at(),
        column: name.to_string(),
        why,
    };
    let Some(v) = text::number(cell, comma) else {
        let why = if cell.is_empty() {
            "is empty".to_string()
        } else if cell.contains('\r') {
            format!(
                "`{}` holds a stray carriage return (\\r) inside the line: save the file with one \
                 kind of line ending",
                capstan_data::quote(cell)
            )
        } else {
            format!("`{}` is not a number", capstan_data::quote(cell))
        };
        return Err(error(why));
    };
    let v = v * scale;
    if tension {
        TENSION_N.check(v).map_err(|why| error(why.to_string()))
    } else {
        Ok(v)
    }
}
