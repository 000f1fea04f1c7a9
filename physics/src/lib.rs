//! Capstan friction laws and force-sensor artefacts, in one place.
//!
//! The simulated plant (`host-sim`, and the QEMU firmware build) transmits tension through
//! [`FrictionLaw`] and measures it through [`SensorArtefacts`]; the analysis fits the very same
//! [`Model`] to measured pairs. The plant we simulate is the model we fit.
//!
//! Conventions: tensions in newtons, angles in radians, diameters in millimetres, times in
//! seconds since the logger trigger, runs counted from 1. `no_std` (uses `libm`), so the
//! friction plant also compiles into the emulated-ARM firmware.
#![cfg_attr(not(feature = "std"), no_std)]
#![deny(missing_docs)]

pub mod catalogue;
mod effect;
pub mod entry;
mod law;
mod partials;
pub mod scalars;
mod sensor;

/// The elementary functions, shared by the friction law and the plant's hot path: the
/// platform's with `std` (the host's are 2-3x faster than `libm`'s, which dominate the
/// analysis's fits and the simulated cord's stretch), `libm`'s on bare metal and WebAssembly.
/// The two differ by an ulp at most; the simulated sensors quantise long before that shows (the
/// emulated board's and the QEMU image's counts equal host-sim's).
#[cfg(feature = "std")]
pub mod math {
    /// e^x.
    pub fn exp(x: f64) -> f64 {
        x.exp()
    }
    /// ln x.
    pub fn log(x: f64) -> f64 {
        x.ln()
    }
    /// x^y.
    pub fn pow(x: f64, y: f64) -> f64 {
        x.powf(y)
    }
    /// √x.
    pub fn sqrt(x: f64) -> f64 {
        x.sqrt()
    }
}
/// The elementary functions: `libm`'s (no `std` here).
#[cfg(not(feature = "std"))]
pub mod math {
    pub use libm::{exp, log, pow, sqrt};
}

pub use catalogue::{rivalry, EffectKind, Rivalry, ENTRIES, HEAT_TAU_S};
pub use effect::{Effect, ParseEffectError};
pub use entry::{EffectEntry, Facts, Level};
pub use law::{FrictionLaw, LoadMemory};
pub use partials::{LawPartials, MuPartials};
pub use scalars::{Enters, Scalar, SCALARS};
pub use sensor::{SensorArtefacts, SLACK_T1_N};

/// Reference capstan diameter for [`FrictionLaw::mu_change_per_mm`] (0.5 in), mm.
pub const REF_DIAMETER_MM: f64 = 12.7;
/// Reference drive voltage for [`FrictionLaw::mu_change_per_v`] (the thesis's runs), V.
pub const REF_DRIVE_V: f64 = 10.0;
/// Reference wrap for [`FrictionLaw::mu_log_slope_per_rad`]: 3π rad (540°, 1.5 turns).
pub const REF_WRAP_RAD: f64 = 3.0 * core::f64::consts::PI;
/// Reference tension of the power law: `k` in dT/dθ = k·Tⁿ equals mu at this tension, N.
pub const REF_TENSION_N: f64 = 1.0;

/// Where on the rig, and when, a tension is transmitted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Operating {
    /// Wrap (contact) angle, rad.
    pub wrap_rad: f64,
    /// Capstan diameter, mm.
    pub diameter_mm: f64,
    /// Drive-motor supply voltage, V.
    pub drive_v: f64,
    /// Repeat run on the same cord, 1-based.
    pub run: f64,
    /// Time since the logger trigger, s.
    pub time_s: f64,
    /// The contact's friction-load memory H at this moment, N s (see [`LoadMemory`]).
    pub load_memory_ns: f64,
}

impl Operating {
    /// A wrap given in degrees on the reference capstan, run 1, t = 0, at the reference voltage.
    pub fn from_wrap_deg(wrap_deg: f64) -> Self {
        Operating {
            wrap_rad: wrap_deg.to_radians(),
            diameter_mm: REF_DIAMETER_MM,
            drive_v: REF_DRIVE_V,
            run: 1.0,
            time_s: 0.0,
            load_memory_ns: 0.0,
        }
    }
}

/// A friction law plus sensor artefacts: predicts the *measured* T2 from the *measured* T1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Model {
    /// The physics of the cord on the capstan.
    pub law: FrictionLaw,
    /// What the two force sensors add.
    pub sensors: SensorArtefacts,
}

impl Model {
    /// Plain Euler-Eytelwein with coefficient `mu` and perfect sensors.
    pub fn euler_eytelwein(mu: f64) -> Self {
        Model {
            law: FrictionLaw::euler_eytelwein(mu),
            sensors: SensorArtefacts::IDEAL,
        }
    }

    /// Measured T2 for a measured T1 (N): undo the T1 artefact, transmit, apply the T2 artefacts.
    pub fn predict_t2_n(&self, t1_measured_n: f64, op: &Operating) -> f64 {
        let t1_true_n = self.sensors.true_t1_n(t1_measured_n);
        let t2_true_n = self.law.t2_n(t1_true_n, op);
        self.sensors.measured_t2_n(t2_true_n)
    }

    /// The model with one catalogue effect switched on at `value` (on top of what it has).
    pub fn with_effect(mut self, effect: Effect) -> Self {
        effect.apply(&mut self);
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn euler_eytelwein_is_exact() {
        let model = Model::euler_eytelwein(0.115);
        for wrap_deg in [270.0, 360.0, 450.0, 630.0, 720.0] {
            let op = Operating::from_wrap_deg(wrap_deg);
            for t1 in [0.3, 2.0, 22.0] {
                let want = t1 * libm::exp(0.115 * op.wrap_rad);
                let got = model.predict_t2_n(t1, &op);
                assert!(
                    (got / want - 1.0).abs() < 1e-12,
                    "{wrap_deg} {t1}: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn artefacts_round_trip_through_the_model() {
        let mut model = Model::euler_eytelwein(0.1);
        model.sensors = SensorArtefacts {
            t1_offset_n: 0.5,
            t2_offset_n: -0.3,
            t2_gain: 1.1,
        };
        let op = Operating::from_wrap_deg(360.0);
        // True T1 = 4 N reads 4.5 N; true T2 = 4 e^(0.1·2π) reads 1.1·T2 − 0.3.
        let t2_true = 4.0 * libm::exp(0.1 * op.wrap_rad);
        let got = model.predict_t2_n(4.5, &op);
        assert!((got - (1.1 * t2_true - 0.3)).abs() < 1e-12);
    }
}
