//! `capstan`: simulate the rig, analyse and diagnose its data, and log real runs.
//!
//! The library behind the `capstan` binary; the integration tests in `tests/` use it directly.

pub mod cli;
pub mod logger;
pub mod outputs;
pub mod term;
