//! The simulated capstan rig, `no_std`: what the firmware drives when there is no rig.
//!
//! ```text
//! servo PWM ─► HS-322HD (its own 0.1°/µs about 1500 µs; 50 Hz frames, slew- and
//!              torque-limited; without pulses, back-driven by the cord) ─► 6.35 mm lever
//!          ─► cord (hardening spring, 0.1 N preload at the rest pulse) ─► T1 sensor
//!          ─► capstan friction (capstan_physics::Model, the shared law) ─► T2 sensor
//! amp PWM ─► RC filter (4.7 ms; 6.9 ms with the pin released) ─► power amplifier (×4)
//!             ─► Pittman gearmotor (19.7:1)
//!             ─► capstan speed, current
//!             ▲ friction torque Σ(T2 − T1)·r of every cord, through the gearbox
//! sensors: zero, gain, Gaussian noise, saturation at the divider's 5 V, 12-bit ADC with its
//!          own offset and noise (nominal = firmware's default calibration)
//! ```
//!
//! [`Plant`] holds the physics; [`hal`] has the adapters that implement the board's traits
//! (`SetDutyCycle`, `OutputPin`, `InputPin`, `ForceAdc`, `Watchdog`) over a
//! `&RefCell<Plant>`, reading the time with `embassy_time::Instant::now()`: the plant sees
//! duty cycles and pin levels, the firmware sees ADC counts and the button (SITL style). The
//! host simulator and the emulated-ARM firmware run the same plant.
//!
//! Friction: with the capstan turning, T2 = `model.law.t2_n(T1, op)` (the catalogue's physical
//! effects live there); stopped, T2 = T1; stalled (the drive cannot supply the friction
//! torque), T2 − T1 is what the stalled motor can push. The model's sensor artefacts are applied
//! by the sensors, and all three ride on the drive (the power amplifier's current shifts the
//! sensor amplifiers' ground and loads their supply): present whenever the capstan is driven,
//! absent during the firmware's tare (capstan stopped, cord at its preload). So the tare
//! neither removes the offsets nor sees the gain, and the data show `T1 + t1_offset` and
//! `t2_gain·T2 + t2_offset`, exactly as the catalogue defines them. (A gain present at the tare
//! too would be calibrated against the 0.1 N preload and leave `t2_gain·T2 − (t2_gain − 1)·0.1
//! N`: a gain plus a T2 offset, i.e. not the catalogue's single effect.)
//!
//! Determinism: all physics is f64 and the noise comes from [`rng::Rng`] (xoshiro256++ and
//! ziggurat normals, the `capstan-rng` crate); the same seed and the same calls give the same counts, on the host and on a
//! Cortex-M. The friction law and the cord's stretch use `capstan_physics::math` (the
//! platform's `pow`/`exp` on the host, `libm`'s elsewhere: an ulp apart at most, far below the
//! counts' quantisation); everything else is `libm`, bit for bit the same everywhere.
#![no_std]
#![deny(missing_docs)]
#![forbid(unsafe_code)]

pub mod config;
pub mod disturb;
pub mod hal;
mod injection;
mod plant;
/// The deterministic generator (its own crate, `capstan-rng`, which the statistics use too).
pub use capstan_rng as rng;
pub mod servo;

pub use config::{
    AdcConfig, CordConfig, CordSetup, FaultConfig, MotorConfig, PlantConfig, SensorConfig,
    ServoCharacteristic, ServoConfig, DIVIDER_SATURATION_COUNTS, THESIS_REST_PULSE_US,
};
pub use disturb::{Disturbances, Unmodelled};
pub use hal::{rig_io, rig_io_on, ForcedOutputs, SimRigIo, AMP_MAX_DUTY, SERVO_MAX_DUTY};
pub use injection::{Injection, InjectionKind, InjectionReport};
pub use plant::{
    CordTruth, DriveState, Plant, PlantError, ServoEvent, MAX_CORDS, MAX_INJECTIONS,
    MAX_SERVO_EVENTS, MAX_TRIGGER_EDGES,
};
pub use servo::ServoDynamics;

/// The thesis's friction coefficient for its plain exponential fit (Table 1).
pub const THESIS_MU: f64 = 0.115;

#[cfg(test)]
mod tests;
