//! Campaigns: every (diameter, drive voltage, wrap) cord, each run `runs` times, through the
//! firmware's own protocol, sampling and conditioning, in parallel threads.
//!
//! Results do not depend on the thread count or on which other cords are in the campaign:
//! every random number of a run comes from a seed derived from the campaign seed and the
//! cord's (diameter, voltage, wrap) values and the run number.
//!
//! * this module: the campaign's configuration ([`CampaignConfig`], [`FaultSpec`]);
//! * `jobs`: the configuration checked and expanded into one [`RunSpec`](crate::run::RunSpec)
//!   per run (seeds, scatter, injections);
//! * `exec`: the runs on worker threads, collected in campaign order;
//! * `results`: what came out ([`CampaignResult`], [`PairRow`], [`FaultSummary`]).

mod exec;
mod jobs;
mod results;

pub use exec::{
    pair_rows, run_campaign, run_campaign_with_progress, stream_campaign, CampaignStats,
    StreamError,
};
pub use results::{summarise_faults, CampaignResult, CordKey, FaultSummary, PairRow, RunResult};

use crate::run::SetupError;
use capstan_physics::{Effect, Model};
use capstan_plant::{InjectionKind, PlantConfig, Unmodelled};
use capstan_rig::safety::SafetyLimits;
use capstan_rig::{Calibration, Protocol, StepOrder};
use std::fmt;
use std::str::FromStr;

/// A fault to inject: `NAME@SECONDS` (every run) or `NAME@SECONDS#RUN` (one run, numbered
/// 1.. over the whole campaign in its run order). Seconds count from the run's trigger.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaultSpec {
    /// What happens to the plant.
    pub kind: InjectionKind,
    /// When, s after the trigger's rising edge (the pairs' `time_s` timebase).
    pub at_s: f64,
    /// Only this run of the campaign (1-based), or every run.
    pub run: Option<u32>,
}

/// Why a fault argument (`NAME@SECONDS[#RUN]`) is refused; `spec` is the argument as given.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FaultSpecError {
    /// No `@` between the name and the time.
    #[error("`{spec}`: expected NAME@SECONDS (e.g. cord_break@40)")]
    Form {
        /// The argument.
        spec: String,
    },
    /// The name is no fault the plant can inject.
    #[error("`{name}`: unknown fault (known: {})", InjectionKind::NAMES.join(", "))]
    Unknown {
        /// The name given.
        name: String,
    },
    /// The run after `#` is not a whole number from 1.
    #[error("`{spec}`: the run after `#` must be 1 or more")]
    Run {
        /// The argument.
        spec: String,
    },
    /// The time is not a number.
    #[error("`{spec}`: `{secs}` is not a number of seconds")]
    NotSeconds {
        /// The argument.
        spec: String,
        /// The time as given.
        secs: String,
    },
    /// The time is negative or not finite.
    #[error("`{spec}`: the time must be 0 or more seconds after the trigger")]
    Negative {
        /// The argument.
        spec: String,
    },
}

impl FromStr for FaultSpec {
    type Err = FaultSpecError;

    fn from_str(s: &str) -> Result<Self, FaultSpecError> {
        let spec = || s.to_string();
        let (name, rest) = s
            .split_once('@')
            .ok_or_else(|| FaultSpecError::Form { spec: spec() })?;
        let kind =
            InjectionKind::from_name(name.trim()).ok_or_else(|| FaultSpecError::Unknown {
                name: name.to_string(),
            })?;
        let (secs, run) = match rest.split_once('#') {
            Some((a, r)) => {
                let run: u32 = r
                    .trim()
                    .parse()
                    .ok()
                    .filter(|&r| r >= 1)
                    .ok_or_else(|| FaultSpecError::Run { spec: spec() })?;
                (a, Some(run))
            }
            None => (rest, None),
        };
        let at_s: f64 = secs
            .trim()
            .parse()
            .map_err(|_| FaultSpecError::NotSeconds {
                spec: spec(),
                secs: secs.to_string(),
            })?;
        if !(at_s.is_finite() && at_s >= 0.0) {
            return Err(FaultSpecError::Negative { spec: spec() });
        }
        Ok(FaultSpec { kind, at_s, run })
    }
}

/// A campaign. `Default` is the thesis's: 2 diameters × 5 wraps × 6 runs at 10 V, monotone
/// steps, Euler-Eytelwein with mu = 0.115, no effect, no scatter, sensor noise on.
#[derive(Clone, Debug)]
pub struct CampaignConfig {
    /// Capstan diameters, mm.
    pub diameters_mm: Vec<f64>,
    /// Wrap angles, deg.
    pub wraps_deg: Vec<f64>,
    /// Drive voltages, V (the firmware commands drive/`amp_gain` of control voltage: at most
    /// 3.3 V × 4 = 13.2 V).
    pub drive_vs: Vec<f64>,
    /// Repeat runs per cord.
    pub runs: u32,
    /// Order of the tension levels.
    pub order: StepOrder,
    /// Catalogue effects switched on (in order) on top of `model`.
    pub effects: Vec<Effect>,
    /// The base friction model (and sensor artefacts).
    pub model: Model,
    /// Cord-to-cord standard deviation of mu, %. A cord is one (diameter, drive voltage, wrap)
    /// group.
    pub scatter_pct: f64,
    /// Run-to-run standard deviation of mu within a cord, % (`None`: half of `scatter_pct`).
    pub run_scatter_pct: Option<f64>,
    /// Physics outside the effect catalogue, on every cord (none by default).
    pub unmodelled: Unmodelled,
    /// Gaussian sensor noise (the plant's `sensor.noise_sd_n`); off = noiseless conversions.
    pub sensor_noise: bool,
    /// Campaign seed.
    pub seed: u64,
    /// Faults to inject.
    pub faults: Vec<FaultSpec>,
    /// The protocol (dwell, windows, sample rate, ...); `order`, `amp_control_v`, diameter and
    /// wrap are set per run from the fields above.
    pub protocol: Protocol,
    /// The calibration the firmware starts each run from.
    pub calibration: Calibration,
    /// The firmware's safety limits.
    pub limits: SafetyLimits,
    /// The rig's constants (`capstan_diameter_mm` is set per cord).
    pub plant: PlantConfig,
    /// Worker threads (0 = one per core).
    pub threads: usize,
    /// Keep every run's decimated raw samples in the result.
    pub keep_raw: bool,
}

impl Default for CampaignConfig {
    fn default() -> Self {
        CampaignConfig {
            diameters_mm: vec![12.7, 25.4],
            wraps_deg: vec![270.0, 360.0, 450.0, 630.0, 720.0],
            drive_vs: vec![10.0],
            runs: 6,
            order: StepOrder::Monotone,
            effects: Vec::new(),
            model: Model::euler_eytelwein(capstan_plant::THESIS_MU),
            scatter_pct: 0.0,
            run_scatter_pct: None,
            unmodelled: Unmodelled::default(),
            sensor_noise: true,
            seed: 1,
            faults: Vec::new(),
            protocol: Protocol::default(),
            calibration: crate::setup::typed_calibration(),
            limits: SafetyLimits::default(),
            plant: PlantConfig::default(),
            threads: 0,
            keep_raw: true,
        }
    }
}

/// Why a campaign cannot run.
#[derive(Clone, Debug, PartialEq)]
pub enum CampaignError {
    /// A list is empty.
    Empty(&'static str),
    /// A value is out of range: which, the value, and what is allowed.
    Bad(&'static str, f64, String),
    /// A fault names a run the campaign does not have.
    FaultRun(u32, u32),
    /// The firmware or the plant refuses the setup.
    Setup(SetupError),
    /// The simulation of a run panicked (a bug in the simulator or the firmware): the run
    /// and the message. The runs before it were handed over.
    Panicked(u32, String),
}

impl fmt::Display for CampaignError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CampaignError::Empty(what) => write!(f, "{what}: give at least one value"),
            CampaignError::Bad(what, v, allowed) => write!(f, "{what} = {v}: {allowed}"),
            CampaignError::FaultRun(r, n) => {
                write!(f, "fault on run {r}, but the campaign has {n} runs")
            }
            CampaignError::Setup(e) => write!(f, "{e}"),
            CampaignError::Panicked(run, why) => {
                write!(f, "the simulation of run {run} panicked: {why}")
            }
        }
    }
}

impl std::error::Error for CampaignError {}
