//! A verdict for every mechanism of the catalogue, decided from the evidence engine's numbers by
//! one rule for all (the rule the engine names its effects by).

use crate::evidence::{candidates, Assessment, Evidence};
use capstan_physics::EffectKind;
use serde::Serialize;

/// What the data say about one mechanism.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// Named: its evidence given the other named causes is below its level's threshold and its
    /// size matters.
    RuledIn,
    /// Supported alone, but not once the named causes are in: it stood in for them.
    ExplainedAway,
    /// Its robust 95 % interval lies inside the region where it would not matter.
    RuledOut,
    /// Neither named nor excluded: a size that matters cannot be excluded.
    NotEstablished,
    /// The data cannot test it (a column is absent, or its covariate has one level).
    NotTestable,
}

impl Verdict {
    /// The verdict's name in JSON and in the report.
    pub fn name(self) -> &'static str {
        match self {
            Verdict::RuledIn => "ruled_in",
            Verdict::ExplainedAway => "explained_away",
            Verdict::RuledOut => "ruled_out",
            Verdict::NotEstablished => "not_established",
            Verdict::NotTestable => "not_testable",
        }
    }

    /// The rule that gives this verdict, in words.
    pub fn rule(self) -> &'static str {
        match self {
            Verdict::RuledIn => "ruled_in: selected by the evidence engine — its ΔBIC given the other named causes (cluster-robust quasi-likelihood; runs as clusters within runs, cords or runs between) is below its level's threshold and its size is outside the region of practical equivalence",
            Verdict::ExplainedAway => "explained_away: alone it would be named (ΔBIC below the threshold, a size that matters), but not once the named causes are in",
            Verdict::RuledOut => "ruled_out: not named, and its cluster-robust 95 % interval lies inside the region of practical equivalence with no effect",
            Verdict::NotEstablished => "not_established: not named, and its 95 % interval still reaches a size that matters",
            Verdict::NotTestable => "not_testable: the data have no variation it could show in",
        }
    }
}

/// The numbers behind a verdict.
#[derive(Clone, Debug, Serialize)]
pub struct Numbers {
    /// The catalogue parameter's name.
    pub parameter: &'static str,
    /// Its value given the named causes (or added to them).
    pub value: f64,
    /// Its cluster-robust standard error (null where none is defined).
    pub se: f64,
    /// At an edge of its range: its 95 % interval (from θ's).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub edge_interval: Option<(f64, f64)>,
    /// ΔBIC given the named causes (dropping it if named, adding it if not).
    pub delta_bic_given_causes: f64,
    /// ΔBIC alone (added to every run's own mu, nothing else).
    pub delta_bic_alone: f64,
    /// Its value alone.
    pub value_alone: f64,
    /// Half-width of the region of practical equivalence with no effect.
    pub relevance_width: f64,
    /// Where its evidence comes from.
    pub level: candidates::Level,
}

/// The verdict on `kind` and its numbers (None for `not_testable`).
pub fn decide(a: &Assessment, kind: EffectKind) -> (Verdict, Option<Numbers>) {
    let Some(given) = a.evidence_of(kind) else {
        return (Verdict::NotTestable, None);
    };
    let alone: Option<&Evidence> = a.alone.iter().find(|e| e.kind == kind);
    let d = &a.design;
    let numbers = Numbers {
        parameter: kind.parameter().unwrap_or(""),
        value: given.value,
        se: given.parameter_se,
        edge_interval: given.edge_interval,
        delta_bic_given_causes: given.delta_bic,
        delta_bic_alone: alone.map_or(f64::NAN, |e| e.delta_bic),
        value_alone: alone.map_or(f64::NAN, |e| e.value),
        relevance_width: candidates::relevance_width(kind, d),
        level: given.level,
    };
    let verdict = if given.selected {
        Verdict::RuledIn
    } else if alone.is_some_and(|e| e.supported) && !given.supported {
        Verdict::ExplainedAway
    } else if candidates::excluded(kind, given.value, given.parameter_se, d)
        || given
            .edge_interval
            .is_some_and(|(lo, hi)| candidates::inside_equivalence(kind, lo, hi, d))
    {
        Verdict::RuledOut
    } else {
        Verdict::NotEstablished
    };
    (verdict, Some(numbers))
}
