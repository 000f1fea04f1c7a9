//! The adversarial corpus: every input and invocation that once misread a data set, lost a
//! session or hung, and the earlier ones of the same kinds, each with the refusal or the result
//! it must give. Fast enough for every `cargo test` (the reader's cases run in process, the
//! command lines refuse before any work).
//!
//! * `reader`: pairs CSVs — positions for every line ending, every column against its range,
//!   quoting, encodings, separators, structure, data that cannot be capstan pairs;
//! * `verdicts`: what `diagnose` and `analyze` say on extreme data (no inf or NaN; "not
//!   identified" where nothing can be said);
//! * `overwrite`: `log --overwrite` over a recorded session, every class of bad stream,
//!   interrupted at several points: the old session byte-identical;
//! * `cli`: command lines — output directories, ranges of every option, stdout errors, signals,
//!   silent input.
//!
//! Run: `cargo test --test adversarial` (it prints how many cases it checked).

mod cli;
mod overwrite;
mod reader;
mod verdicts;

use std::sync::atomic::{AtomicUsize, Ordering};

/// Cases checked in this process (each test adds its own).
pub static CHECKED: AtomicUsize = AtomicUsize::new(0);

/// Count one checked case (`--nocapture` shows the running total).
pub fn checked() {
    let n = CHECKED.fetch_add(1, Ordering::Relaxed) + 1;
    if n.is_multiple_of(25) {
        eprintln!("adversarial: {n} cases checked");
    }
}

/// A fresh scratch directory for `name`.
pub fn scratch(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("capstan-adv-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}
