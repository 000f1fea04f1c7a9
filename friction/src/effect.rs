//! The effect catalogue: the single departures from Euler-Eytelwein the rig can show.
//!
//! Names and parameters are fixed (they appear on the command line, in JSON and in tests):
//!
//! | effect | parameter | neutral |
//! |---|---|---|
//! | `none` | - | - |
//! | `pressure_friction` | `n` | 1 |
//! | `bending_stiffness` | `b_nm2` | 0 |
//! | `t1_offset` | `offset_n` | 0 |
//! | `t2_offset` | `offset_n` | 0 |
//! | `sensor_gain` | `gain` | 1 |
//! | `thermal_drift` | `mu_change_per_100s` | 0 |
//! | `wear` | `mu_change_per_run` | 0 |
//! | `diameter_dependence` | `mu_change_per_mm` | 0 |
//! | `speed_dependence` | `mu_change_per_v` | 0 |
//! | `contact_heating` | `heat_per_n` | 0 |
//!
//! `contact_heating` is friction that falls with the friction load T2 − T1 the contact
//! carries: mu·exp(−h·H) with H the load remembered over [`HEAT_TAU_S`] (see
//! [`crate::LoadMemory`]). Its parameter is h·τ, the steady-state loss of ln mu per newton of
//! load (1/N); the memory is short against any conditioning window, so the data see
//! mu·exp(−heat_per_n·(T2 − T1)).

use crate::Model;

/// Memory time of the catalogue's `contact_heating`, s: shorter than the settling before any
/// conditioning window, so a window sees the steady state of the load it carries.
pub const HEAT_TAU_S: f64 = 0.25;
use core::fmt;
use core::str::FromStr;

/// One kind of departure from Euler-Eytelwein.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum EffectKind {
    /// Euler-Eytelwein holds.
    None,
    /// dT/dθ = k·Tⁿ with n < 1.
    PressureFriction,
    /// The cord lifts off at low tension.
    BendingStiffness,
    /// Zero offset on the T1 sensor.
    T1Offset,
    /// Zero offset on the T2 sensor.
    T2Offset,
    /// T2 gain error relative to T1.
    SensorGain,
    /// mu drifts with time in a run.
    ThermalDrift,
    /// mu changes from run to run.
    Wear,
    /// mu depends on capstan diameter.
    DiameterDependence,
    /// mu depends on drive voltage.
    SpeedDependence,
    /// mu falls with the friction load T2 − T1 (contact heating with a short memory).
    ContactHeating,
}

impl EffectKind {
    /// Every effect, `none` first.
    pub const ALL: [EffectKind; 11] = [
        EffectKind::None,
        EffectKind::PressureFriction,
        EffectKind::BendingStiffness,
        EffectKind::T1Offset,
        EffectKind::T2Offset,
        EffectKind::SensorGain,
        EffectKind::ThermalDrift,
        EffectKind::Wear,
        EffectKind::DiameterDependence,
        EffectKind::SpeedDependence,
        EffectKind::ContactHeating,
    ];

    /// The catalogue name.
    pub const fn name(self) -> &'static str {
        match self {
            EffectKind::None => "none",
            EffectKind::PressureFriction => "pressure_friction",
            EffectKind::BendingStiffness => "bending_stiffness",
            EffectKind::T1Offset => "t1_offset",
            EffectKind::T2Offset => "t2_offset",
            EffectKind::SensorGain => "sensor_gain",
            EffectKind::ThermalDrift => "thermal_drift",
            EffectKind::Wear => "wear",
            EffectKind::DiameterDependence => "diameter_dependence",
            EffectKind::SpeedDependence => "speed_dependence",
            EffectKind::ContactHeating => "contact_heating",
        }
    }

    /// The catalogue parameter name (`None` for `none`).
    pub const fn parameter(self) -> Option<&'static str> {
        match self {
            EffectKind::None => None,
            EffectKind::PressureFriction => Some("n"),
            EffectKind::BendingStiffness => Some("b_nm2"),
            EffectKind::T1Offset | EffectKind::T2Offset => Some("offset_n"),
            EffectKind::SensorGain => Some("gain"),
            EffectKind::ThermalDrift => Some("mu_change_per_100s"),
            EffectKind::Wear => Some("mu_change_per_run"),
            EffectKind::DiameterDependence => Some("mu_change_per_mm"),
            EffectKind::SpeedDependence => Some("mu_change_per_v"),
            EffectKind::ContactHeating => Some("heat_per_n"),
        }
    }

    /// The parameter value at which the effect vanishes.
    pub const fn neutral_value(self) -> f64 {
        match self {
            EffectKind::PressureFriction | EffectKind::SensorGain => 1.0,
            _ => 0.0,
        }
    }

    /// The data column the effect needs to be testable (beyond wrap, T1, T2), if any.
    pub const fn required_column(self) -> Option<&'static str> {
        match self {
            EffectKind::ThermalDrift => Some("time_s"),
            EffectKind::Wear => Some("run"),
            EffectKind::DiameterDependence => Some("capstan_diameter_mm"),
            EffectKind::SpeedDependence => Some("drive_v"),
            EffectKind::BendingStiffness => Some("capstan_diameter_mm"),
            _ => None,
        }
    }

    /// Look an effect up by its catalogue name.
    pub fn from_name(name: &str) -> Option<EffectKind> {
        EffectKind::ALL.into_iter().find(|k| k.name() == name)
    }
}

impl fmt::Display for EffectKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// An effect at a given parameter value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Effect {
    /// Which effect.
    pub kind: EffectKind,
    /// Its parameter (ignored for `none`).
    pub value: f64,
}

impl Effect {
    /// No departure from Euler-Eytelwein.
    pub const NONE: Effect = Effect {
        kind: EffectKind::None,
        value: 0.0,
    };

    /// Switch the effect on in `model` (overwrites that one parameter).
    pub fn apply(&self, model: &mut Model) {
        let v = self.value;
        match self.kind {
            EffectKind::None => {}
            EffectKind::PressureFriction => model.law.tension_exponent = v,
            EffectKind::BendingStiffness => model.law.bending_b_nm2 = v,
            EffectKind::T1Offset => model.sensors.t1_offset_n = v,
            EffectKind::T2Offset => model.sensors.t2_offset_n = v,
            EffectKind::SensorGain => model.sensors.t2_gain = v,
            EffectKind::ThermalDrift => model.law.mu_change_per_100s = v,
            EffectKind::Wear => model.law.mu_change_per_run = v,
            EffectKind::DiameterDependence => model.law.mu_change_per_mm = v,
            EffectKind::SpeedDependence => model.law.mu_change_per_v = v,
            // Without heating the memory time means nothing: leave it.
            EffectKind::ContactHeating if v == 0.0 => model.law.heat_per_ns = 0.0,
            EffectKind::ContactHeating => {
                model.law.heat_per_ns = v / HEAT_TAU_S;
                model.law.heat_tau_s = HEAT_TAU_S;
            }
        }
    }

    /// The value of this effect's parameter in `model`.
    pub fn read(kind: EffectKind, model: &Model) -> f64 {
        match kind {
            EffectKind::None => 0.0,
            EffectKind::PressureFriction => model.law.tension_exponent,
            EffectKind::BendingStiffness => model.law.bending_b_nm2,
            EffectKind::T1Offset => model.sensors.t1_offset_n,
            EffectKind::T2Offset => model.sensors.t2_offset_n,
            EffectKind::SensorGain => model.sensors.t2_gain,
            EffectKind::ThermalDrift => model.law.mu_change_per_100s,
            EffectKind::Wear => model.law.mu_change_per_run,
            EffectKind::DiameterDependence => model.law.mu_change_per_mm,
            EffectKind::SpeedDependence => model.law.mu_change_per_v,
            EffectKind::ContactHeating => model.law.heat_per_ns * model.law.heat_tau_s,
        }
    }
}

/// Why `NAME=VALUE` is not an effect.
#[derive(Clone, Debug, PartialEq)]
pub enum ParseEffectError {
    /// The name is not in the catalogue.
    UnknownEffect,
    /// `none` takes no value; every other effect needs one.
    MissingValue,
    /// The value is not a finite number.
    BadValue,
}

impl fmt::Display for ParseEffectError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ParseEffectError::UnknownEffect => {
                f.write_str("unknown effect (known: ")?;
                for (i, k) in EffectKind::ALL.iter().enumerate() {
                    if i > 0 {
                        f.write_str(", ")?;
                    }
                    f.write_str(k.name())?;
                }
                f.write_str(")")
            }
            ParseEffectError::MissingValue => f.write_str("expected NAME=VALUE"),
            ParseEffectError::BadValue => f.write_str("the value is not a finite number"),
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for ParseEffectError {}

impl FromStr for Effect {
    type Err = ParseEffectError;

    /// `NAME=VALUE`, e.g. `pressure_friction=0.85`, or `none`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let (name, value) = match s.split_once('=') {
            Some((n, v)) => (n.trim(), Some(v.trim())),
            None => (s.trim(), None),
        };
        let kind = EffectKind::from_name(name).ok_or(ParseEffectError::UnknownEffect)?;
        match (kind, value) {
            (EffectKind::None, None) => Ok(Effect::NONE),
            (_, None) => Err(ParseEffectError::MissingValue),
            (_, Some(v)) => {
                let value: f64 = v.parse().map_err(|_| ParseEffectError::BadValue)?;
                if !value.is_finite() {
                    return Err(ParseEffectError::BadValue);
                }
                Ok(Effect { kind, value })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_neutral_values_do_nothing() {
        for kind in EffectKind::ALL {
            assert_eq!(EffectKind::from_name(kind.name()), Some(kind));
            let base = Model::euler_eytelwein(0.115);
            let neutral = base.with_effect(Effect {
                kind,
                value: kind.neutral_value(),
            });
            assert_eq!(neutral, base, "{kind}");
        }
    }

    #[test]
    fn parses_name_value() {
        let e: Effect = "pressure_friction=0.85".parse().unwrap();
        assert_eq!(e.kind, EffectKind::PressureFriction);
        assert_eq!(e.value, 0.85);
        assert_eq!("none".parse::<Effect>(), Ok(Effect::NONE));
        assert_eq!(
            "wear".parse::<Effect>(),
            Err(ParseEffectError::MissingValue)
        );
        assert_eq!(
            "heat=1".parse::<Effect>(),
            Err(ParseEffectError::UnknownEffect)
        );
        assert_eq!("wear=x".parse::<Effect>(), Err(ParseEffectError::BadValue));
        assert_eq!(
            "wear=inf".parse::<Effect>(),
            Err(ParseEffectError::BadValue)
        );
    }

    #[test]
    fn apply_then_read_gives_the_value() {
        for kind in EffectKind::ALL.into_iter().skip(1) {
            let m = Model::euler_eytelwein(0.1).with_effect(Effect { kind, value: 0.37 });
            assert!((Effect::read(kind, &m) - 0.37).abs() < 1e-15, "{kind}");
        }
    }
}
