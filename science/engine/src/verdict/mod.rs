//! The one verdict layer: the evidence engine's assessment ([`crate::evidence`]) turned into
//! verdicts and their sentences, which `capstan diagnose` and `capstan analyze` both render.
//!
//! * the effects the data hold ([`Found`]: the engine's selected effects, with their evidence
//!   given the others) and the verdict on the set in one sentence ([`Verdicts::sentence`]:
//!   what the data hold, what is left unexplained, which rivals they cannot rule out, and on
//!   what structure);
//! * every mechanism of the catalogue with its verdict, decided by one rule for all
//!   ([`decide`]: ruled in, explained away, ruled out, not established, not testable), and its
//!   sentence made from that verdict ([`words`]).
//!
//! What is left over after the named causes is reported as unexplained, with its pattern,
//! rather than pinned on a cause.

mod decide;
pub mod words;

use crate::evidence::{Assessment, Level, Rival};
use capstan_physics::EffectKind;
pub use decide::{decide, Numbers, Verdict};
use serde::Serialize;
use serde_json::{json, Value};
use std::collections::BTreeMap;

/// One effect the data hold.
#[derive(Clone, Debug, Serialize)]
pub struct Found {
    /// Catalogue name.
    pub effect: &'static str,
    /// Its fitted catalogue parameter (with the other found effects in the model).
    pub parameters: BTreeMap<&'static str, f64>,
    /// Its standard error (cluster-robust).
    pub parameter_se: f64,
    /// ΔBIC of dropping it, given the other found effects (negative: the data want it).
    pub delta_bic_given_others: f64,
    /// Where its evidence comes from.
    pub level: Level,
}

/// The verdicts on an assessment: what `diagnose` and `analyze` render.
#[derive(Clone, Debug)]
pub struct Verdicts {
    /// The effects the data hold, strongest first.
    pub found: Vec<Found>,
    /// The verdict on the set in words.
    pub sentence: String,
    /// Every mechanism's verdict.
    pub mechanisms: Mechanisms,
}

/// The verdicts of an assessment.
pub fn of(a: &Assessment) -> Verdicts {
    let found: Vec<Found> = a
        .selected_evidence()
        .iter()
        .map(|e| Found {
            effect: e.effect,
            parameters: e.parameters.clone(),
            parameter_se: e.parameter_se,
            delta_bic_given_others: e.delta_bic,
            level: e.level,
        })
        .collect();
    let mut sentence = words::verdict(&found, &a.adequacy, &a.rivals);
    if let Some(caveat) = words::structure_caveat(&a.design.structure) {
        sentence = format!("{sentence} {caveat}");
    }
    Verdicts {
        found,
        sentence,
        mechanisms: mechanisms(a),
    }
}

/// One mechanism's verdict.
#[derive(Clone, Debug, Serialize)]
pub struct Mechanism {
    /// Catalogue name.
    pub name: &'static str,
    /// What it is, physically.
    pub title: &'static str,
    /// The verdict.
    pub verdict: Verdict,
    /// The rule that decided it.
    pub rule: &'static str,
    /// One sentence, made from the verdict and its numbers.
    pub summary: String,
    /// The numbers behind it (null when not testable).
    pub evidence: Option<Numbers>,
    /// Why it cannot be tested (empty otherwise).
    pub not_testable_reason: String,
    /// A named cause it could replace with a fit nearly as good (the engine's rivals), if any.
    pub rival: Option<Rival>,
    /// The effect.
    #[serde(skip)]
    pub kind: EffectKind,
}

/// A named cause.
#[derive(Clone, Debug, Serialize)]
pub struct Cause {
    /// Catalogue name.
    pub name: &'static str,
    /// What it is.
    pub description: &'static str,
    /// Its parameter, value and cluster-robust SE.
    pub evidence: Value,
}

/// What is left that no catalogue effect explains.
#[derive(Clone, Debug, Serialize)]
pub struct Unexplained {
    /// Structure is left.
    pub flag: bool,
    /// Its pattern, if one was found.
    pub pattern: Option<&'static str>,
    /// The adequacy check's sentence.
    pub sentence: String,
}

/// All verdicts.
#[derive(Clone, Debug, Serialize)]
pub struct Mechanisms {
    /// Every mechanism of the catalogue.
    pub tests: Vec<Mechanism>,
    /// The named causes (verdict `ruled_in`), strongest first.
    pub causes: Vec<Cause>,
    /// What is left unexplained.
    pub unexplained: Unexplained,
    /// The order in which the within-run causes came in, with their ΔBIC then.
    pub selection_path: Vec<(&'static str, f64)>,
    /// What this design cannot separate.
    pub protocol_limits: Vec<String>,
}

/// Every mechanism's verdict on an assessment.
fn mechanisms(a: &Assessment) -> Mechanisms {
    let named: Vec<EffectKind> = a.selected_evidence().iter().map(|e| e.kind).collect();
    let names: Vec<&str> = named.iter().map(|k| k.name()).collect();
    let tests: Vec<Mechanism> = EffectKind::ALL
        .into_iter()
        .skip(1)
        .map(|kind| {
            let (v, numbers) = decide(a, kind);
            let reason = a
                .not_testable
                .iter()
                .find(|n| n.effect == kind.name())
                .map_or(String::new(), |n| n.reason.clone());
            let others: Vec<&str> = names
                .iter()
                .copied()
                .filter(|n| *n != kind.name())
                .collect();
            // The strongest rival claim, if it could stand in place of a named cause.
            let rival = a.rivals.iter().find(|r| r.kind == kind).cloned();
            let mut summary = words::sentence(kind, v, numbers.as_ref(), &others, &reason);
            if let Some(r) = &rival {
                summary.push(' ');
                summary += &words::rival_sentences(std::slice::from_ref(r));
            }
            Mechanism {
                name: kind.name(),
                title: words::title(kind),
                verdict: v,
                rule: v.rule(),
                summary,
                evidence: numbers,
                not_testable_reason: reason,
                rival,
                kind,
            }
        })
        .collect();
    let causes = a
        .selected_evidence()
        .iter()
        .map(|e| Cause {
            name: e.effect,
            description: words::title(e.kind),
            evidence: json!({"parameters": e.parameters, "parameter_se": e.parameter_se, "delta_bic_given_others": e.delta_bic, "level": e.level}),
        })
        .collect();
    Mechanisms {
        tests,
        causes,
        unexplained: Unexplained {
            flag: a.adequacy.unexplained,
            pattern: a.adequacy.pattern,
            sentence: a.adequacy.sentence.clone(),
        },
        selection_path: a.path.iter().map(|(k, b)| (k.name(), *b)).collect(),
        protocol_limits: words::protocol_limits(&a.design, &named),
    }
}

impl Mechanisms {
    /// The mechanism called `name`.
    pub fn get(&self, name: &str) -> Option<&Mechanism> {
        self.tests.iter().find(|t| t.name == name)
    }

    /// The named causes' catalogue kinds.
    pub fn cause_kinds(&self) -> Vec<EffectKind> {
        self.tests
            .iter()
            .filter(|t| t.verdict == Verdict::RuledIn)
            .map(|t| t.kind)
            .collect()
    }
}
