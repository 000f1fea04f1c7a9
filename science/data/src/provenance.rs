//! Where an output came from: the program's version and commit, the input's SHA-256 and the
//! command line. Every command that writes a result (`analyze`'s `metrics.json` and report,
//! `simulate`'s and `log`'s `summary.json`, `diagnose --json`) carries one, so that a number in
//! a paper can be traced to the data and the program that made it.

use serde::Serialize;
use sha2::{Digest, Sha256};
use std::io::Read;
use std::path::Path;

/// The provenance of one output.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Provenance {
    /// The program (`capstan`) and its version.
    pub program: String,
    /// The git commit it was built from ("unknown" when built outside a git checkout; a
    /// "-dirty" suffix when the work tree had changes).
    pub commit: String,
    /// The input file's name as given (or the bundled data set).
    pub input: Option<String>,
    /// SHA-256 of the input's bytes (hex); None for a command without an input file.
    pub input_sha256: Option<String>,
    /// The command line, arguments separated by spaces (each quoted when it has a space).
    pub command_line: String,
}

impl Provenance {
    /// One line for a report or a terminal.
    pub fn line(&self) -> String {
        let mut s = format!("{}, commit {}", self.program, self.commit);
        if let (Some(i), Some(h)) = (&self.input, &self.input_sha256) {
            s.push_str(&format!("; input {i}, SHA-256 {h}"));
        }
        s.push_str(&format!("; command: {}", self.command_line));
        s
    }
}

/// SHA-256 (hex) of bytes.
pub fn sha256_hex(bytes: &[u8]) -> String {
    hex(&Sha256::digest(bytes))
}

/// SHA-256 (hex) of a file, read in blocks (a file of any size in bounded memory).
pub fn sha256_file(path: &Path) -> std::io::Result<String> {
    let mut f = std::fs::File::open(path)?;
    let mut h = Sha256::new();
    let mut buf = vec![0u8; 1 << 16];
    loop {
        let n = f.read(&mut buf)?;
        if n == 0 {
            break;
        }
        h.update(&buf[..n]);
    }
    Ok(hex(&h.finalize()))
}

fn hex(d: &[u8]) -> String {
    d.iter().map(|b| format!("{b:02x}")).collect()
}

/// SHA-256 of the bundled thesis data ([`crate::THESIS_CSV`]): a file with these bytes is the
/// thesis data set, whatever its name.
pub fn thesis_sha256() -> String {
    sha256_hex(crate::THESIS_CSV.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sha256_of_known_text() {
        assert_eq!(
            sha256_hex(b"abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }

    #[test]
    fn the_repository_copy_of_the_thesis_data_hashes_as_bundled() {
        let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/thesis-conditioned.csv");
        assert_eq!(sha256_file(&p).unwrap(), thesis_sha256());
    }
}
