//! Writing pairs in the CSV schema the reader reads: the header ([`PAIRS_HEADER`]) minus any
//! optional column the pairs do not all carry, or every column as the pairs come
//! ([`PairsWriter`], for `capstan log`).

use super::{Pair, PAIRS_HEADER};
use std::io::Write;
use std::path::Path;

/// Write pairs to a file (see [`write_pairs_to`]).
pub fn write_pairs(path: &Path, pairs: &[Pair]) -> Result<(), WriteError> {
    let at = |source| WriteError {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::create(path).map_err(at)?;
    let mut w = std::io::BufWriter::new(file);
    write_pairs_to(&mut w, pairs).map_err(at)?;
    w.flush().map_err(at)
}

/// A pairs file that could not be created or written.
#[derive(Debug, thiserror::Error)]
#[error("{}: {source}", path.display())]
pub struct WriteError {
    /// The file.
    pub path: std::path::PathBuf,
    /// What the system said.
    pub source: std::io::Error,
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

/// The columns of [`PAIRS_HEADER`] (indices) that every pair carries.
pub(super) fn columns_of(pairs: &[Pair]) -> Vec<usize> {
    (0..PAIRS_HEADER.len())
        .filter(|&i| pairs.iter().all(|p| column_value(p, i).is_some()))
        .collect()
}

/// Write pairs to any writer: the standard header ([`PAIRS_HEADER`]) minus any optional column
/// that the pairs do not all carry (so what is written reads back as it was).
pub fn write_pairs_to(w: &mut impl Write, pairs: &[Pair]) -> std::io::Result<()> {
    let columns = columns_of(pairs);
    let mut out = PairsWriter::with_columns(w, columns, &[], &[])?;
    pairs.iter().try_for_each(|p| out.write(p))
}

/// Writes pairs one at a time, as they come (`capstan log` writes each step's pair when the rig
/// reports it): the header first, then one row per [`PairsWriter::write`]. With
/// [`PairsWriter::new`] every column of [`PAIRS_HEADER`] is written, since later pairs are not
/// known yet: a `None`, or a wrap angle that is not finite (unknown), is an empty cell. A row
/// with an empty cell does not read back with [`super::read_pairs`]; `capstan log` keeps such rows in a
/// file of their own.
pub struct PairsWriter<W: Write> {
    inner: W,
    /// Indices into [`PAIRS_HEADER`], in order.
    columns: Vec<usize>,
    /// Further numeric columns after them: each pair's [`Pair::extra`], in order.
    extra: usize,
    /// Text (label) columns after those: each pair's [`Pair::labels`], in order.
    labels: usize,
}

impl<W: Write> PairsWriter<W> {
    /// Start the CSV with every column: write the header.
    pub fn new(inner: W) -> std::io::Result<Self> {
        Self::with_columns(inner, (0..PAIRS_HEADER.len()).collect(), &[], &[])
    }

    /// Start the CSV with every column and the text columns `labels` after them (e.g.
    /// `boot`, a run label of [`super::read::RUN_LABELS`]); each pair written carries their
    /// values in [`Pair::labels`].
    pub fn with_labels(inner: W, labels: &[&str]) -> std::io::Result<Self> {
        Self::with_columns(inner, (0..PAIRS_HEADER.len()).collect(), &[], labels)
    }

    /// Start the CSV with every column, the numeric columns `extra` after them (e.g.
    /// `t2_target_n`, force control's target) and then the text columns `labels`; each pair
    /// written carries their values in [`Pair::extra`] and [`Pair::labels`].
    pub fn with_extra(inner: W, extra: &[&str], labels: &[&str]) -> std::io::Result<Self> {
        Self::with_columns(inner, (0..PAIRS_HEADER.len()).collect(), extra, labels)
    }

    /// Start the CSV with these columns of [`PAIRS_HEADER`] (indices, in order).
    fn with_columns(
        mut inner: W,
        columns: Vec<usize>,
        extra: &[&str],
        labels: &[&str],
    ) -> std::io::Result<Self> {
        let mut names: Vec<&str> = columns.iter().map(|&i| PAIRS_HEADER[i]).collect();
        names.extend_from_slice(extra);
        names.extend_from_slice(labels);
        writeln!(inner, "{}", names.join(","))?;
        Ok(PairsWriter {
            inner,
            columns,
            extra: extra.len(),
            labels: labels.len(),
        })
    }

    /// Write one pair (not flushed).
    pub fn write(&mut self, p: &Pair) -> std::io::Result<()> {
        let mut cells: Vec<String> = self
            .columns
            .iter()
            .map(|&i| column_value(p, i).map_or(String::new(), |v| v.to_string()))
            .collect();
        cells.extend((0..self.extra).map(|k| {
            p.extra
                .get(k)
                .filter(|v| v.is_finite())
                .map_or(String::new(), |v| v.to_string())
        }));
        cells.extend((0..self.labels).map(|k| text_cell(p.labels.get(k).map_or("", |l| l))));
        writeln!(self.inner, "{}", cells.join(","))
    }

    /// Flush what was written to the underlying writer.
    pub fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }

    /// The underlying writer.
    pub fn into_inner(self) -> W {
        self.inner
    }
}

/// A text cell, quoted when it holds a comma, a quote or a line break.
pub fn text_cell(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}
