//! Why: every mechanism of the catalogue with its verdict, decided from the evidence engine
//! ([`crate::evidence`], the same statistics as `capstan diagnose`) by one rule for all
//! ([`verdict`]), and its sentence made from that verdict ([`words`]).
//!
//! The named causes are the engine's selected effects; what the engine's adequacy check finds
//! left over is reported as unexplained, with its pattern, rather than pinned on a cause.

pub mod verdict;
pub mod words;

use crate::evidence::{Assessment, Rival};
use capstan_friction::EffectKind;
use serde::Serialize;
use serde_json::{json, Value};
pub use verdict::{Numbers, Verdict};

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

/// The verdicts of an assessment.
pub fn run(a: &Assessment) -> Mechanisms {
    let named: Vec<EffectKind> = a.selected_evidence().iter().map(|e| e.kind).collect();
    let names: Vec<&str> = named.iter().map(|k| k.name()).collect();
    let tests: Vec<Mechanism> = EffectKind::ALL
        .into_iter()
        .skip(1)
        .map(|kind| {
            let (v, numbers) = verdict::decide(a, kind);
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
                summary += &crate::diagnose::words::rival_sentences(std::slice::from_ref(r));
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
