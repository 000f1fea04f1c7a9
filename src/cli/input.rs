//! The arguments every command that reads pairs shares (analyze, diagnose, discover, plan):
//! the data file, and how steps are timed without a `time_s` column. One definition, flattened
//! into each command's `Args`, so the commands read and describe their input alike.

use capstan_data::{load_pairs, thesis_dataset, Dataset, Provenance};
use std::path::PathBuf;

/// The pairs a command reads.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct DataArgs {
    /// Pairs CSV (`wrap_deg,t1_n,t2_n` required; `capstan_diameter_mm,drive_v,run,step,time_s`
    /// optional). Without it, the bundled thesis data (720 pairs).
    pub data: Option<PathBuf>,
}

impl DataArgs {
    /// The pairs: the file's, or the bundled thesis data.
    pub fn load(&self) -> anyhow::Result<Dataset> {
        Ok(match &self.data {
            Some(p) => load_pairs(p)?,
            None => thesis_dataset(),
        })
    }

    /// Where an answer from these data comes from (the input's SHA-256 among it).
    pub fn provenance(&self) -> anyhow::Result<Provenance> {
        crate::provenance::of_input(self.data.as_deref())
    }
}

/// How the steps are timed without a `time_s` column (analyze, diagnose, discover).
#[derive(clap::Args, Debug, Clone, Copy, Default)]
pub struct TimingArgs {
    /// Without a `time_s` column, take the times from `step` with the thesis protocol (10 s
    /// steps), so that a drift in time (`thermal_drift`) can be tested.
    #[arg(long)]
    pub protocol_times: bool,
}
