//! CSV records from a byte stream, each cell with the exact line it starts on.
//!
//! Lines end in LF, CRLF or a lone CR (a file saved by an old Mac spreadsheet); every one is
//! counted, blank lines included, so an error names the line an editor shows. Cells are
//! separated by commas and may be quoted (`"a, b"`, `""` for a quote); a quoted cell may span
//! lines. Leading and trailing blanks around a cell are dropped. A UTF-8 byte-order mark at
//! the start is skipped.
//!
//! Bounded: a record (a line, or several joined by a quoted cell) longer than
//! [`MAX_RECORD_BYTES`] is an error at the line it starts on, whatever it holds (`/dev/zero`,
//! a binary file, a quote never closed), so memory stays bounded by one record.
//!
//! Why by hand: the `csv` crate reports a record's line by counting LF only (a CR-only file is
//! one line, and its positions drift on blank lines), buffers a whole quoted cell whatever
//! its size, and gives no cell's own line; this reader is one small state machine.

use std::io::{BufRead, BufReader, Read};

/// The longest record (a line, or the lines one quoted cell joins), bytes: a header of a few
/// hundred columns fits many times.
pub const MAX_RECORD_BYTES: usize = 1 << 20;

/// One cell: its text (unquoted, trimmed) and the line it starts on (1-based).
#[derive(Clone, Debug, PartialEq)]
pub struct Cell {
    /// The text.
    pub text: String,
    /// The line the cell starts on.
    pub line: u64,
}

/// One record: the line it starts on and its cells.
#[derive(Clone, Debug, PartialEq)]
pub struct Record {
    /// The line the record starts on (1-based).
    pub line: u64,
    /// Its cells, in order.
    pub cells: Vec<Cell>,
    /// It ended at a carriage return that no line feed follows, in a file with line feeds: a
    /// stray `\r` cut the line.
    pub cut_by_cr: bool,
}

/// Why a record could not be read. Lines and columns (cells) are 1-based.
#[derive(Debug)]
pub enum RecordError {
    /// Reading failed.
    Io { line: u64, source: std::io::Error },
    /// The record starting at `line` is longer than [`MAX_RECORD_BYTES`]; `quoted`: a quoted
    /// cell (column `column`) was open when the limit was reached.
    TooLong {
        line: u64,
        column: usize,
        quoted: bool,
    },
    /// A cell is not UTF-8 text.
    NotText { line: u64, column: usize },
    /// The file ends inside a quoted cell opened at `line`.
    UnclosedQuote { line: u64, column: usize },
}

#[derive(Clone, Copy, PartialEq)]
enum State {
    /// Before a cell's first character (blanks skipped).
    Start,
    /// Inside an unquoted cell.
    Plain,
    /// Inside quotes.
    Quoted,
    /// A quote inside quotes: the end of the quoted part, or the first of `""`.
    AfterQuote,
}

/// Reads records one at a time.
pub struct Records<R> {
    inner: BufReader<R>,
    /// The line of the next byte.
    line: u64,
    /// The previous byte was a CR ending a line: an LF right after it belongs to it.
    after_cr: bool,
    started: bool,
    /// A line feed has been read.
    lf_seen: bool,
}

/// A record being assembled.
struct Partial {
    line: u64,
    cells: Vec<Cell>,
    cur: Vec<u8>,
    cell_line: u64,
    state: State,
    bytes: usize,
    quoted_any: bool,
}

impl Partial {
    fn end_cell(&mut self) -> Result<(), RecordError> {
        if matches!(self.state, State::Plain | State::Start) {
            while self.cur.last().is_some_and(|b| *b == b' ' || *b == b'\t') {
                self.cur.pop();
            }
        }
        let bytes = std::mem::take(&mut self.cur);
        let text = String::from_utf8(bytes).map_err(|_| RecordError::NotText {
            line: self.cell_line,
            column: self.cells.len() + 1,
        })?;
        self.cells.push(Cell {
            text,
            line: self.cell_line,
        });
        self.state = State::Start;
        Ok(())
    }

    /// A line with nothing on it (or only blanks).
    fn is_blank(&self) -> bool {
        !self.quoted_any && self.cells.len() == 1 && self.cells[0].text.is_empty()
    }
}

impl<R: Read> Records<R> {
    /// Start reading `inner`.
    pub fn new(inner: R) -> Self {
        Records {
            inner: BufReader::with_capacity(64 * 1024, inner),
            line: 1,
            after_cr: false,
            started: false,
            lf_seen: false,
        }
    }

    /// The next record that is not a blank line, or `None` at the end.
    pub fn next_record(&mut self) -> Result<Option<Record>, RecordError> {
        loop {
            match self.next_any()? {
                Some(p) if p.is_blank() => continue,
                Some(p) => {
                    let cut_by_cr = self.after_cr && self.lf_seen && self.next_is_not_lf();
                    return Ok(Some(Record {
                        line: p.line,
                        cells: p.cells,
                        cut_by_cr,
                    }));
                }
                None => return Ok(None),
            }
        }
    }

    /// The next byte is there and is not a line feed (a read error counts as a line feed:
    /// it is reported by the next record).
    fn next_is_not_lf(&mut self) -> bool {
        self.inner
            .fill_buf()
            .is_ok_and(|b| b.first().is_some_and(|&c| c != b'\n'))
    }

    fn skip_bom(&mut self) -> Result<(), RecordError> {
        self.started = true;
        let buf = self.inner.fill_buf().map_err(|source| RecordError::Io {
            line: self.line,
            source,
        })?;
        if buf.starts_with(&[0xEF, 0xBB, 0xBF]) {
            self.inner.consume(3);
        }
        Ok(())
    }

    /// The next record, blank or not.
    fn next_any(&mut self) -> Result<Option<Partial>, RecordError> {
        if !self.started {
            self.skip_bom()?;
        }
        let mut p = Partial {
            line: self.line,
            cells: Vec::new(),
            cur: Vec::new(),
            cell_line: self.line,
            state: State::Start,
            bytes: 0,
            quoted_any: false,
        };
        loop {
            let line = self.line;
            let buf = match self.inner.fill_buf() {
                Ok(b) => b,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(source) => return Err(RecordError::Io { line, source }),
            };
            if buf.is_empty() {
                return self.at_end(p);
            }
            self.lf_seen |= buf.contains(&b'\n');
            let (used, done) = scan(&mut self.line, &mut self.after_cr, &mut p, buf)?;
            self.inner.consume(used);
            if done {
                return Ok(Some(p));
            }
        }
    }

    /// The end of the input: the last record, if it has anything.
    fn at_end(&mut self, mut p: Partial) -> Result<Option<Partial>, RecordError> {
        match p.state {
            State::Quoted => Err(RecordError::UnclosedQuote {
                line: p.cell_line,
                column: p.cells.len() + 1,
            }),
            State::Start if p.cells.is_empty() && p.bytes == 0 => Ok(None),
            _ => {
                p.end_cell()?;
                Ok(Some(p))
            }
        }
    }
}

/// Take bytes of `buf` into `p` (`line`: the line of the next byte; `after_cr`: the previous
/// byte ended a line with a CR); returns how many were used and whether the record ended.
fn scan(
    line: &mut u64,
    after_cr: &mut bool,
    p: &mut Partial,
    buf: &[u8],
) -> Result<(usize, bool), RecordError> {
    for (k, &b) in buf.iter().enumerate() {
        if std::mem::take(after_cr) && b == b'\n' {
            continue;
        }
        p.bytes += 1;
        if p.bytes > MAX_RECORD_BYTES {
            return Err(RecordError::TooLong {
                line: p.line,
                column: p.cells.len() + 1,
                quoted: p.state == State::Quoted,
            });
        }
        let newline = b == b'\n' || b == b'\r';
        if newline {
            *line += 1;
            *after_cr = b == b'\r';
        }
        match (p.state, b) {
            (State::Quoted, b'"') => p.state = State::AfterQuote,
            (State::Quoted, _) => p.cur.push(b),
            (State::AfterQuote, b'"') => {
                p.cur.push(b'"');
                p.state = State::Quoted;
            }
            (State::AfterQuote, b' ' | b'\t') => {}
            (State::Start, b' ' | b'\t') => {}
            (State::Start, b'"') => {
                p.state = State::Quoted;
                p.quoted_any = true;
                p.cell_line = *line;
            }
            (_, b',') => {
                p.end_cell()?;
                p.cell_line = *line;
            }
            (_, _) if newline => {
                p.end_cell()?;
                return Ok((k + 1, true));
            }
            (State::AfterQuote | State::Start | State::Plain, _) => {
                p.cur.push(b);
                p.state = State::Plain;
            }
        }
    }
    Ok((buf.len(), false))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn all(text: &[u8]) -> Vec<(u64, Vec<(String, u64)>)> {
        let mut r = Records::new(text);
        let mut out = Vec::new();
        while let Some(rec) = r.next_record().unwrap() {
            out.push((
                rec.line,
                rec.cells.into_iter().map(|c| (c.text, c.line)).collect(),
            ));
        }
        out
    }

    fn cells(text: &[u8]) -> Vec<(u64, Vec<String>)> {
        all(text)
            .into_iter()
            .map(|(l, c)| (l, c.into_iter().map(|x| x.0).collect()))
            .collect()
    }

    #[test]
    fn every_line_ending_and_blank_line_is_counted() {
        let want = |a: u64, b: u64| {
            vec![
                (1, vec!["a".into(), "b".into()]),
                (a, vec!["1".into(), "2".into()]),
                (b, vec!["3".into(), "4".into()]),
            ]
        };
        assert_eq!(cells(b"a,b\n1,2\n3,4\n"), want(2, 3));
        assert_eq!(cells(b"a,b\r\n1,2\r\n3,4"), want(2, 3));
        assert_eq!(cells(b"a,b\r1,2\r3,4\r"), want(2, 3));
        assert_eq!(cells(b"a,b\n\n\r\n  \n1,2\r\r3,4\n\n"), want(5, 7));
        assert_eq!(cells(b"\xEF\xBB\xBFa,b\n1,2\n3,4"), want(2, 3));
    }

    #[test]
    fn quoted_cells_keep_commas_quotes_and_their_own_line() {
        let r = all(b"a, \"b,c\" ,\"say \"\"hi\"\"\"\n\"two\nlines\",x,\"\"\n");
        assert_eq!(
            r[0].1,
            [("a".into(), 1), ("b,c".into(), 1), ("say \"hi\"".into(), 1)]
        );
        assert_eq!(r[1].0, 2);
        assert_eq!(
            r[1].1,
            [("two\nlines".into(), 2), ("x".into(), 3), ("".into(), 3)]
        );
    }

    #[test]
    fn long_records_unclosed_quotes_and_bad_text_are_located() {
        let mut long = b"a\n1\n".to_vec();
        long.extend(std::iter::repeat_n(b'x', MAX_RECORD_BYTES + 1));
        let mut r = Records::new(long.as_slice());
        r.next_record().unwrap();
        r.next_record().unwrap();
        assert!(matches!(
            r.next_record(),
            Err(RecordError::TooLong {
                line: 3,
                column: 1,
                quoted: false
            })
        ));
        let mut q = b"a,b\n1,\"".to_vec();
        q.extend(std::iter::repeat_n(b'\n', MAX_RECORD_BYTES + 1));
        let mut r = Records::new(q.as_slice());
        r.next_record().unwrap();
        assert!(matches!(
            r.next_record(),
            Err(RecordError::TooLong {
                line: 2,
                column: 2,
                quoted: true
            })
        ));
        let mut r = Records::new(&b"a,b\n1,\"open\n"[..]);
        r.next_record().unwrap();
        assert!(matches!(
            r.next_record(),
            Err(RecordError::UnclosedQuote { line: 2, column: 2 })
        ));
        let mut r = Records::new(&b"a,b\r\n1,\xff\r\n"[..]);
        r.next_record().unwrap();
        assert!(matches!(
            r.next_record(),
            Err(RecordError::NotText { line: 2, column: 2 })
        ));
    }
}
