//! A model to fit: a base [`Model`], its free parameters (each with a [`Transform`]), an
//! optional per-group random effect, and an optional [`Tie`] between values.

use super::param::{Param, Transform};
use capstan_physics::Model;

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
                let r = other_mm / capstan_physics::REF_DIAMETER_MM;
                m.law.mu_change_per_mm = (r.powf(1.0 - m.law.tension_exponent) - 1.0)
                    / (other_mm - capstan_physics::REF_DIAMETER_MM);
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
    pub fn starting_from(mut self, model: capstan_physics::Model) -> Self {
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
