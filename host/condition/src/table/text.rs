//! A logger's export as lines of cells: line endings (LF, CRLF, CR-only), a byte-order mark,
//! the separator (tab, `;`, `,` or blanks) and the decimal mark (a point, or a comma as
//! European spreadsheets write it), and where the rows of numbers start — after a block of
//! metadata (a DAQ's `Logger,ACME …` lines, LabVIEW's `***End_of_Header***`), found, or given
//! by `--skip-rows` / `--header-row`.

use crate::error::{option, Error, Place};
use std::borrow::Cow;
use std::path::Path;

/// How the cells of a line are separated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sep {
    /// A character (tab, `;`, `,`), with `"…"` quoting.
    Char(char),
    /// Runs of blanks.
    Blanks,
}

impl Sep {
    /// In words, for `condition.json` and the terminal.
    pub fn name(self) -> &'static str {
        match self {
            Sep::Char('\t') => "tab",
            Sep::Char(';') => "semicolon",
            Sep::Char(',') => "comma",
            Sep::Char(_) => "other",
            Sep::Blanks => "blanks",
        }
    }
}

/// The text's lines (1-based numbers are the index + 1), a byte-order mark dropped, each
/// line's ending removed: LF, CRLF, or CR alone where the file uses no LF.
pub fn lines(text: &str) -> Vec<&str> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    if !text.contains('\n') && text.contains('\r') {
        return text.split('\r').collect();
    }
    let mut v: Vec<&str> = text
        .split('\n')
        .map(|l| l.strip_suffix('\r').unwrap_or(l))
        .collect();
    if v.last() == Some(&"") {
        v.pop();
    }
    v
}

/// The cells of `line`: split at `sep` outside quotes, each trimmed and unquoted (borrowed
/// from the line when it has no quote: a million-row export is read without a string a cell).
pub fn cells(line: &str, sep: Sep) -> Vec<Cow<'_, str>> {
    match sep {
        Sep::Blanks => line.split_whitespace().map(Cow::Borrowed).collect(),
        Sep::Char(d) if !line.contains('"') => {
            line.split(d).map(|c| Cow::Borrowed(c.trim())).collect()
        }
        Sep::Char(d) => {
            let (mut out, mut cur, mut quoted) = (Vec::new(), String::new(), false);
            let mut chars = line.chars().peekable();
            while let Some(c) = chars.next() {
                match c {
                    '"' if quoted && chars.peek() == Some(&'"') => {
                        cur.push('"');
                        chars.next();
                    }
                    '"' => quoted = !quoted,
                    c if c == d && !quoted => {
                        out.push(Cow::Owned(std::mem::take(&mut cur).trim().to_string()))
                    }
                    c => cur.push(c),
                }
            }
            out.push(Cow::Owned(cur.trim().to_string()));
            out
        }
    }
}

/// A number as a logger writes it, with a decimal point or (`comma`) a decimal comma.
pub fn number(cell: &str, comma: bool) -> Option<f64> {
    let v = if comma && cell.contains(',') {
        if cell.contains('.') {
            return None;
        }
        cell.replacen(',', ".", 1).parse::<f64>().ok()?
    } else {
        cell.parse::<f64>().ok()?
    };
    v.is_finite().then_some(v)
}

/// A row of numbers: at least two, and every cell a number or empty (a run that ended
/// earlier, side by side with a longer one).
fn numeric(cells: &[Cow<str>], comma: bool) -> bool {
    cells.iter().filter(|c| !c.is_empty()).count() >= 2
        && cells
            .iter()
            .all(|c| c.is_empty() || number(c, comma).is_some())
}

/// Where the numbers are and how to read them.
#[derive(Clone, Debug)]
pub struct Grid {
    /// The separator.
    pub sep: Sep,
    /// Decimal commas.
    pub comma: bool,
    /// Index of the header line (`None`: no header, the columns are numbered).
    pub header: Option<usize>,
    /// Index of a units line under the header (`s,N,N`), if any.
    pub units: Option<usize>,
    /// Index of the first row of numbers.
    pub first_row: usize,
    /// Cells per row.
    pub width: usize,
}

/// Where the header and the rows are: `skip` lines before the header, or the header at line
/// `header_row` (1-based), or found: the first two rows of numbers with as many cells as
/// each other, and the nearest line above them with as many cells (a units line between them
/// allowed). Lines above the header are a metadata block, skipped.
pub fn grid(
    path: &Path,
    lines: &[&str],
    skip: Option<usize>,
    header_row: Option<usize>,
) -> Result<Grid, Error> {
    let from = match (skip, header_row) {
        (Some(n), None) => n,
        (None, Some(h)) if h >= 1 => h - 1,
        (None, Some(_)) => {
            let why = "--header-row 0: lines are numbered from 1";
            return Err(option("--header-row", why.into()));
        }
        (None, None) => 0,
        (Some(_), Some(_)) => {
            let why = "--skip-rows and --header-row: give one of them";
            return Err(option("--skip-rows", why.into()));
        }
    };
    if from >= lines.len() {
        return Err(Error::Shape {
            place: Place::file(path),
            why: format!(
                "the file has {} lines, fewer than --skip-rows/--header-row asks to pass",
                lines.len()
            ),
        });
    }
    let given = skip.is_some() || header_row.is_some();
    let mut best: Option<Grid> = None;
    for sep in [Sep::Char('\t'), Sep::Char(';'), Sep::Char(','), Sep::Blanks] {
        for comma in [false, true] {
            if let Some(g) = try_grid(lines, from, given, sep, comma) {
                if best.as_ref().is_none_or(|b| g.width > b.width) {
                    best = Some(g);
                }
            }
        }
    }
    best.ok_or_else(|| Error::Shape {
        place: Place::file(path),
        why: format!(
            "no rows of numbers found{} (at least two lines with the same number of numeric \
             cells, separated by tabs, `;`, `,` or blanks): is it a logger's export? A time \
             written as a clock (10:00:00.033) is not read: export the time in seconds",
            if given {
                format!(" after line {}", from + 1)
            } else {
                String::new()
            }
        ),
    })
}

/// Lines searched for the header and the first rows of numbers.
const SCAN_LINES: usize = 10_000;

fn try_grid(lines: &[&str], from: usize, given: bool, sep: Sep, comma: bool) -> Option<Grid> {
    let width = |i: usize| cells(lines[i], sep).len();
    // The header and the first rows are near the top: a metadata block of thousands of
    // lines is no logger's.
    let rows: Vec<usize> = (from..lines.len())
        .filter(|&i| !lines[i].trim().is_empty())
        .take(SCAN_LINES)
        .collect();
    let is_numeric = |i: usize| numeric(&cells(lines[i], sep), comma);
    // The first row of numbers followed by another as wide; else the first row of numbers.
    let pair = rows
        .windows(2)
        .position(|w| is_numeric(w[0]) && is_numeric(w[1]) && width(w[0]) == width(w[1]));
    let mut k = pair.or_else(|| rows.iter().position(|&i| is_numeric(i)))?;
    let n = width(rows[k]);
    // A decimal comma must be one: some cell has it.
    if comma
        && !cells(lines[rows[k]], sep)
            .iter()
            .any(|c| c.contains(',') && number(c, false).is_none())
    {
        return None;
    }
    let (header, units) = if given {
        // The header is the first line after the skipped ones, a units line may follow it,
        // and the rows start after them.
        let h = rows.first().copied().filter(|&h| !is_numeric(h));
        let u = h
            .and_then(|_| rows.get(1).copied())
            .filter(|&u| is_units_line(lines[u], sep));
        k = h.map_or(0, |_| 1) + u.map_or(0, |_| 1);
        (h, u)
    } else {
        // Rows above it as wide, with a number in them, are rows too (a bad cell in one is
        // then named, not taken for the header).
        let row_like = |i: usize| {
            width(i) == n
                && cells(lines[i], sep)
                    .iter()
                    .any(|c| number(c, comma).is_some())
        };
        while k > 0 && row_like(rows[k - 1]) {
            k -= 1;
        }
        // The header: the line above, as wide as the rows or a cell more or less (a
        // `Comment` column LabVIEW leaves empty; rows ending in a separator); a units line
        // may sit between them.
        let wide = |i: usize| width(i).abs_diff(n) <= 1;
        let above = k.checked_sub(1).map(|j| rows[j]).filter(|&i| wide(i));
        match above {
            Some(u) if is_units_line(lines[u], sep) => {
                let h = k.checked_sub(2).map(|j| rows[j]).filter(|&i| wide(i));
                (h.or(Some(u)), h.map(|_| u))
            }
            h => (h, None),
        }
    };
    let first_row = *rows.get(k)?;
    Some(Grid {
        sep,
        comma,
        header,
        units,
        first_row,
        width: n,
    })
}

/// A line of units only (`s,N,N`, `(s),(N),(N)`).
fn is_units_line(line: &str, sep: Sep) -> bool {
    let c = cells(line, sep);
    c.iter().filter(|u| !u.is_empty()).count() >= 2
        && c.iter().all(|u| {
            let u = u.trim_matches(|c| c == '(' || c == ')' || c == '[' || c == ']');
            u.is_empty()
                || !matches!(
                    super::columns::Col::parse("x", Some(u)).unit,
                    super::columns::Unit::Other(_)
                )
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn found(text: &str) -> Grid {
        grid(Path::new("x"), &lines(text), None, None).unwrap()
    }

    #[test]
    fn a_metadata_block_is_skipped_and_the_header_found() {
        let daq = "Logger,ACME DAQ-8\nSerial,A1\nRate,30 Hz\nChannels,2\n\n\
                   Time (s),Force 1 (N),Force 2 (N)\n0,0.1,0.2\n0.033,0.1,0.2\n";
        let g = found(daq);
        assert_eq!(
            (g.sep, g.comma, g.header, g.first_row, g.width),
            (Sep::Char(','), false, Some(5), 6, 3)
        );
        // European Excel: BOM, semicolons, decimal commas, CRLF.
        let excel = "\u{feff}Time (s);T1 (kg);T2 (kg)\r\n0;0,044;0,045\r\n0,033;0,044;0,046\r\n";
        let g = found(excel);
        assert_eq!(
            (g.sep, g.comma, g.header, g.first_row),
            (Sep::Char(';'), true, Some(0), 1)
        );
        // A units line under the names.
        let g = found("time\tt1\tt2\ns\tN\tN\n0\t1\t2\n1\t1\t2\n");
        assert_eq!((g.header, g.units, g.first_row), (Some(0), Some(1), 2));
        // No header at all.
        assert_eq!(found("0 1 2\n1 1 2\n").header, None);
    }

    #[test]
    fn quoted_cells_keep_their_commas() {
        assert_eq!(
            cells(
                "\"Run 1: Time (s)\",\"1,5\",\"say \"\"x\"\"\"",
                Sep::Char(',')
            ),
            ["Run 1: Time (s)", "1,5", "say \"x\""]
        );
        assert_eq!(number("1,5", true), Some(1.5));
        assert_eq!(number("1,5", false), None);
        assert_eq!(number("1.5,0", true), None);
    }
}
