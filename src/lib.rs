//! `capstan`: simulate the rig, analyse and diagnose its data, and log real runs — the command
//! line over every host crate of the workspace (`capstan-data`, `capstan-engine`,
//! `capstan-discover`, `capstan-plan`, `capstan-report`, `capstan-validation`, `capstan-sim`,
//! `capstan-link`, `capstan-outdir`, `capstan-log` (the files of a logged session),
//! `capstan-simboard` (the simulated board behind `rig --sim DIR` and `log --sim DIR`),
//! `capstan-condition` (a raw time series into pairs), `capstan-tracking`).
//!
//! * [`cli`]: one module per command, each with its `Args` and `run`, and `input`, `simboard`
//!   and `signal`, which serve several;
//! * [`outputs`]: how every command opens its output directory;
//! * [`provenance`]: version, commit, input hash and command line for every output;
//! * [`term`]: stdout and stderr that survive a closed pipe. Only this crate prints.
//!
//! The integration tests in `tests/` drive the binary, and use this library and the crates
//! directly.

pub mod cli;
pub mod outputs;
pub mod provenance;
pub mod term;
