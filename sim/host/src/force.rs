//! Force control on the simulated rig (issue 43): the firmware in force mode (the same
//! `capstan_rig::run_once`, the same supervisor) against the plant, with the servo's dead band on
//! (`capstan_plant::ServoDynamics::HS_322HD`), the thesis rig's noise, and a cord whose friction
//! may differ from the law the board was given.
//!
//! * this file: one force run ([`ForceRig`], [`run_force`]) and its trace for the tracking
//!   analysis;
//! * `law.rs`: a fitted model reduced to the board's law, and checked;
//! * `compare.rs`: open loop against feedback on the same plant, side by side.

mod compare;
mod law;

pub use compare::{compare, standard, Comparison, ComparisonRow, Controller, CordCase};
pub use law::{board_law, settled_t2_n, LawError, TOLERANCE_N, TOLERANCE_REL};

use crate::noise::NoiseProfile;
use crate::run::{self, RunLog, RunOutput, RunSpec, SetupError};
use crate::setup;
use capstan_physics::{FrictionLaw, Model, Operating, SensorArtefacts};
use capstan_plant::{CordSetup, Injection, PlantConfig, ServoDynamics};
use capstan_rig::safety::SafetyLimits;
use capstan_rig::{BoardLaw, Calibration, ControlMode, ForceConfig, Protocol, StepOrder};

/// The extended model `capstan analyze` fits to the bundled thesis data (its
/// `metrics.json: prediction_model.values`): mu 0.1453 at 1 N, contact heating 0.0332 /(N s)
/// remembered over 0.25 s, a T2 sensor offset of −0.823 N. `tests/force_control.rs` holds these
/// to a fresh analysis.
pub const THESIS_FIT_MU: f64 = 0.145_274_841;
/// See [`THESIS_FIT_MU`].
pub const THESIS_FIT_HEAT_PER_NS: f64 = 0.033_178_741;
/// See [`THESIS_FIT_MU`].
pub const THESIS_FIT_HEAT_TAU_S: f64 = 0.25;
/// See [`THESIS_FIT_MU`].
pub const THESIS_FIT_T2_OFFSET_N: f64 = -0.823_443_891;

/// The one-mu Euler-Eytelwein fit of the same analysis (`metrics.json`: `models`, baseline):
/// the open-loop Euler-Eytelwein row's mu.
pub const THESIS_EE_MU: f64 = 0.116_200_3;

/// The thesis fit as a model.
pub fn thesis_fit() -> Model {
    Model {
        law: FrictionLaw {
            mu: THESIS_FIT_MU,
            heat_per_ns: THESIS_FIT_HEAT_PER_NS,
            heat_tau_s: THESIS_FIT_HEAT_TAU_S,
            ..FrictionLaw::euler_eytelwein(THESIS_FIT_MU)
        },
        sensors: SensorArtefacts {
            t2_offset_n: THESIS_FIT_T2_OFFSET_N,
            ..SensorArtefacts::IDEAL
        },
    }
}

/// The thesis fit with its mu scaled by `factor` (a new cord: 1.2 is 20 % more friction).
pub fn thesis_cord(factor: f64) -> Model {
    let mut m = thesis_fit();
    m.law.mu *= factor;
    m
}

/// `f` with its feedback on (its own gains), or off (open loop in T2: kp = ki = 0).
pub fn feedback(f: ForceConfig, on: bool) -> ForceConfig {
    if on {
        f
    } else {
        ForceConfig {
            kp: 0.0,
            ki: 0.0,
            ..f
        }
    }
}

/// One force run on the simulated thesis rig.
#[derive(Clone, Debug)]
pub struct ForceRig {
    /// Wrap, deg.
    pub wrap_deg: f64,
    /// Capstan diameter, mm.
    pub diameter_mm: f64,
    /// Drive voltage, V.
    pub drive_v: f64,
    /// The cord's true law (and sensor artefacts): what the plant does.
    pub cord: Model,
    /// Force control as the board runs it (mode force is set by the run): profile, gains, law.
    pub force: ForceConfig,
    /// The protocol's timing (dwell, windows, trigger).
    pub protocol: Protocol,
    /// The rig's noise: `thesis` (wander of mu, zero errors, sensor noise) or `quiet`.
    pub noise: NoiseProfile,
    /// The plant's constants (the servo's dead band on).
    pub plant: PlantConfig,
    /// The firmware's safety limits.
    pub limits: SafetyLimits,
    /// Seed of the plant.
    pub seed: u64,
    /// Faults to inject.
    pub injections: Vec<Injection>,
    /// Sample the plant's truth this often, ms (0: never).
    pub trace_every_ms: u32,
}

impl Default for ForceRig {
    /// The thesis rig (720° on the 12.7 mm capstan at 10 V), the cord the thesis fit describes,
    /// the board given that fit, steps of 5, 10, 20 and 30 N with feedback, thesis noise.
    fn default() -> Self {
        let cord = thesis_fit();
        let op = Operating {
            diameter_mm: 12.7,
            ..Operating::from_wrap_deg(720.0)
        };
        let law = board_law(&cord, &op, 12.0).unwrap_or(BoardLaw::NONE);
        let mut plant = PlantConfig::default();
        plant.servo.dynamics = ServoDynamics::HS_322HD;
        ForceRig {
            wrap_deg: 720.0,
            diameter_mm: 12.7,
            drive_v: 10.0,
            cord,
            force: ForceConfig {
                law,
                ..ForceConfig::default()
            },
            protocol: Protocol::default(),
            noise: NoiseProfile::Thesis,
            plant,
            limits: SafetyLimits::default(),
            seed: 1,
            injections: Vec::new(),
            trace_every_ms: 0,
        }
    }
}

impl ForceRig {
    /// The protocol the board runs: the timing, the rig's wrap and diameter, the drive's
    /// control voltage, force mode.
    pub fn board_protocol(&self) -> Protocol {
        let p = setup::cord_protocol(
            &self.protocol,
            &Calibration::default(),
            StepOrder::Monotone,
            self.diameter_mm,
            self.wrap_deg,
            self.drive_v,
        );
        Protocol {
            force: ForceConfig {
                mode: ControlMode::Force,
                ..self.force
            },
            ..p
        }
    }

    /// The run as host-sim runs any run.
    pub fn spec(&self) -> Result<RunSpec, SetupError> {
        setup::check_diameter(self.diameter_mm).map_err(SetupError::Range)?;
        setup::check_wrap(self.wrap_deg).map_err(SetupError::Range)?;
        setup::check_drive_v(self.drive_v, &Calibration::default()).map_err(SetupError::Range)?;
        let mut plant = setup::cord_plant(&self.plant, self.diameter_mm, true);
        plant.disturbances = self.noise.disturbances();
        Ok(RunSpec {
            plant,
            cord: CordSetup::new(self.wrap_deg, self.cord),
            protocol: self.board_protocol(),
            calibration: setup::typed_calibration(),
            limits: setup::cord_limits(&self.limits, &plant),
            seed: self.seed,
            injections: self.injections.clone(),
            keep_raw: true,
            trace_every_ms: self.trace_every_ms,
        })
    }
}

/// Run the firmware in force mode once against the plant.
pub fn run_force(rig: &ForceRig) -> Result<RunOutput, SetupError> {
    run::run(&rig.spec()?)
}

/// The raw log as the tracking analysis reads it: seconds since the trigger, the target and
/// the measured T2.
pub fn trace_of(log: &RunLog) -> capstan_tracking::Trace {
    let mut tr = capstan_tracking::Trace::default();
    for r in &log.raw {
        tr.push(
            r.t_us as f64 * 1e-6,
            f64::from(r.t2_target_n),
            f64::from(r.force_n[1]),
        );
    }
    tr
}

/// `n` force-controlled channels on one drive (the two-control rig generalised): 720° cords
/// of the thesis fit on the 12.7 mm capstan at 10 V, the board given the fitted law; odd
/// channels (1, 3) step through 5, 10, 20 and 30 N, even ones (2, 4) hold 15 N, starting 5 s
/// later so that they hold while the others step. Thesis noise, the servos' dead band on.
pub fn channels(n: usize) -> crate::two_control::TwoControlConfig {
    use crate::two_control::{ChannelSpec, TwoControlConfig};
    let rig = ForceRig::default();
    let mut plant = rig.plant;
    plant.disturbances = NoiseProfile::Thesis.disturbances();
    let (steps, hold) = (
        ForceConfig {
            levels_n: [5.0, 10.0, 20.0, 30.0],
            ..rig.force
        },
        ForceConfig {
            levels_n: [15.0; 4],
            ..rig.force
        },
    );
    TwoControlConfig {
        channels: (0..n)
            .map(|i| ChannelSpec {
                wrap_deg: 720.0,
                order: StepOrder::Monotone,
                delay_ms: if i % 2 == 0 { 0 } else { 5_000 },
            })
            .collect(),
        model: rig.cord,
        plant,
        force: (0..n)
            .map(|i| if i % 2 == 0 { steps } else { hold })
            .collect(),
        ..TwoControlConfig::default()
    }
}
