//! The simulated rig: what `--sim DIR` and its options describe (`sim.json`), the session it
//! makes for host-sim, and its hidden truth (`sim-truth.json`).

use crate::{Result, SimError};
use capstan_physics::{Effect, Model};
use capstan_rig::hal::Channel;
use capstan_sim::noise::NoiseProfile;
use capstan_sim::plant::rng::{derive_seed, Rng};
use capstan_sim::plant::{CordSetup, Plant, PlantConfig};
use capstan_sim::session::{SessionSpec, Step};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// How far a sensor's true sensitivity strays from its nominal one: the standard deviation of
/// the drawn factor (clamped to ±[`MAX_SENSITIVITY_ERROR`]).
pub const SENSITIVITY_ERROR_SD: f64 = 0.05;
/// The largest sensitivity error drawn.
pub const MAX_SENSITIVITY_ERROR: f64 = 0.12;
/// The spread of each sensor's zero around the nominal 400 counts, counts (sd).
pub const ZERO_SPREAD_COUNTS: f64 = 30.0;

/// What chooses a simulated board (`capstan rig` and `capstan log` take them as `--sim DIR`
/// and the `--sim-*` options). Only `dir` matters for a board that exists; the others describe
/// a new one (and, given for an existing board, must describe it).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SimOptions {
    /// The board's directory (created on first use: a new, unconfigured board).
    pub dir: Option<PathBuf>,
    /// Seed of its sensors' hidden errors and its noise [default: 1].
    pub seed: Option<u64>,
    /// Friction coefficient of its cord [default: [`capstan_sim::plant::THESIS_MU`]].
    pub mu: Option<f64>,
    /// The cord's true wrap, deg [default: 360].
    pub wrap_deg: Option<f64>,
    /// Catalogue effects, NAME=VALUE.
    pub effects: Vec<String>,
    /// Noise profile, `quiet` or `thesis` [default: quiet].
    pub noise: Option<String>,
}

/// The simulated rig (`sim.json`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct SimConfig {
    /// Seed of everything random.
    pub seed: u64,
    /// Friction coefficient of the base model.
    pub mu: f64,
    /// The cord's true wrap, deg.
    pub wrap_deg: f64,
    /// Catalogue effects, NAME=VALUE.
    pub effects: Vec<String>,
    /// Noise profile.
    pub noise: String,
}

/// One sensor's truth.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SensorTruth {
    /// Counts at 0 N.
    pub zero_counts: f64,
    /// True sensitivity, N per count.
    pub n_per_count: f64,
    /// True sensitivity over the nominal one the firmware's defaults assume (0.015 N/count).
    pub vs_nominal: f64,
}

/// What the firmware cannot see (`sim-truth.json`).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Truth {
    /// The rig.
    pub config: SimConfig,
    /// T1's sensor.
    pub t1: SensorTruth,
    /// T2's sensor.
    pub t2: SensorTruth,
    /// Capstan diameter, mm.
    pub capstan_diameter_mm: f64,
    /// Tension of the slack cord at the servo's rest, N (it is on both sensors at a zero).
    pub preload_n: f64,
}

impl SimConfig {
    /// The rig the options describe, checked.
    pub fn from_options(a: &SimOptions) -> Result<SimConfig> {
        let c = SimConfig {
            seed: a.seed.unwrap_or(1),
            mu: a.mu.unwrap_or(capstan_sim::plant::THESIS_MU),
            wrap_deg: a.wrap_deg.unwrap_or(360.0),
            effects: a.effects.clone(),
            noise: a.noise.clone().unwrap_or_else(|| "quiet".into()),
        };
        if !(c.mu.is_finite() && (0.0..=2.0).contains(&c.mu)) {
            return Err(SimError::Mu(c.mu));
        }
        if !(c.wrap_deg.is_finite() && c.wrap_deg > 0.0 && c.wrap_deg <= 1800.0) {
            return Err(SimError::WrapDeg(c.wrap_deg));
        }
        c.model()?;
        c.profile()?;
        Ok(c)
    }

    /// An existing board: options that would describe another rig are refused.
    pub fn check_same(&self, a: &SimOptions) -> Result<()> {
        let given = a.seed.is_some()
            || a.mu.is_some()
            || a.wrap_deg.is_some()
            || !a.effects.is_empty()
            || a.noise.is_some();
        if given && SimConfig::from_options(a)? != *self {
            let json = serde_json::to_string(self).expect("serialises");
            return Err(SimError::OtherRig(json));
        }
        Ok(())
    }

    fn model(&self) -> Result<Model> {
        let mut model = Model::euler_eytelwein(self.mu);
        let mut seen = Vec::new();
        for e in &self.effects {
            let eff: Effect = e
                .parse()
                .map_err(|err: capstan_physics::ParseEffectError| SimError::Effect {
                    effect: e.clone(),
                    reason: err.to_string(),
                })?;
            if seen.contains(&eff.kind) {
                return Err(SimError::EffectTwice {
                    effect: e.clone(),
                    kind: eff.kind.to_string(),
                });
            }
            seen.push(eff.kind);
            eff.apply(&mut model);
        }
        Ok(model)
    }

    fn profile(&self) -> Result<NoiseProfile> {
        self.noise.parse().map_err(SimError::Noise)
    }

    fn plant(&self) -> Result<PlantConfig> {
        let mut plant = PlantConfig::default();
        plant.sensor.zero_spread_counts = ZERO_SPREAD_COUNTS;
        plant.disturbances = self.profile()?.disturbances();
        Ok(plant)
    }

    fn cord(&self) -> Result<CordSetup> {
        Ok(CordSetup {
            wrap_deg: self.wrap_deg,
            model: self.model()?,
            ..CordSetup::default()
        })
    }

    /// Each sensor's true sensitivity over its nominal one (counts per newton), drawn from the
    /// seed.
    pub fn sensitivity_factors(&self) -> [f64; 2] {
        let mut rng = Rng::new(derive_seed(self.seed, &[0x5E45_0000]));
        let mut f = || {
            let e = (SENSITIVITY_ERROR_SD * rng.normal())
                .clamp(-MAX_SENSITIVITY_ERROR, MAX_SENSITIVITY_ERROR);
            1.0 + e
        };
        [f(), f()]
    }

    /// The steps that give the sensors their true sensitivities (first in every replay).
    pub fn sensor_steps(&self) -> Vec<Step> {
        let [a, b] = self.sensitivity_factors();
        vec![
            Step::ScaleSensor(Channel::T1, a),
            Step::ScaleSensor(Channel::T2, b),
        ]
    }

    /// The bench session for host-sim: the firmware's built-in settings (an unconfigured
    /// board), this rig.
    pub fn session_spec(&self) -> Result<SessionSpec> {
        Ok(SessionSpec {
            plant: self.plant()?,
            cord: self.cord()?,
            seed: self.seed,
            ..SessionSpec::default()
        })
    }

    /// The truth: the plant this rig builds, read before anything happens.
    pub fn truth(&self) -> Result<Truth> {
        let spec = self.session_spec()?;
        let plant = Plant::new_at(spec.plant, &[spec.cord], spec.seed, 0)
            .map_err(|e| SimError::Build(format!("{e:?}")))?;
        let zero = plant.sensor_zero_counts(0);
        let f = self.sensitivity_factors();
        let s = &spec.plant.sensor;
        let sensor = |k: usize| {
            let vs = s.gain * f[k];
            SensorTruth {
                zero_counts: zero[k],
                n_per_count: s.n_per_count / vs,
                vs_nominal: 1.0 / vs,
            }
        };
        Ok(Truth {
            config: self.clone(),
            t1: sensor(0),
            t2: sensor(1),
            capstan_diameter_mm: spec.plant.capstan_diameter_mm,
            preload_n: spec.plant.cord.preload_n,
        })
    }
}
