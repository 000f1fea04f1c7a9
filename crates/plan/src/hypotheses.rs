//! The hypotheses a data set leaves open, from its diagnosis: the effects it names (at their
//! fitted sizes), and the same set with one named effect swapped for each rival the engine
//! could not rule out (at the rival's fitted size). What cannot be simulated — effects the
//! design could not test, structure no catalogue effect explains — is listed, not guessed.

use capstan_engine::diagnose::Diagnosis;
use capstan_friction::{Effect, EffectKind};
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

/// The hypotheses of `d`: the named set first, then one per rival (duplicates dropped).
pub fn open_hypotheses(d: &Diagnosis) -> (Vec<Hypothesis>, Vec<NotSimulated>) {
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
    (all, not_simulated(d))
}

fn not_simulated(d: &Diagnosis) -> Vec<NotSimulated> {
    let mut v: Vec<NotSimulated> = (d.not_testable.iter())
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
                 hypotheses only (see `capstan discover`)",
                d.residual_pattern
                    .map(|p| format!(" (pattern: {p})"))
                    .unwrap_or_default()
            ),
        });
    }
    v
}
