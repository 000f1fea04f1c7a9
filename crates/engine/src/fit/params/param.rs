//! The scalars of a [`Model`] a fit may move ([`Param`]) and the maps from an unbounded
//! internal coordinate θ to their values ([`Transform`]).

use capstan_friction::{EffectKind, Model};

/// One scalar of [`Model`] (friction law or sensor artefact).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Param {
    /// `law.mu`: friction coefficient at the reference conditions.
    Mu,
    /// `law.tension_exponent`: n of dT/dθ = k·Tⁿ.
    TensionExponent,
    /// `law.bending_b_nm2`: bending stiffness, N m².
    BendingB,
    /// `law.mu_change_per_100s`: drift of mu with time since the trigger.
    MuChangePer100s,
    /// `law.mu_change_per_run`: wear between runs.
    MuChangePerRun,
    /// `law.mu_change_per_mm`: diameter dependence.
    MuChangePerMm,
    /// `law.mu_change_per_v`: speed dependence.
    MuChangePerV,
    /// `law.mu_log_slope_per_rad`: wrap dependence of ln mu (anchored at 540°).
    MuLogSlopePerRad,
    /// `law.heat_per_ns`: contact heating, 1/(N s).
    HeatPerNs,
    /// `law.heat_tau_s`: memory time of the friction load, s.
    HeatTauS,
    /// `sensors.t1_offset_n`: T1 zero offset / T1-path loss, N.
    T1Offset,
    /// `sensors.t2_offset_n`: T2 zero offset, N.
    T2Offset,
    /// `sensors.t2_gain`: T2 gain relative to T1.
    T2Gain,
}

/// How a parameter enters the prediction (decides how its sensitivity is computed).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Role {
    /// Inside `FrictionLaw::t2_n` (sensitivity by central differences of the law).
    Law,
    /// The load-memory time constant (sensitivity through the memory recursion).
    Tau,
    /// Shifts the true T1.
    T1Offset,
    /// Adds to the measured T2.
    T2Offset,
    /// Multiplies the measured T2.
    T2Gain,
}

impl Param {
    /// Every parameter.
    pub const ALL: [Param; 13] = [
        Param::Mu,
        Param::TensionExponent,
        Param::BendingB,
        Param::MuChangePer100s,
        Param::MuChangePerRun,
        Param::MuChangePerMm,
        Param::MuChangePerV,
        Param::MuLogSlopePerRad,
        Param::HeatPerNs,
        Param::HeatTauS,
        Param::T1Offset,
        Param::T2Offset,
        Param::T2Gain,
    ];

    /// Short name used in JSON and reports.
    pub const fn name(self) -> &'static str {
        match self {
            Param::Mu => "mu",
            Param::TensionExponent => "n",
            Param::BendingB => "b_nm2",
            Param::MuChangePer100s => "mu_change_per_100s",
            Param::MuChangePerRun => "mu_change_per_run",
            Param::MuChangePerMm => "mu_change_per_mm",
            Param::MuChangePerV => "mu_change_per_v",
            Param::MuLogSlopePerRad => "mu_log_slope_per_rad",
            Param::HeatPerNs => "heat_per_ns",
            Param::HeatTauS => "heat_tau_s",
            Param::T1Offset => "t1_offset_n",
            Param::T2Offset => "t2_offset_n",
            Param::T2Gain => "t2_gain",
        }
    }

    /// The value in `model`.
    pub fn get(self, m: &Model) -> f64 {
        match self {
            Param::Mu => m.law.mu,
            Param::TensionExponent => m.law.tension_exponent,
            Param::BendingB => m.law.bending_b_nm2,
            Param::MuChangePer100s => m.law.mu_change_per_100s,
            Param::MuChangePerRun => m.law.mu_change_per_run,
            Param::MuChangePerMm => m.law.mu_change_per_mm,
            Param::MuChangePerV => m.law.mu_change_per_v,
            Param::MuLogSlopePerRad => m.law.mu_log_slope_per_rad,
            Param::HeatPerNs => m.law.heat_per_ns,
            Param::HeatTauS => m.law.heat_tau_s,
            Param::T1Offset => m.sensors.t1_offset_n,
            Param::T2Offset => m.sensors.t2_offset_n,
            Param::T2Gain => m.sensors.t2_gain,
        }
    }

    /// Set the value in `model`.
    pub fn set(self, m: &mut Model, v: f64) {
        match self {
            Param::Mu => m.law.mu = v,
            Param::TensionExponent => m.law.tension_exponent = v,
            Param::BendingB => m.law.bending_b_nm2 = v,
            Param::MuChangePer100s => m.law.mu_change_per_100s = v,
            Param::MuChangePerRun => m.law.mu_change_per_run = v,
            Param::MuChangePerMm => m.law.mu_change_per_mm = v,
            Param::MuChangePerV => m.law.mu_change_per_v = v,
            Param::MuLogSlopePerRad => m.law.mu_log_slope_per_rad = v,
            Param::HeatPerNs => m.law.heat_per_ns = v,
            Param::HeatTauS => m.law.heat_tau_s = v,
            Param::T1Offset => m.sensors.t1_offset_n = v,
            Param::T2Offset => m.sensors.t2_offset_n = v,
            Param::T2Gain => m.sensors.t2_gain = v,
        }
    }

    /// The parameter behind a catalogue effect (`None` for `none`): the model scalar its entry
    /// names.
    pub fn from_effect(kind: EffectKind) -> Option<Param> {
        if kind == EffectKind::None {
            return None;
        }
        Param::from_name(kind.entry().population.scalar)
    }

    /// The parameter of this name.
    pub fn from_name(name: &str) -> Option<Param> {
        Param::ALL.into_iter().find(|p| p.name() == name)
    }

    /// A natural transform for this parameter (`Log` for the positive ones).
    pub fn default_transform(self) -> Transform {
        match self {
            Param::Mu | Param::HeatTauS | Param::T2Gain | Param::HeatPerNs => Transform::Log,
            Param::BendingB => Transform::Log,
            Param::TensionExponent => Transform::Logistic { lo: 0.3, hi: 1.7 },
            _ => Transform::Identity,
        }
    }

    pub(crate) fn role(self) -> Role {
        match self {
            Param::HeatTauS => Role::Tau,
            Param::T1Offset => Role::T1Offset,
            Param::T2Offset => Role::T2Offset,
            Param::T2Gain => Role::T2Gain,
            _ => Role::Law,
        }
    }

    /// A typical magnitude, to size finite-difference steps.
    pub(crate) fn scale(self) -> f64 {
        match self {
            Param::Mu => 0.1,
            Param::TensionExponent => 1.0,
            Param::BendingB => 1e-5,
            Param::HeatPerNs => 1e-3,
            Param::MuChangePerMm => 1e-3,
            _ => 0.01,
        }
    }
}

impl std::fmt::Display for Param {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Map from an internal coordinate θ (any real) to a model value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Transform {
    /// value = θ.
    Identity,
    /// value = exp(θ) (positive).
    Log,
    /// value = lo + (hi − lo)/(1 + exp(−θ)) (inside (lo, hi)).
    Logistic {
        /// Lower bound.
        lo: f64,
        /// Upper bound.
        hi: f64,
    },
}

impl Transform {
    /// Model value of θ.
    pub fn value(self, theta: f64) -> f64 {
        match self {
            Transform::Identity => theta,
            Transform::Log => theta.exp(),
            Transform::Logistic { lo, hi } => lo + (hi - lo) / (1.0 + (-theta).exp()),
        }
    }

    /// d value / d θ.
    pub fn derivative(self, theta: f64) -> f64 {
        match self {
            Transform::Identity => 1.0,
            Transform::Log => theta.exp(),
            Transform::Logistic { lo, hi } => {
                let s = 1.0 / (1.0 + (-theta).exp());
                (hi - lo) * s * (1.0 - s)
            }
        }
    }

    /// θ of a model value (clamped into the transform's range).
    pub fn internal(self, value: f64) -> f64 {
        match self {
            Transform::Identity => value,
            Transform::Log => value.max(1e-300).ln(),
            Transform::Logistic { lo, hi } => {
                let s = ((value - lo) / (hi - lo)).clamp(1e-12, 1.0 - 1e-12);
                (s / (1.0 - s)).ln()
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transforms_round_trip() {
        for t in [
            Transform::Identity,
            Transform::Log,
            Transform::Logistic { lo: 0.3, hi: 1.7 },
        ] {
            for v in [0.4, 0.9, 1.2] {
                assert!((t.value(t.internal(v)) - v).abs() < 1e-12);
                let th = t.internal(v);
                let num = (t.value(th + 1e-6) - t.value(th - 1e-6)) / 2e-6;
                assert!((num - t.derivative(th)).abs() < 1e-8);
            }
        }
    }

    #[test]
    fn get_set_every_param_and_effects_map() {
        for p in Param::ALL {
            let mut m = Model::euler_eytelwein(0.1);
            p.set(&mut m, 0.4321);
            assert_eq!(p.get(&m), 0.4321, "{p}");
        }
        for kind in EffectKind::ALL.into_iter().skip(1) {
            let p = Param::from_effect(kind).unwrap();
            let m = Model::euler_eytelwein(0.1)
                .with_effect(capstan_friction::Effect { kind, value: 0.77 });
            let scale = kind.entry().population.value_per_scalar;
            assert!((p.get(&m) * scale - 0.77).abs() < 1e-15, "{kind}");
        }
    }
}
