//! Every command's output directory as the program opens it (`capstan_outdir`): locked, with
//! what was recovered in it said on stderr, and a set kept after a failure said where.

use capstan_outdir::OutputDir;
use std::path::Path;

/// The output directory, locked, with what was recovered in it said on stderr.
pub fn open_out(dir: &Path, kind: &'static str, names: &[&str]) -> anyhow::Result<OutputDir> {
    let out = OutputDir::open(dir, kind, names)?;
    say_recovered(&out);
    Ok(out)
}

/// Say on stderr what opening `out` found and did (an interrupted commit finished, an
/// abandoned set kept).
pub fn say_recovered(out: &OutputDir) {
    for r in &out.recovered {
        crate::errln!("note: {r}");
    }
}

/// Say on stderr where the work of a set dropped after a failure is kept (for
/// [`capstan_outdir::Staged::keep_on_failure`]).
pub fn say_kept(kept: &Path) {
    crate::errln!("the work done so far is kept in {}", kept.display());
}
