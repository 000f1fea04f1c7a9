//! The hypotheses a data set leaves open, from its diagnosis: the effects it names (at their
//! fitted sizes), and the same set with one named effect swapped for each rival the engine
//! could not rule out (at the rival's fitted size); and the named set with each effect the
//! design could not test, at the smallest size of the catalogue's planted cases that matters
//! (its entry's `cases.care`, spread over the span of the design that would test it). What
//! cannot be simulated — structure no catalogue effect explains, an effect no candidate could
//! test — is listed, not guessed.

use crate::candidates::{testing_design, Design};
use crate::world::{campaign, World};
use capstan_engine::diagnose::Diagnosis;
use capstan_physics::{Effect, EffectKind};
use serde::Serialize;

/// One hypothesis: a set of catalogue effects at given sizes (empty: Euler-Eytelwein).
#[derive(Clone, Debug, PartialEq)]
pub struct Hypothesis {
    /// The effects, in the order the diagnosis named them.
    pub effects: Vec<Effect>,
    /// Where it comes from: `named` or `rival of EFFECT`.
    pub origin: String,
}

impl Hypothesis {
    /// Its effects' names joined with `+` (`euler_eytelwein` when empty).
    pub fn label(&self) -> String {
        if self.effects.is_empty() {
            return "euler_eytelwein".to_string();
        }
        let names: Vec<&str> = self.effects.iter().map(|e| e.kind.name()).collect();
        names.join("+")
    }

    /// The effect kinds, sorted (the set a diagnosis must name).
    pub fn kinds(&self) -> Vec<EffectKind> {
        let mut k: Vec<EffectKind> = self.effects.iter().map(|e| e.kind).collect();
        k.sort();
        k
    }
}

impl Serialize for Hypothesis {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let effects: Vec<serde_json::Value> = (self.effects.iter())
            .map(|e| serde_json::json!({"effect": e.kind.name(), "value": e.value}))
            .collect();
        serde_json::json!({"label": self.label(), "origin": self.origin, "effects": effects})
            .serialize(s)
    }
}

/// What the data leave open but the planner cannot simulate, in words.
#[derive(Clone, Debug, Serialize)]
pub struct NotSimulated {
    /// The effect, or `unexplained`.
    pub what: String,
    /// Why it is open and why it is not simulated.
    pub why: String,
}

/// The effects `d` could not test that a campaign of some design could (by their entries'
/// conditions on the data's own design `current`).
pub fn untestable_kinds(d: &Diagnosis, current: &Design, world: &World) -> Vec<EffectKind> {
    (d.not_testable.iter())
        .filter_map(|n| EffectKind::from_name(n.effect))
        .filter(|k| current.untestable(*k, &world.protocol).is_some())
        .collect()
}

/// The hypotheses of `d` on the data's design `current`: the named set first, then one per
/// rival, then one per effect the design could not test (duplicates dropped).
pub fn open_hypotheses(
    d: &Diagnosis,
    current: &Design,
    world: &World,
) -> (Vec<Hypothesis>, Vec<NotSimulated>) {
    let named = Hypothesis {
        effects: d.found_effects(),
        origin: "named".to_string(),
    };
    let mut all = vec![named.clone()];
    for r in &d.rivals {
        let value = r
            .kind
            .parameter()
            .and_then(|p| r.parameters.get(p))
            .copied();
        let Some(value) = value.filter(|v| v.is_finite()) else {
            continue;
        };
        let effects = (named.effects.iter())
            .map(|e| match e.kind == r.instead_of_kind {
                true => Effect {
                    kind: r.kind,
                    value,
                },
                false => *e,
            })
            .collect();
        let h = Hypothesis {
            effects,
            origin: format!("rival of {}", r.instead_of),
        };
        if all.iter().all(|o| o.kinds() != h.kinds()) {
            all.push(h);
        }
    }
    let open = untestable_kinds(d, current, world);
    let testing = testing_design(current, &open, &world.protocol);
    let cfg = campaign(&testing, &named.effects, world, 0);
    let mut sized = Vec::new();
    for kind in open {
        if testing.untestable(kind, &world.protocol).is_some() {
            continue;
        }
        let value = capstan_validation::cases::smallest_that_matters(kind, &cfg);
        let reason = (d.not_testable.iter())
            .find(|n| n.effect == kind.name())
            .map_or(String::new(), |n| n.reason.clone());
        let mut effects = named.effects.clone();
        effects.push(Effect { kind, value });
        all.push(Hypothesis {
            effects,
            origin: format!(
                "not testable in these data ({reason}); at the smallest size of the catalogue's \
                 planted cases that matters ({} = {value:.4})",
                kind.parameter().unwrap_or("value")
            ),
        });
        sized.push(kind.name());
    }
    (all, not_simulated(d, &sized))
}

fn not_simulated(d: &Diagnosis, sized: &[&str]) -> Vec<NotSimulated> {
    let mut v: Vec<NotSimulated> = (d.not_testable.iter())
        .filter(|n| !sized.contains(&n.effect))
        .map(|n| NotSimulated {
            what: n.effect.to_string(),
            why: format!(
                "not testable in these data ({}); its size is unknown, so no campaign is \
                 simulated with it",
                n.reason
            ),
        })
        .collect();
    if d.unexplained {
        v.push(NotSimulated {
            what: "unexplained".to_string(),
            why: format!(
                "structure no catalogue effect explains{}; the planner simulates catalogue \
                 hypotheses only (the discovery search beyond the catalogue is capstan \
                 discover's, and analyze reports its terms under Discovered)",
                d.residual_pattern
                    .map(|p| format!(" (pattern: {p})"))
                    .unwrap_or_default()
            ),
        });
    }
    v
}
