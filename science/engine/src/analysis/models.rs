//! The model specs of the analysis: the baseline, and the extended model built from the causes
//! the evidence engine names.

use crate::evidence::Assessment;
use crate::fit::{ModelSpec, Param, Transform};
use capstan_physics::{Effect, EffectKind, Model};

/// Euler-Eytelwein with one free mu.
pub fn baseline() -> ModelSpec {
    ModelSpec::new("baseline", Model::euler_eytelwein(0.115)).free(Param::Mu)
}

/// How a named cause enters the population model: its parameter and transform.
fn free_param(kind: EffectKind) -> Option<(Param, Transform)> {
    Some((Param::from_effect(kind)?, kind.entry().population.transform))
}

/// The extended model: Euler-Eytelwein with every cause the engine names, each at the value
/// it found (the start of the fit), one population mu and a per-cord random log-mu (mixed).
/// Contact heating keeps the catalogue's short memory (τ = `HEAT_TAU_S`). Without named
/// causes it is Euler-Eytelwein with the cord effects.
pub fn extended(a: &Assessment) -> ModelSpec {
    population(a).random_effect_on(Param::Mu)
}

/// The population-averaged model: the named causes and one mu for every cord, by least
/// squares in T2 — what a new cord is predicted with (its own mu is unknown, so the curve to
/// use is the average over cords, not the typical cord's).
pub fn population(a: &Assessment) -> ModelSpec {
    let mu0 = crate::fit::stats::mean(&a.fit.mu);
    let mut base = Model::euler_eytelwein(if mu0.is_finite() { mu0 } else { 0.115 });
    let causes = a.selected_evidence();
    for e in &causes {
        Effect {
            kind: e.kind,
            value: e.value,
        }
        .apply(&mut base);
    }
    for e in &causes {
        (e.kind.entry().prepare)(&mut base);
    }
    let mut spec = ModelSpec::new("extended", base).free(Param::Mu);
    for e in &causes {
        if let Some((p, t)) = free_param(e.kind) {
            spec = spec.free_with(p, t);
        }
    }
    spec
}
