//! The provenance this binary puts in its outputs ([`capstan_data::Provenance`]): its version,
//! the commit it was built from (embedded by `build.rs`), the input's SHA-256 and the command
//! line.

use capstan_data::provenance::{sha256_file, thesis_sha256};
use capstan_data::Provenance;
use std::path::Path;

/// The commit this binary was built from, or "unknown".
pub const COMMIT: &str = env!("CAPSTAN_GIT_COMMIT");

/// The command line as typed (arguments with spaces quoted).
pub fn command_line() -> String {
    std::env::args()
        .map(|a| {
            if a.contains(char::is_whitespace) || a.is_empty() {
                format!("'{a}'")
            } else {
                a
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// Provenance without an input file.
pub fn without_input() -> Provenance {
    Provenance {
        program: format!("capstan {}", env!("CARGO_PKG_VERSION")),
        commit: COMMIT.to_string(),
        input: None,
        input_sha256: None,
        command_line: command_line(),
    }
}

/// Provenance of a command that read `path` (None: the bundled thesis data).
pub fn of_input(path: Option<&Path>) -> anyhow::Result<Provenance> {
    let (input, sha) = match path {
        Some(p) => (
            p.display().to_string(),
            sha256_file(p).map_err(|e| anyhow::anyhow!("cannot read {}: {e}", p.display()))?,
        ),
        None => (
            capstan_data::bundled_path().display().to_string() + " (bundled)",
            thesis_sha256(),
        ),
    };
    Ok(Provenance {
        input: Some(input),
        input_sha256: Some(sha),
        ..without_input()
    })
}

/// True when the provenance's input is the thesis data set (its bytes, whatever its name).
pub fn is_thesis(p: &Provenance) -> bool {
    p.input_sha256.as_deref() == Some(thesis_sha256().as_str())
}
