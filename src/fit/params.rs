//! Which numbers of a [`capstan_friction::Model`] a fit may move, and how.
//!
//! A fit works in *internal coordinates* θ (unbounded reals); each free parameter maps θ to its
//! model value through a [`Transform`] (bounds by reparametrisation: `Log` keeps a value
//! positive, `Logistic` keeps it in an interval). A [`ModelSpec`] is a base model, the list of
//! free parameters and, optionally, a per-group random effect added to the internal coordinate
//! of one of them (on a `Log` parameter this is a multiplicative factor exp(u), e.g. a per-cord
//! log-mu offset).

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

    /// The parameter behind a catalogue effect (`None` for `none`).
    pub fn from_effect(kind: EffectKind) -> Option<Param> {
        Some(match kind {
            EffectKind::None => return None,
            EffectKind::PressureFriction => Param::TensionExponent,
            EffectKind::BendingStiffness => Param::BendingB,
            EffectKind::T1Offset => Param::T1Offset,
            EffectKind::T2Offset => Param::T2Offset,
            EffectKind::SensorGain => Param::T2Gain,
            EffectKind::ThermalDrift => Param::MuChangePer100s,
            EffectKind::Wear => Param::MuChangePerRun,
            EffectKind::DiameterDependence => Param::MuChangePerMm,
            EffectKind::SpeedDependence => Param::MuChangePerV,
        })
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

/// A parameter the fit moves, with its transform.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FreeParam {
    /// Which number of the model.
    pub param: Param,
    /// How θ maps onto it.
    pub transform: Transform,
}

/// A model to fit: a base [`Model`] (fixed values, and start values of the free ones), the free
/// parameters, and optionally a per-group random effect on one of them.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelSpec {
    /// Name for reports.
    pub name: String,
    /// Fixed values and start values.
    pub base: Model,
    /// Parameters the fit moves, in θ order.
    pub free: Vec<FreeParam>,
    /// Index into `free` of the parameter that carries a per-group random effect u_g
    /// (θ_g = θ + u_g, u_g ~ N(0, σ_u²)), if any.
    pub random: Option<usize>,
    /// A constraint that sets some model values from others after θ is applied.
    pub tie: Option<Tie>,
}

/// A constraint between model values, applied after the free parameters are set.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Tie {
    /// Howell's power law in line pressure T/R: dT/dθ = a·R^(1−n)·Tⁿ, so mu scales as
    /// (d/12.7 mm)^(1−n). The law's linear diameter factor 1 + c·(d − 12.7) is set to match it
    /// exactly at 12.7 mm and at `other_mm` (the data's second diameter).
    HowellDiameter {
        /// The other capstan diameter of the data, mm.
        other_mm: f64,
    },
}

impl Tie {
    fn apply(self, m: &mut Model) {
        match self {
            Tie::HowellDiameter { other_mm } => {
                let r = other_mm / capstan_friction::REF_DIAMETER_MM;
                m.law.mu_change_per_mm = (r.powf(1.0 - m.law.tension_exponent) - 1.0)
                    / (other_mm - capstan_friction::REF_DIAMETER_MM);
            }
        }
    }
}

impl ModelSpec {
    /// A spec with nothing free.
    pub fn new(name: impl Into<String>, base: Model) -> Self {
        ModelSpec {
            name: name.into(),
            base,
            free: Vec::new(),
            random: None,
            tie: None,
        }
    }

    /// Free `param` (starting from its value in the base model) with its default transform.
    pub fn free(self, param: Param) -> Self {
        let t = param.default_transform();
        self.free_with(param, t)
    }

    /// Free `param` with a chosen transform.
    pub fn free_with(mut self, param: Param, transform: Transform) -> Self {
        if let Some(f) = self.free.iter_mut().find(|f| f.param == param) {
            f.transform = transform;
        } else {
            self.free.push(FreeParam { param, transform });
        }
        self
    }

    /// Set a value in the base model (a fixed value, or the start of a free one).
    pub fn with_value(mut self, param: Param, value: f64) -> Self {
        param.set(&mut self.base, value);
        self
    }

    /// Put a per-group random effect on the internal coordinate of `param` (which must be
    /// free; on a `Log` parameter this is a multiplicative factor per group).
    ///
    /// # Panics
    /// If `param` is not free (a programming error, not a data error).
    pub fn random_effect_on(mut self, param: Param) -> Self {
        let i = self
            .free
            .iter()
            .position(|f| f.param == param)
            .expect("the random-effect parameter must be free");
        self.random = Some(i);
        self
    }

    /// Fix `param` at `value` (removing it from the free list if it was free).
    pub fn fix(mut self, param: Param, value: f64) -> Self {
        if let Some(i) = self.free.iter().position(|f| f.param == param) {
            self.free.remove(i);
            self.random = match self.random {
                Some(r) if r == i => None,
                Some(r) if r > i => Some(r - 1),
                r => r,
            };
        }
        param.set(&mut self.base, value);
        self
    }

    /// The same spec starting from `model`'s values (e.g. a previous fit).
    pub fn starting_from(mut self, model: capstan_friction::Model) -> Self {
        self.base = model;
        self
    }

    /// The same spec without the random effect.
    pub fn without_random(mut self) -> Self {
        self.random = None;
        self
    }

    /// Rename.
    pub fn named(mut self, name: impl Into<String>) -> Self {
        self.name = name.into();
        self
    }

    /// Number of fixed (free, population-level) parameters.
    pub fn n_fixed(&self) -> usize {
        self.free.len()
    }

    /// Start θ from the base model.
    pub fn start(&self) -> Vec<f64> {
        self.free
            .iter()
            .map(|f| f.transform.internal(f.param.get(&self.base)))
            .collect()
    }

    /// The model at θ, with group offset `u` on the random-effect parameter.
    pub fn model(&self, theta: &[f64], u: f64) -> Model {
        let mut m = self.base;
        for (i, (f, &t)) in self.free.iter().zip(theta).enumerate() {
            let t = if Some(i) == self.random { t + u } else { t };
            f.param.set(&mut m, f.transform.value(t));
        }
        if let Some(tie) = self.tie {
            tie.apply(&mut m);
        }
        m
    }

    /// Add a tie (its sensitivities are then taken by differences in θ).
    pub fn with_tie(mut self, tie: Tie) -> Self {
        self.tie = Some(tie);
        self
    }

    /// d value / d θ for every free parameter at θ (group offset `u` included).
    pub(crate) fn derivatives(&self, theta: &[f64], u: f64) -> Vec<f64> {
        self.free
            .iter()
            .zip(theta)
            .enumerate()
            .map(|(i, (f, &t))| {
                let t = if Some(i) == self.random { t + u } else { t };
                f.transform.derivative(t)
            })
            .collect()
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
            assert_eq!(p.get(&m), 0.77, "{kind}");
        }
    }

    #[test]
    fn random_effect_shifts_the_internal_coordinate() {
        let spec = ModelSpec::new("t", Model::euler_eytelwein(0.12))
            .free(Param::Mu)
            .free(Param::T1Offset)
            .random_effect_on(Param::Mu);
        let th = spec.start();
        let m = spec.model(&th, 0.1);
        assert!((m.law.mu - 0.12 * 0.1f64.exp()).abs() < 1e-12);
        assert_eq!(m.sensors.t1_offset_n, 0.0);
    }
}
