//! The command line: one module per subcommand, each with its `Args` and `run`; `input` (the
//! data commands' shared arguments), `simboard` (`--sim DIR`) and `signal` serve several.

use clap::{Parser, Subcommand};

pub mod analyze;
pub mod condition;
pub mod diagnose;
pub mod discover;
pub mod input;
pub mod log;
pub mod plan;
pub mod predict;
pub mod rig;
pub mod signal;
pub mod simboard;
pub mod simulate;

/// `capstan --version`: the version and the git commit this binary was built from (as every
/// output's provenance gives them).
pub const VERSION: &str = concat!(
    env!("CARGO_PKG_VERSION"),
    " (commit ",
    env!("CAPSTAN_GIT_COMMIT"),
    ")"
);

/// Capstan-friction rig: simulate, analyse, diagnose and log.
#[derive(Parser, Debug)]
#[command(name = "capstan", version = VERSION, about, long_about = None)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// Subcommands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Run the firmware against the simulated plant (a whole campaign in virtual time).
    Simulate(simulate::Args),
    /// Analyse measured pairs against the models and write the report.
    Analyze(analyze::Args),
    /// Say which catalogue effects a data set holds (several, or none), or that it holds
    /// structure no catalogue effect explains.
    Diagnose(diagnose::Args),
    /// Search a library of physical terms beyond the catalogue for what is left; propose one
    /// only if it earns its evidence and helps held-out cords.
    Discover(discover::Args),
    /// Plan the experiment that decides between the hypotheses a data set leaves open, with
    /// each protocol's chance of deciding from simulated campaigns.
    Plan(plan::Args),
    /// T2 and amplification from an analysis's fitted model, with a 95 % confidence interval
    /// (the mean curve) and a 95 % prediction interval (a new measurement on a new cord).
    Predict(predict::Args),
    /// Record a real run from the board over defmt/RTT (or decode a saved stream).
    Log(log::Args),
    /// Set up the rig from the host: live forces, jog the servo, calibrate, set the protocol,
    /// store it on the board, start a run.
    Rig(rig::Args),
    /// Condition a raw time series (raw.csv, a logger's CSV or Logger Pro export) into pairs.
    Condition(condition::Args),
}

/// The checks every command that reads pairs runs before its work
/// ([`capstan_data::check_capstan_data`]): refused data are an error; what passes with a few
/// suspect rows or an unusual column is said on stderr, one `warning:` line each, and the
/// same sentences come back for the command's JSON (`data.warnings`).
pub fn check_data(ds: &capstan_data::Dataset) -> anyhow::Result<Vec<String>> {
    let found = capstan_data::check_capstan_data(ds)?;
    let warnings = found.warnings(&ds.source);
    for w in &warnings {
        crate::errln!("warning: {w}");
    }
    Ok(warnings)
}

/// Run a parsed command line.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    // The engine's developer traces (CAPSTAN_FIT_LOG, CAPSTAN_LAPS) go to stderr.
    capstan_engine::trace::set_sink(|line| crate::errln!("{line}"));
    match cli.command {
        Command::Simulate(a) => simulate::run(a),
        Command::Analyze(a) => analyze::run(a),
        Command::Diagnose(a) => diagnose::run(a),
        Command::Discover(a) => discover::run(a),
        Command::Plan(a) => plan::run(a),
        Command::Log(a) => log::run(a),
        Command::Predict(a) => predict::run(a),
        Command::Rig(a) => rig::run(a),
        Command::Condition(a) => condition::run(a),
    }
}
