//! Logger Pro's text export: "Vernier Format" blocks, one per data set (a run): the format
//! line, a source and date line, the data set's name, the columns' long names, short names
//! and units (tab-separated), a blank line, then the rows.

use super::columns::Col;
use super::text::{self, Grid, Sep};
use super::{unit_notes, Block, Columns, Layout, Picked, Series};
use crate::error::{Error, Place};
use std::path::Path;

/// Logger Pro's text export: one "Vernier Format" block per data set (run).
pub(super) fn read(
    path: &Path,
    lines: &[&str],
    want: &Columns,
) -> Result<(Vec<Series>, Layout), Error> {
    let starts: Vec<usize> = (0..lines.len())
        .filter(|&i| lines[i].starts_with("Vernier Format"))
        .collect();
    let mut all = Vec::new();
    let mut layout = None;
    for (k, &s) in starts.iter().enumerate() {
        let end = starts.get(k + 1).copied().unwrap_or(lines.len());
        if end < s + 7 {
            return Err(Error::Shape {
                place: Place::cell(path, s as u64 + 1, 1),
                why: "a Logger Pro block needs 6 header lines (format, source, data set, names, \
                      short names, units) and a blank line"
                    .into(),
            });
        }
        let sep = Sep::Char('\t');
        let names = text::cells(lines[s + 3], sep);
        let units = text::cells(lines[s + 5], sep);
        let cols: Vec<Col> = names
            .iter()
            .enumerate()
            .map(|(i, n)| Col::parse(n, units.get(i).map(|u| &**u)))
            .collect();
        let comma = lines[s + 7..end].iter().any(|l| {
            text::cells(l, sep)
                .iter()
                .any(|c| c.contains(',') && text::number(c, true).is_some())
        });
        let g = Grid {
            sep,
            comma,
            header: Some(s + 3),
            units: Some(s + 5),
            first_row: s + 7,
            width: cols.len(),
        };
        let block = Block {
            label: None,
            idx: (0..cols.len()).collect(),
        };
        let p = Picked::of(&cols, &block, want, true)?;
        let mut series = super::rows::rows(path, (&lines[..end], &g), &cols, &p)?;
        if series.is_empty() {
            return Err(Error::Shape {
                place: Place::line(path, s as u64 + 1),
                why: "a Logger Pro block without rows".into(),
            });
        }
        let name = lines[s + 2].trim().to_string();
        for x in series.iter_mut() {
            x.label = Some(match &x.label {
                Some(run) => format!("{name}, run {run}"),
                None => name.clone(),
            });
        }
        all.extend(series);
        layout.get_or_insert_with(|| Layout {
            format: "logger-pro".into(),
            separator: "tab".into(),
            decimal_comma: comma,
            header_line: Some(s + 4),
            used: p.used(&cols),
            notes: unit_notes(&cols, &p),
            ..Layout::default()
        });
    }
    Ok((all, layout.expect("a block")))
}
