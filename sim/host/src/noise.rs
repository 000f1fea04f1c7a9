//! How noisy a simulated campaign is: the quiet simulator (sensor white noise only), or the
//! scatter of the thesis rig, measured on its data (`docs/README-diagnose.md`, "Noise").
//!
//! The thesis profile sets every level the analysis must see through:
//! * cord-to-cord scatter of mu and run-to-run scatter within a cord (campaign),
//! * a slow wander of mu inside each run: serially correlated pairs (plant),
//! * a zero error of each sensor after the tare, one per run (plant),
//! * the sensors' white noise and the 12-bit ADC (plant, always on).

use crate::campaign::CampaignConfig;
use capstan_plant::Disturbances;
use std::fmt;
use std::str::FromStr;

/// A named noise level for campaigns.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NoiseProfile {
    /// Sensor white noise only; no scatter of mu unless asked for.
    Quiet,
    /// The thesis rig's scatter, within runs, between runs and between cords.
    Thesis,
}

/// The thesis profile's levels. Measured on the thesis data with the residuals of the model
/// `capstan diagnose` selects, and matched by simulated clean campaigns measured the same way
/// (see `docs/README-diagnose.md`, "Noise").
pub mod thesis {
    /// Cord-to-cord SD of mu, %.
    pub const CORD_SCATTER_PCT: f64 = 4.3;
    /// Run-to-run SD of mu within a cord, %.
    pub const RUN_SCATTER_PCT: f64 = 3.4;
    /// Stationary SD of the wander of ln mu inside a run.
    pub const MU_WANDER_SD: f64 = 0.03;
    /// Correlation time of that wander, s.
    pub const MU_WANDER_TAU_S: f64 = 40.0;
    /// SD of each sensor's zero error after the tare, N.
    pub const ZERO_ERROR_SD_N: f64 = 0.1;
}

impl NoiseProfile {
    /// Names on the command line.
    pub const NAMES: [&'static str; 2] = ["quiet", "thesis"];

    /// The plant's disturbances of this profile.
    pub fn disturbances(self) -> Disturbances {
        match self {
            NoiseProfile::Quiet => Disturbances::QUIET,
            NoiseProfile::Thesis => Disturbances {
                mu_wander_sd: thesis::MU_WANDER_SD,
                mu_wander_tau_s: thesis::MU_WANDER_TAU_S,
                zero_error_sd_n: thesis::ZERO_ERROR_SD_N,
            },
        }
    }

    /// Set `cfg`'s scatter of mu and its plant's disturbances to this profile (the thesis
    /// profile's scatter; the quiet one leaves the scatter as it is).
    pub fn apply(self, cfg: &mut CampaignConfig) {
        cfg.plant.disturbances = self.disturbances();
        cfg.sensor_noise = true;
        if self == NoiseProfile::Thesis {
            cfg.scatter_pct = thesis::CORD_SCATTER_PCT;
            cfg.run_scatter_pct = Some(thesis::RUN_SCATTER_PCT);
        }
    }
}

impl fmt::Display for NoiseProfile {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            NoiseProfile::Quiet => "quiet",
            NoiseProfile::Thesis => "thesis",
        })
    }
}

/// A noise profile's name that is none of [`NoiseProfile::NAMES`].
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("`{}`: unknown noise profile (known: {})", .0, NoiseProfile::NAMES.join(", "))]
pub struct UnknownNoiseProfile(
    /// The name given.
    pub String,
);

impl FromStr for NoiseProfile {
    type Err = UnknownNoiseProfile;

    fn from_str(s: &str) -> Result<Self, UnknownNoiseProfile> {
        match s.trim() {
            "quiet" => Ok(NoiseProfile::Quiet),
            "thesis" => Ok(NoiseProfile::Thesis),
            other => Err(UnknownNoiseProfile(other.to_string())),
        }
    }
}
