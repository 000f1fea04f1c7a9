//! The scalars of a [`Model`] a fit may move ([`Param`]) and the maps from an unbounded
//! internal coordinate θ to their values ([`Transform`], the catalogue's own: each scalar's
//! row names its transform).

pub use capstan_physics::entry::Transform;
use capstan_physics::scalars::{index_of, Enters, SCALARS};
use capstan_physics::{EffectKind, Model};

/// One scalar of [`Model`] (friction law or sensor artefact): a row of `friction`'s
/// [`SCALARS`], which says its name, how to read and set it, how it enters a prediction, its
/// transform and size. The fitter lists none by hand.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Param(u8);

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

/// The parameter of the scalar named `name` (a compile-time error when there is none).
const fn named(name: &str) -> Param {
    Param(index_of(name) as u8)
}

// The parameters the engine's own model specs name (the rest it reaches through the entries).
#[allow(non_upper_case_globals)]
impl Param {
    /// `law.mu`: friction coefficient at the reference conditions.
    pub const Mu: Param = named("mu");
    /// `law.tension_exponent`: n of dT/dθ = k·Tⁿ.
    pub const TensionExponent: Param = named("n");
    /// `law.mu_change_per_100s`: drift of mu with time since the trigger.
    pub const MuChangePer100s: Param = named("mu_change_per_100s");
    /// `law.mu_log_slope_per_rad`: wrap dependence of ln mu (anchored at 540°).
    pub const MuLogSlopePerRad: Param = named("mu_log_slope_per_rad");
    /// `law.heat_per_ns`: contact heating, 1/(N s).
    pub const HeatPerNs: Param = named("heat_per_ns");
    /// `law.heat_tau_s`: memory time of the friction load, s.
    pub const HeatTauS: Param = named("heat_tau_s");
    /// `sensors.t1_offset_n`: T1 zero offset / T1-path loss, N.
    pub const T1Offset: Param = named("t1_offset_n");
    /// `sensors.t2_offset_n`: T2 zero offset, N.
    pub const T2Offset: Param = named("t2_offset_n");
    /// `sensors.t2_gain`: T2 gain relative to T1.
    pub const T2Gain: Param = named("t2_gain");
}

impl Param {
    /// Every parameter, in the table's order.
    pub const ALL: [Param; SCALARS.len()] = {
        let mut all = [Param(0); SCALARS.len()];
        let mut i = 0;
        while i < all.len() {
            all[i] = Param(i as u8);
            i += 1;
        }
        all
    };

    /// Short name used in JSON and reports.
    pub const fn name(self) -> &'static str {
        SCALARS[self.0 as usize].name
    }

    /// The value in `model`.
    pub fn get(self, m: &Model) -> f64 {
        (SCALARS[self.0 as usize].get)(m)
    }

    /// Set the value in `model`.
    pub fn set(self, m: &mut Model, v: f64) {
        (SCALARS[self.0 as usize].set)(m, v)
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
        SCALARS[self.0 as usize].transform
    }

    pub(crate) fn role(self) -> Role {
        match SCALARS[self.0 as usize].enters {
            Enters::Law => Role::Law,
            Enters::MemoryTime => Role::Tau,
            Enters::T1Offset => Role::T1Offset,
            Enters::T2Offset => Role::T2Offset,
            Enters::T2Gain => Role::T2Gain,
        }
    }

    /// A typical magnitude, to size finite-difference steps.
    pub(crate) fn scale(self) -> f64 {
        SCALARS[self.0 as usize].scale
    }
}

impl std::fmt::Display for Param {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
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
                .with_effect(capstan_physics::Effect { kind, value: 0.77 });
            let scale = kind.entry().population.value_per_scalar;
            assert!((p.get(&m) * scale - 0.77).abs() < 1e-15, "{kind}");
        }
    }
}
