//! The answer of `capstan discover`: what it proposes, declines and searched, as data (the JSON
//! contract of docs/README-discover.md), and how each is worded.

use crate::heldout::Ratio;
use crate::joint;
use crate::library::{ActsOn, Term, Var, LIBRARY};
use crate::screen::{self, Level};
use capstan_data::structure::StructureSummary;
use capstan_engine::evidence::adequacy::lof_p_equals;
use capstan_engine::evidence::adequacy::LackOfFit;
use capstan_engine::evidence::RIVAL_GAP;
use serde::Serialize;
use std::collections::BTreeMap;

/// A proposed term must leave no lack of fit against the replicate runs at this level.
pub const LOF_ALPHA: f64 = 0.01;

/// A library term that might explain the data as well as a proposed one.
#[derive(Clone, Debug, Serialize)]
pub struct Rival {
    /// Its name.
    pub name: &'static str,
    /// What it depends on.
    pub depends_on: &'static [Var],
    /// Its ΔBIC in the same search step.
    pub delta_bic: f64,
    /// Correlation of its column with the proposed term's (within runs, after the model).
    pub correlation: Option<f64>,
}

/// A proposed term.
#[derive(Clone, Debug, Serialize)]
pub struct Proposed {
    /// Library name.
    pub name: &'static str,
    /// Formula (θ = 0 is off).
    pub formula: &'static str,
    /// Where it acts.
    pub acts_on: ActsOn,
    /// What it depends on.
    pub depends_on: &'static [Var],
    /// Its parameter (first-order estimate).
    pub parameters: BTreeMap<&'static str, f64>,
    /// Its cluster-robust standard error.
    pub parameter_se: BTreeMap<&'static str, f64>,
    /// Its parameter's units.
    pub units: &'static str,
    /// ΔBIC given the catalogue effects and any term proposed before it (no search penalty).
    pub delta_bic_given_others: f64,
    /// Share of whole-cord resamples in which it is the search's pick and passes the bar.
    pub stability: f64,
    /// Held-out RMSE with it over without it.
    pub loco_rmse_ratio: Ratio,
    /// The held-out upper end is below 1: shown to predict new cords better.
    pub shown_to_predict_better: bool,
    /// Where its evidence comes from.
    pub level: Level,
    /// Its physical reading.
    pub reading: &'static str,
    /// Where the physics comes from.
    pub source: &'static str,
    /// Lack of fit against the replicate runs with it in (None: not testable).
    pub lack_of_fit_after: Option<LackOfFit>,
    /// The lack of fit stays significant with it, but it removes most of its systematic part
    /// (`Options::min_share_resolved`): proposed with "unexplained" kept.
    pub partial: bool,
    /// Its evidence on the replicate cells' means: the replicate gate it passed (None:
    /// between-level, or the gate could not be computed, see `replicate_gate_not_applied`).
    pub replicate: Option<crate::replicate::Replicate>,
    /// Why a within-run term was proposed without the replicate gate (None: it passed it, or
    /// it is between-level, where the gate does not apply).
    pub replicate_gate_not_applied: Option<&'static str>,
    /// Library terms within the rival gap of it.
    pub rivals: Vec<Rival>,
    /// The catalogue effect it takes the place of (the joint search), if any.
    pub displaced: Option<joint::Displaced>,
    /// The catalogue effect the engine did not select that it comes with (the joint search's
    /// restores), if any.
    pub restored: Option<joint::Displaced>,
    /// The catalogue the engine selects with it (and the terms before it) taken out of the
    /// data, when that differs from the catalogue as selected (None: the same).
    pub catalogue_given: Option<Vec<&'static str>>,
    /// How to word it.
    pub words: String,
}

/// A term the search looked at closely and did not propose, and why.
#[derive(Clone, Debug, Serialize)]
pub struct Declined {
    /// Library name.
    pub name: &'static str,
    /// ΔBIC given the others.
    pub delta_bic: f64,
    /// Its stability, if it got that far.
    pub stability: Option<f64>,
    /// Its held-out ratio, if it got that far.
    pub loco_rmse_ratio: Option<Ratio>,
    /// The catalogue effect it was tried in place of (the joint search), if any.
    pub displaced: Option<joint::Displaced>,
    /// Why not.
    pub reason: String,
}

/// A term that could not be tested on these data.
#[derive(Clone, Debug, Serialize)]
pub struct NotTestable {
    /// Library name.
    pub name: &'static str,
    /// Why.
    pub reason: &'static str,
}

/// The data set read.
#[derive(Clone, Debug, Serialize)]
pub struct DataInfo {
    /// Where it came from.
    pub source: String,
    /// Rows.
    pub rows: usize,
    /// Its structure, and how each level was found.
    pub structure: StructureSummary,
    /// What the data checks warned about, as the command that read the data gives them
    /// (`None`: not given, and not in the JSON).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub warnings: Option<Vec<String>>,
}

/// How the search was paid for.
#[derive(Clone, Debug, Serialize)]
pub struct Search {
    /// Terms in the library.
    pub library_size: usize,
    /// Terms testable on these data.
    pub tried: usize,
    /// The engine's ΔBIC threshold.
    pub threshold: f64,
    /// Extended-BIC γ.
    pub gamma: f64,
    /// The bar the first term had to pass (ΔBIC below this).
    pub first_bar: f64,
    /// Models tried at each step: every term added, and in place of each displaceable effect.
    pub models_per_step: f64,
    /// The within-run catalogue effects a term may take the place of (the joint search).
    pub displaceable: Vec<&'static str>,
    /// The within-run catalogue effects the engine tested and did not select, each of which a
    /// term may come with (the joint search's restores).
    pub restorable: Vec<&'static str>,
    /// Cord resamples of the stability (None: too few cords to resample, see `cord_checks`).
    pub resamples: Option<usize>,
    /// Cords in the data set.
    pub cords: usize,
    /// Why stability and the held-out gain were not computed (None: they were).
    pub cord_checks: Option<String>,
    /// Least stability.
    pub min_stability: f64,
    /// Every testable term's screen given the catalogue, best first.
    pub screen: Vec<ScreenRow>,
}

/// One term's screen given the catalogue.
#[derive(Clone, Debug, Serialize)]
pub struct ScreenRow {
    /// Library name.
    pub name: &'static str,
    /// Where its evidence comes from.
    pub level: Level,
    /// ΔBIC given the catalogue (before the search penalty).
    pub delta_bic: f64,
    /// θ̂ (first order).
    pub theta: f64,
    /// Its cluster-robust standard error (None: fewer than 3 runs, no run-clustered error).
    pub se: Option<f64>,
    /// θ̂ keeps the term's physical sign.
    pub sign_ok: bool,
    /// Share of its column the catalogue's columns explain within runs (1 − 1/VIF).
    pub r2_model: f64,
    /// Its evidence on the replicate cells' means (None: between-level, or no replicates).
    pub replicate: Option<crate::replicate::Replicate>,
}

/// The answer of `capstan discover`.
#[derive(Clone, Debug, Serialize)]
pub struct Discovery {
    /// The data set and its structure.
    pub data: DataInfo,
    /// The catalogue effects the engine selected.
    pub catalogue_effects: Vec<&'static str>,
    /// The catalogue the engine selects with the proposed terms taken out of the data, when
    /// that differs from `catalogue_effects` (None: the same, or nothing proposed).
    pub catalogue_given_terms: Option<Vec<&'static str>>,
    /// The terms proposed (empty: nothing in the library explains what is left).
    pub terms: Vec<Proposed>,
    /// Structure is still left after the proposed terms: the lack of fit against the replicate
    /// runs after the last one (or the catalogue's decision when none is proposed). None: it
    /// could not be tested (no replicate runs, or they agree exactly).
    pub unexplained_after: Option<bool>,
    /// The pattern of what is left (the catalogue fit's residuals), if anything is; None also
    /// when a proposed term depends on that pattern's variable (it was not re-tested).
    pub residual_pattern: Option<&'static str>,
    /// The answer in words.
    pub verdict: String,
    /// The lack of fit the catalogue leaves.
    pub lack_of_fit_before: Option<LackOfFit>,
    /// Terms looked at closely and not proposed.
    pub declined: Vec<Declined>,
    /// Terms not testable here.
    pub not_testable: Vec<NotTestable>,
    /// The search.
    pub search: Search,
    /// Wall time, s.
    pub elapsed_s: f64,
    /// Where the answer came from (program, commit, the input's SHA-256, the command line),
    /// as the command that prints it gives it (`None`: not given, and not in the JSON).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub provenance: Option<capstan_data::Provenance>,
}

impl Discovery {
    /// One JSON object: pretty, the keys of every object sorted (as `capstan discover --json`
    /// has always written it), whatever the order of the fields here.
    pub fn to_json(&self) -> String {
        serde_json::to_value(self)
            .and_then(|v| serde_json::to_string_pretty(&v))
            .unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
    }
}

/// The answer's row of a first-step screen.
pub(crate) fn screen_row(s: &screen::Screen) -> ScreenRow {
    ScreenRow {
        name: LIBRARY[s.term].name,
        level: s.level,
        delta_bic: s.delta_bic,
        theta: s.theta,
        se: Some(s.se).filter(|v| v.is_finite()),
        sign_ok: s.sign_ok,
        r2_model: s.r2_model,
        replicate: s.replicate.clone(),
    }
}

/// The catalogue effect a swap's term takes the place of.
pub(crate) fn displaced(alt: &joint::Alternative<'_>, s: joint::Swap) -> joint::Displaced {
    joint::Displaced {
        effect: alt.dropped.name(),
        effect_delta_bic: alt.dropped_delta_bic,
        delta_bic_swap: s.delta_bic,
    }
}

pub(crate) fn decline(
    t: &Term,
    s: &screen::Screen,
    stability: Option<f64>,
    ratio: Option<Ratio>,
    reason: String,
) -> Declined {
    Declined {
        name: t.name,
        delta_bic: s.delta_bic,
        stability,
        loco_rmse_ratio: ratio,
        displaced: None,
        reason,
    }
}

/// Why a within-run term's replicate gate could not be computed (the gate returns nothing).
const NO_GATE: &str = "fewer than 4 replicate cells (a cell is a cord's step seen by two runs or more; with one run per cord there are none), so the run-to-run wander of mu is not ruled out as what it fits (without the gate, a false term was proposed in 2 to 3 of 12 catalogue-only planted sets)";

/// A parameter's unit after its value: none for a dimensionless one ("1").
fn unit_words(units: &str) -> String {
    match units {
        "1" | "" => String::new(),
        u => format!(" {u}"),
    }
}

pub(crate) fn proposed(
    t: &'static Term,
    s: &screen::Screen,
    (stab, ratio): (f64, Ratio),
    lof: Option<LackOfFit>,
    rivals: Vec<Rival>,
    (displaced, given): (Option<(joint::Displaced, joint::Change)>, &str),
) -> Proposed {
    let shown = ratio.ci95.hi < 1.0;
    let rival_words = if rivals.is_empty() {
        String::new()
    } else {
        let names: Vec<&str> = rivals.iter().map(|r| r.name).collect();
        format!(
            " The data cannot tell it from {} (within {RIVAL_GAP:.0} BIC units).",
            names.join(", ")
        )
    };
    let (displaced, restored) = match displaced {
        Some((x, joint::Change::Restored)) => (None, Some(x)),
        Some((x, joint::Change::Dropped)) => (Some(x), None),
        None => (None, None),
    };
    let displace_words = displaced.as_ref().map_or(String::new(), |x| {
        format!(
            " It takes the place of the catalogue's {} (ΔBIC of the swap {:.1} against the catalogue as selected).",
            x.effect, x.delta_bic_swap
        )
    }) + &restored.as_ref().map_or(String::new(), |x| {
        format!(
            " It comes with the catalogue's {}, which the engine alone did not select (ΔBIC {:+.1} given its selection; of the catalogue with both {:.1} against the catalogue as selected).",
            x.effect, x.effect_delta_bic, x.delta_bic_swap
        )
    });
    let no_gate = (s.level == Level::WithinRun && s.replicate.is_none()).then_some(NO_GATE);
    let gate_words = no_gate.map_or(String::new(), |why| {
        format!(" The replicate gate was not applied: {why}.")
    });
    let words = format!(
        "Discovered, not an established cause: {} ({}; {} = {:.4} ± {:.4}{}), ΔBIC {:.1} given {given}, chosen in {:.0} % of cord resamples; held-out RMSE ratio {:.3} (95 % {:.3}–{:.3}){}.{}",
        t.name,
        t.reading,
        t.parameter,
        s.theta,
        s.se,
        unit_words(t.units),
        s.delta_bic,
        100.0 * stab,
        ratio.value,
        ratio.ci95.lo,
        ratio.ci95.hi,
        if shown { ": shown to predict new cords better" } else { ": not shown to predict new cords better" },
        rival_words
    ) + &displace_words
        + &gate_words;
    Proposed {
        name: t.name,
        formula: t.formula,
        acts_on: t.acts_on,
        depends_on: t.depends_on,
        parameters: BTreeMap::from([(t.parameter, s.theta)]),
        parameter_se: BTreeMap::from([(t.parameter, s.se)]),
        units: t.units,
        delta_bic_given_others: s.delta_bic,
        stability: stab,
        loco_rmse_ratio: ratio,
        shown_to_predict_better: shown,
        level: s.level,
        reading: t.reading,
        source: t.source,
        lack_of_fit_after: lof,
        partial: false,
        replicate: s.replicate.clone(),
        replicate_gate_not_applied: no_gate,
        rivals,
        displaced,
        restored,
        catalogue_given: None,
        words,
    }
}

pub(crate) fn verdict_words(
    terms: &[Proposed],
    (unexplained, pattern): (Option<bool>, Option<&str>),
    (lof_before, lof_last): (&Option<LackOfFit>, Option<&LackOfFit>),
    declined: &[Declined],
) -> String {
    if !terms.is_empty() {
        let names: Vec<String> = terms
            .iter()
            .map(|t| match t.replicate_gate_not_applied {
                Some(_) => format!("{} (without the replicate gate)", t.name),
                None => t.name.to_string(),
            })
            .collect();
        let with = if terms.len() == 1 { "it" } else { "them" };
        let left = match (unexplained, lof_last) {
            (Some(true), _) => match pattern {
                Some(p) => format!(" Structure is still left (pattern: {p})."),
                None => format!(" Structure is still left with {with} (its pattern was not re-tested: the catalogue's is what a proposed term fits)."),
            },
            (Some(false), Some(l)) if lof_before.as_ref().is_some_and(|b| b.p < LOF_ALPHA) => format!(
                " With {with}, the lack of fit against the replicate runs is resolved (p {}).",
                lof_p_equals(l.p)
            ),
            (Some(false), Some(l)) => format!(
                " No significant lack of fit against the replicate runs is left with {with} (p {}); the catalogue left none significant either.",
                lof_p_equals(l.p)
            ),
            _ => format!(" Whether structure is left with {with} cannot be tested: {NO_LOF}."),
        };
        return format!(
            "Discovered (a candidate to test, not an established cause): {}.{left}",
            names.join(" + ")
        );
    }
    let why = declined.first().map_or(String::new(), |d| {
        format!(
            " The strongest candidate, {}, was not proposed: {}.",
            d.name, d.reason
        )
    });
    match unexplained {
        Some(true) => format!(
            "Nothing in the library explains what the catalogue leaves (pattern: {}).{why}",
            pattern.unwrap_or("cells")
        ),
        Some(false) if lof_before.is_none() => format!(
            "Nothing to add: no library term earns its evidence beyond the catalogue (the lack of fit against the replicate runs cannot be tested: {NO_LOF}; the tests of the residuals against T1, time and wrap find nothing that matters).{why}"
        ),
        Some(false) => format!(
            "Nothing to add: no library term earns its evidence beyond the catalogue.{why}"
        ),
        None => format!(
            "Nothing to add that can be judged: no library term earns its evidence beyond the catalogue, and what the catalogue leaves cannot be tested ({NO_LOF}).{why}"
        ),
    }
}

/// Why the lack of fit against the replicate runs could not be tested.
const NO_LOF: &str = "no cord step is seen by two runs or more, or the runs that repeat one agree exactly, so there is no pure error to judge the model against";
