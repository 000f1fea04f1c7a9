//! Is anything left? After the selected effects are fitted, the residuals are tested for the
//! structure no catalogue effect took up — each question against the units it varies over.
//!
//! * **Lack of fit against pure error** (Draper & Smith §2.1, with clustered replicates): the
//!   runs of a cord repeat the same steps, so the residuals of a cord × step cell scatter
//!   around their cell mean by the run-to-run error alone. F = MS_LOF/MS_PE with
//!   MS_LOF = Σ n_c·m_c²/(cells − cords − k) (each run's mu removes one mean per cord) and
//!   MS_PE = Σ(z − m_c)²/Σ(n_c − 1), on the standardised residuals z = r·√w; its p from sign
//!   flips of whole runs (the runs' residuals are serially correlated). Its size, the
//!   systematic part's RMS per observation (SS_LOF beyond what the flips give) over the pure
//!   error's, tells a pattern that matters from one that is merely detectable. It is taken
//!   twice: on the shared fit, and with every cord's own T2 zero and selected effects
//!   ([`super::cords`]). What the second no longer finds is cord-to-cord scatter of the model's
//!   own parameters (the rig re-hooks and re-zeroes every cord): said as such, not unexplained.
//! * **Between cords** ([`super::cords`]): every cord's parameters and residual shape against
//!   the wrap and the diameter, cords as units (t with G − 2 degrees of freedom, Bonferroni over
//!   the family); which parameters scatter from cord to cord beyond the runs' scatter.
//! * **Directed tests inside runs** ([`directed`]): the residuals beyond the cords' own
//!   parameters along T1 (asinh(T1/0.5 N) and its square), time inside runs, the step
//!   direction; cords as units where there are enough (Hotelling's T² over the cords'
//!   coefficients), else runs as clusters. They name the pattern that remains, and decide
//!   without replicates.
//!
//! `unexplained` is set when a pattern between cords is significant, or when the lack of fit
//! beyond the cords' own parameters is both significant and large; the sentence is generated
//! from that decision and the pattern found.

use super::cords::{cord_level, CordLevel};
use super::design::Design;
use super::within::{Weights, WithinFit};
use serde::Serialize;

mod common;
mod directed;
mod pure_error;

pub use common::CommonProfile;

use directed::directed_tests;
pub use pure_error::lack_of_fit;
use pure_error::pure_error;

/// The decision rule's constants.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct AdequacyRule {
    /// A test is significant below this p.
    pub alpha: f64,
    /// The systematic RMS over the noise's (pure-error test) at or above which a significant
    /// lack of fit is large.
    pub min_ratio: f64,
    /// The share of the residual variance a directed test explains at or above which it is
    /// large (used without replicates).
    pub min_r2: f64,
    /// The spread of an effect's per-wrap sizes (fraction of its common size) at or above
    /// which a significant inconstancy is large.
    pub min_spread: f64,
    /// A pattern between cords (a cord's parameters or residual shape against wrap or
    /// diameter, cords as units) is significant below this p, Bonferroni-adjusted over every
    /// such test (the family's level).
    pub alpha_between: f64,
    /// A parameter's scatter from cord to cord is supported below this p.
    pub alpha_random: f64,
}

impl Default for AdequacyRule {
    fn default() -> Self {
        AdequacyRule {
            alpha: 1e-3,
            min_ratio: 0.35,
            min_r2: 0.05,
            min_spread: 0.5,
            alpha_between: 0.01,
            alpha_random: 0.01,
        }
    }
}

/// The pure-error lack-of-fit test.
#[derive(Clone, Debug, Serialize)]
pub struct LackOfFit {
    /// Replicate cells used (with at least two runs).
    pub cells: usize,
    /// F = MS_LOF / MS_PE.
    pub f: f64,
    /// Degrees of freedom of the lack of fit.
    pub df_lof: f64,
    /// Degrees of freedom of the pure error.
    pub df_pe: f64,
    /// Upper-tail p of F (from the wild bootstrap).
    pub p: f64,
    /// `p` is the bootstrap's floor, 1/2000: no sign flip was as large, so p is at most this.
    pub p_at_floor: bool,
    /// RMS of the systematic part over the RMS of the pure error.
    pub systematic_ratio: f64,
    /// The replicated cells hold no more means than the parameters fitted to them (every
    /// cord's own, and the model's): no lack of fit can show, so the test says nothing.
    pub saturated: bool,
}

/// Do the selected effects have one size for all wraps? The same physics has the same size on
/// every cord; an effect that takes different sizes on different wraps stands in for something
/// else. Each cord's size ([`super::cords`]), averaged per wrap; the test is the cords' sizes
/// against the wrap, cords as units (the most significant effect's, Bonferroni-adjusted).
#[derive(Clone, Debug, Serialize)]
pub struct Constancy {
    /// Per effect: its size on each wrap, (wrap in degrees, value).
    pub by_wrap: Vec<(&'static str, Vec<(f64, f64)>)>,
    /// F (= t²) of the cords' sizes against the wrap.
    pub f: f64,
    /// 1.
    pub df1: f64,
    /// Cords − 2.
    pub df2: f64,
    /// p, Bonferroni-adjusted over the cord-level pattern tests.
    pub p: f64,
    /// The largest spread of one effect's per-wrap sizes around its common size, as a
    /// fraction of the common size's departure from no effect.
    pub spread: f64,
}

/// One directed test of the residuals.
#[derive(Clone, Debug, Serialize)]
pub struct Directed {
    /// What the residuals were tested against.
    pub structure: &'static str,
    /// F of the cluster-robust Wald statistic.
    pub f: f64,
    /// Its numerator degrees of freedom.
    pub df1: f64,
    /// Its denominator degrees of freedom (runs − q).
    pub df2: f64,
    /// Upper-tail p.
    pub p: f64,
    /// Share of the run-centred residual variance the structure explains (for wrap and
    /// diameter: of the best cord summary's variance between cords).
    pub partial_r2: f64,
    /// The units the test counts: `cords` or `runs`.
    pub unit: &'static str,
    /// How many.
    pub units: usize,
}

/// What is left after the selected effects.
#[derive(Clone, Debug, Serialize)]
pub struct Adequacy {
    /// Significant and large structure remains that no catalogue effect explains.
    pub unexplained: bool,
    /// The structure that explains most of what remains (`step_direction`, `t1_shape`,
    /// `time`, `wrap`, `diameter`, or `cells` when none of them does), if any is significant.
    pub pattern: Option<&'static str>,
    /// Any test of what is left could be made (replicate runs, or runs enough for a directed
    /// test).
    pub tested: bool,
    /// The tests that could not be computed on these data, and why.
    pub not_identified: Vec<String>,
    /// The decision in one sentence.
    pub sentence: String,
    /// Selected effects whose best fit sits on the edge of their physical range, with the
    /// value there: the data want more than the effect can be.
    pub at_physical_limit: Vec<(&'static str, f64)>,
    /// The selected within-run effects' sizes per wrap, from the cords' own sizes (None with
    /// one wrap, fewer than four cords or none selected).
    pub constancy: Option<Constancy>,
    /// The pure-error test of the shared fit (None without replicate runs).
    pub lack_of_fit: Option<LackOfFit>,
    /// The pure-error test with every cord's own T2 zero and selected effects.
    pub lack_of_fit_beyond_cords: Option<LackOfFit>,
    /// The cords as units: random cord effects and patterns between cords.
    pub cords: CordLevel,
    /// The step profile the cords share beyond their own parameters, against sign flips of
    /// whole cords (None with fewer than [`COMMON_MIN_CORDS`] cords).
    pub common: Option<CommonProfile>,
    /// What is left is cord-to-cord scatter of these parameters (the shared fit's lack of fit
    /// is significant and large, the cords' own parameters take it up): the supported random
    /// cord effects, strongest first. Empty otherwise.
    pub left_between_cords: Vec<&'static str>,
    /// The directed tests.
    pub directed: Vec<Directed>,
    /// The rule.
    pub rule: AdequacyRule,
}

/// Test the residuals of `fit` (weights `w`) for structure left.
pub fn assess(d: &Design, fit: &WithinFit, w: &Weights, rule: AdequacyRule) -> Adequacy {
    let z: Vec<f64> = (0..d.n())
        .map(|i| (d.t2[i] - fit.fitted[i]) * w.w[i].sqrt())
        .collect();
    let mut not_identified = Vec::new();
    let cords = cord_level(d, fit, w, rule.alpha_random);
    let lack_of_fit = identified_lack_of_fit(d, &z, fit.k(), &mut not_identified);
    let k_cords = fit.k() + cords.per_cord_parameters * cords.cords;
    let after = |signs: &[f64], out: &mut [f64]| cords.projection.after(d, signs, out);
    let beyond = pure_error::pure_error_with(d, k_cords, &after)
        .filter(|l| [l.f, l.p, l.systematic_ratio].iter().all(|v| v.is_finite()));
    let mut directed = directed_tests(d, &cords.z_after);
    directed.extend(between_directed(&cords));
    if cords.cords < super::cords::MIN_CORDS && cords.cords >= 2 {
        not_identified.push(format!(
            "patterns between cords (wrap, diameter): {} cords are too few to judge them              against the cords' own scatter (at least {})",
            cords.cords,
            super::cords::MIN_CORDS
        ));
    }
    let untested = lack_of_fit.is_none() && directed.is_empty();
    if untested {
        not_identified.push(format!(
            "what is left: {} run(s) are too few for any test of the residuals",
            d.units.len()
        ));
    }
    // A pattern between cords is flagged only where there is something left for it to be:
    // the lack of fit against the replicate runs significant, or, without replicates, a shape
    // pattern that accounts for a share of the residuals the rule calls large (a pattern of
    // the cords' summaries can be exact and still far too small to matter).
    let sized = |t: &&Directed| match &lack_of_fit {
        Some(l) => l.p < rule.alpha,
        None => (cords.patterns.iter())
            .filter(|p| p.covariate == t.structure && p.p_family <= t.p * (1.0 + 1e-9))
            .any(|p| p.share >= rule.min_r2),
    };
    let between = directed
        .iter()
        .filter(|t| is_between(t.structure) && t.p < rule.alpha_between)
        .filter(sized)
        .min_by(|a, b| a.p.total_cmp(&b.p));
    let within: Vec<&Directed> = directed
        .iter()
        .filter(|t| !is_between(t.structure))
        .collect();
    let best = within
        .iter()
        .filter(|t| t.p < rule.alpha)
        .min_by(|a, b| a.p.total_cmp(&b.p).then(b.f.total_cmp(&a.f)))
        .copied();
    let at_physical_limit: Vec<(&'static str, f64)> = (0..fit.k())
        .filter(|&j| fit.maps[j].at_physical_limit(fit.theta[j]))
        .map(|j| (fit.maps[j].kind.name(), fit.value(j)))
        .collect();
    let large = |l: &LackOfFit| l.p < rule.alpha && l.systematic_ratio >= rule.min_ratio;
    let bonferroni = rule.alpha / within.len().max(1) as f64;
    let directed_lack = best.is_some_and(|t| t.p < bonferroni && t.partial_r2 >= rule.min_r2);
    // With cords enough, what is left must be shared by the cords to be a pattern the model
    // misses; each cord's own departures are cord-to-cord scatter. With fewer, the lack of fit
    // beyond the cords' own parameters decides (it cannot tell the two apart).
    let common = common::common_profile(d, &cords.z_after, COMMON_MIN_CORDS);
    let lack = match (&common, &beyond) {
        (Some(c), _) => {
            (c.p < rule.alpha_between && c.systematic_ratio >= rule.min_ratio)
                || (best.is_some_and(|t| t.unit == "cords") && directed_lack)
        }
        (None, Some(l)) => large(l),
        (None, None) => directed_lack,
    };
    let constancy = constancy(d, fit, &cords);
    let unexplained = lack || between.is_some() || !at_physical_limit.is_empty();
    let left_between_cords = if !unexplained && lack_of_fit.as_ref().is_some_and(large) {
        supported_scatter(&cords)
    } else {
        Vec::new()
    };
    let own_shape_left = !unexplained && beyond.as_ref().is_some_and(large);
    let pattern = match between {
        Some(t) => Some(t.structure),
        None => pattern(best, beyond.as_ref(), &within, rule),
    };
    let mut sentence = sentence(
        lack || between.is_some(),
        pattern,
        beyond.as_ref(),
        &directed,
    );
    if let Some(t) = between {
        sentence = between_sentence(&cords, t.structure, lack_of_fit.as_ref());
    }
    if !unexplained && lack_of_fit.as_ref().is_some_and(large) {
        let own = own_shape_left.then_some(common.as_ref()).flatten();
        sentence = scatter_sentence(
            &cords,
            &left_between_cords,
            (lack_of_fit.as_ref(), beyond.as_ref()),
            own,
        );
    }
    // Too few replicate runs to rule out structure that matters, by the test beyond the
    // cords' own parameters or, failing that, by the plain one (each cord's own parameters can
    // absorb what a small design cannot test: a quiet F after them is no evidence).
    let weak = (beyond.as_ref().filter(|l| underpowered(l, rule)))
        .or(lack_of_fit.as_ref().filter(|l| underpowered(l, rule)));
    if let Some(l) = weak.filter(|_| !lack && between.is_none() && common.is_none()) {
        sentence = if l.saturated {
            format!(
                "The replicate runs fill {} cells, no more than the parameters fitted to them (each of the {} cords' own and the model's): no lack of fit can show, so these runs cannot rule out structure that matters.",
                l.cells,
                cords.cords
            )
        } else {
            format!(
            "The lack of fit against the replicate runs is not significant at the rule's level of {} (F = {:.2}, p = {}), but its systematic part is estimated at {:.2}× the noise, above the rule's {:.2}×: these replicate runs are too few to rule out structure that matters.",
            rule.alpha,
            l.f,
            p_shown(l.p),
            l.systematic_ratio,
            rule.min_ratio
        )
        };
    }
    if untested {
        sentence = format!(
            "What is left is not identified: with {} run(s) no test of it can be made (no \
             replicate runs, and too few runs for a test of the residuals against T1, time or \
             wrap).",
            d.units.len()
        );
    }
    let sentence = with_limits(sentence, lack || between.is_some(), &at_physical_limit);
    Adequacy {
        unexplained,
        pattern,
        tested: lack_of_fit.is_some() || !directed.is_empty(),
        not_identified,
        sentence,
        at_physical_limit,
        constancy,
        lack_of_fit,
        lack_of_fit_beyond_cords: beyond,
        cords,
        common,
        left_between_cords,
        directed,
        rule,
    }
}

/// From this many cords the cords decide whether what is left is shared by them (a pattern)
/// or each cord's own (cord-to-cord scatter): exact sign flips of 8 cords resolve p to 1/128.
pub const COMMON_MIN_CORDS: usize = 8;

/// A structure that varies only between cords.
fn is_between(structure: &str) -> bool {
    matches!(structure, "wrap" | "diameter")
}

/// The cord-level pattern tests as directed tests: per covariate, its most significant
/// summary (t², 1 and G − 2 degrees of freedom, p Bonferroni-adjusted over the family).
fn between_directed(c: &CordLevel) -> Vec<Directed> {
    ["wrap", "diameter"]
        .into_iter()
        .filter_map(|cov| {
            let best = c
                .patterns
                .iter()
                .filter(|p| p.covariate == cov)
                .min_by(|a, b| a.p.total_cmp(&b.p))?;
            Some(Directed {
                structure: cov,
                f: best.t * best.t,
                df1: 1.0,
                df2: best.df,
                p: best.p_family,
                partial_r2: best.r2,
                unit: "cords",
                units: c.cords,
            })
        })
        .collect()
}

/// The supported random cord effects beyond mu (which every run's own mu takes up anyway),
/// strongest first.
fn supported_scatter(c: &CordLevel) -> Vec<&'static str> {
    let mut v: Vec<&super::cords::RandomEffect> = c
        .random_effects
        .iter()
        .filter(|e| e.supported && e.parameter != "mu")
        .collect();
    v.sort_by(|a, b| a.p.total_cmp(&b.p).then(b.f.total_cmp(&a.f)));
    v.into_iter().map(|e| e.parameter).collect()
}

/// What a parameter is, for the sentence on what is left.
pub fn scatter_words(parameter: &str) -> &'static str {
    match parameter {
        "t2_offset" => "the T2 offset",
        "t1_offset" => "the T1 offset",
        "contact_heating" => "contact heating",
        "pressure_friction" => "the pressure exponent",
        "bending_stiffness" => "the bending stiffness",
        "thermal_drift" => "the drift with time",
        "mu" => "mu",
        "sensor_gain" => "the T2 gain",
        _ => "an effect's size",
    }
}

/// A pattern between cords: which cord summary changes with `covariate`, with its test.
fn between_sentence(c: &CordLevel, covariate: &str, lof: Option<&LackOfFit>) -> String {
    let Some(p) = c
        .patterns
        .iter()
        .filter(|p| p.covariate == covariate)
        .min_by(|a, b| a.p.total_cmp(&b.p))
    else {
        return String::new();
    };
    let what = match p.summary {
        "shape_t1" | "shape_t1_squared" => "the shape of T2 against T1".to_string(),
        s => format!("the size of {}", scatter_words(s)),
    };
    let by = if covariate == "wrap" {
        "the wrap"
    } else {
        "the capstan diameter"
    };
    let mut s = format!(
        "{what} changes with {by} (the {} cords as units: t({:.0}) = {:.2}, p {} after Bonferroni over {} cord-level tests); no catalogue effect explains it",
        c.cords,
        p.df,
        p.t,
        p_equals(p.p_family),
        c.patterns.len()
    );
    if let Some(l) = lof {
        s += &format!(
            " (lack of fit against the replicate runs F = {}, p {})",
            f_shown(l.f, 1),
            lof_p_equals(l.p)
        );
    }
    s + "."
}

/// What follows [`scatter_head`] when the cords' summaries were tested against wrap and
/// diameter and none follows them.
pub const NO_ORDER: &str = ", in no order of wrap or diameter";

/// The head of the verdict that what is left is cord-to-cord scatter of `what` (the
/// parameters in words, [`scatter_words`], with or without their numbers): one wording for
/// `diagnose`, `analyze`'s headline and the report.
pub fn scatter_head(what: &[String]) -> String {
    if what.is_empty() {
        return "What is left differs from cord to cord".to_string();
    }
    format!(
        "What is left is cord-to-cord scatter: {} {} from cord to cord more than from run to run",
        crate::text::list(what),
        if what.len() == 1 { "differs" } else { "differ" }
    )
}

/// What is left is cord-to-cord scatter: the sentence, with the supported random cord effects
/// `left`, the lack of fit before and beyond the cords' own parameters, and, when each cord's
/// own shape beyond them is left too (`own`: the test that it is shared by no pattern), that.
fn scatter_sentence(
    c: &CordLevel,
    left: &[&'static str],
    (common, beyond): (Option<&LackOfFit>, Option<&LackOfFit>),
    own: Option<&CommonProfile>,
) -> String {
    let what: Vec<String> = left
        .iter()
        .map(|p| {
            let e = c.random_effects.iter().find(|e| e.parameter == *p);
            let sd = e.map_or(String::new(), |e| {
                let test = if e.method == super::cords::ANOVA {
                    "one-way ANOVA over cords"
                } else {
                    "score test, sign flips of whole runs"
                };
                format!(
                    " (SD {} {} between cords; {test}: p {})",
                    two_digits(e.sd_between),
                    e.unit,
                    flip_p(e.p)
                )
            });
            format!("{}{sd}", scatter_words(p))
        })
        .collect();
    let mut s = scatter_head(&what);
    if !c.patterns.is_empty() {
        let order = c.patterns.iter().map(|p| p.p_family).fold(1.0, f64::min);
        s += &format!(
            "{NO_ORDER} (the {} cords as units: each cord's values regressed on wrap and on diameter, t tests, Bonferroni-adjusted smallest p = {})",
            c.cords,
            p_shown(order)
        );
    }
    if let (Some(a), Some(b)) = (common, beyond) {
        s += &format!(
            "; with every cord's own T2 offset and effects the lack of fit against the replicate runs (pure-error F, p by sign flips of whole runs) falls from F = {} (p {}; the systematic part {:.2}× the noise) to F = {} (p {}; {:.2}×)",
            f_shown(a.f, 1),
            flip_p(a.p),
            a.systematic_ratio,
            f_shown(b.f, 1),
            flip_p(b.p),
            b.systematic_ratio
        );
    }
    if let Some(o) = own {
        s += &format!(
            ", and what each cord keeps beyond them is mostly its own: a profile shared by the {} cords over the {} steps is not established (sign flips of whole cords, p = {}; shared part {:.2}× the noise)",
            o.cords,
            o.steps,
            p_shown(o.p),
            o.systematic_ratio
        );
    }
    s + "."
}

/// Two significant digits.
fn two_digits(v: f64) -> String {
    if !v.is_finite() || v == 0.0 {
        return crate::text::sig(v);
    }
    let e = v.abs().log10().floor() as i32;
    let decimals = (1 - e).max(0) as usize;
    format!("{v:.decimals$}")
}

/// A sign-flip p: "≤ 5.0e-4" at its floor (no flip as large), else "= p".
fn flip_p(p: f64) -> String {
    if p <= pure_error::P_FLOOR * (1.0 + 1e-9) {
        format!("≤ {:.1e}", pure_error::P_FLOOR)
    } else {
        p_equals(p)
    }
}

/// The pure-error lack-of-fit test, if it could be computed with finite numbers (otherwise
/// why not, in `not_identified`).
fn identified_lack_of_fit(
    d: &Design,
    z: &[f64],
    k: usize,
    not_identified: &mut Vec<String>,
) -> Option<LackOfFit> {
    pure_error(d, z, k).filter(|l| {
        let ok = [l.f, l.p, l.systematic_ratio].iter().all(|v| v.is_finite());
        if !ok {
            not_identified.push(
                "lack of fit: the replicate runs agree exactly (no pure error to compare with)"
                    .to_string(),
            );
        }
        ok
    })
}

/// The pattern of what is left: the significant directed test (`best`), or, when the pure
/// error says structure is left, the directed test that comes closest to it (a description of
/// what is left, at p < 0.05: the omnibus test has made the decision).
fn pattern(
    best: Option<&Directed>,
    lack_of_fit: Option<&LackOfFit>,
    directed: &[&Directed],
    rule: AdequacyRule,
) -> Option<&'static str> {
    let closest = directed
        .iter()
        .filter(|t| t.p < 0.05)
        .min_by(|a, b| a.p.total_cmp(&b.p));
    match (best, lack_of_fit) {
        (Some(t), _) => Some(t.structure),
        (None, Some(l)) if l.p < rule.alpha => Some(closest.map_or("cells", |t| t.structure)),
        _ => None,
    }
}

/// The decision's sentence with the effects pushed to the edge of the physical range, which
/// says the catalogue does not explain the data (replacing the sentence when nothing before it
/// said so).
fn with_limits(sentence: String, lack: bool, at_physical_limit: &[(&'static str, f64)]) -> String {
    if at_physical_limit.is_empty() {
        return sentence;
    }
    let list: Vec<String> = at_physical_limit
        .iter()
        .map(|(k, v)| format!("{k} ({v:.4})"))
        .collect();
    let edge = format!(
        "The data push {} to the edge of the physical range, so the catalogue does not explain them.",
        list.join(" and ")
    );
    if lack {
        format!("{sentence} {edge}")
    } else {
        edge
    }
}

/// The sentence of the decision.
pub fn sentence(
    unexplained: bool,
    pattern: Option<&str>,
    lof: Option<&LackOfFit>,
    directed: &[Directed],
) -> String {
    if unexplained {
        let what = match pattern.unwrap_or("cells") {
            "step_direction" => "T2 depends on the step direction (rising against falling tension)",
            "t1_shape" => "T2 departs from the fitted model along T1 (the shape of T2 against T1)",
            "time" => "T2 drifts with time inside runs beyond the fitted effects",
            "wrap" => "the shape of T2 against T1 changes with the wrap",
            "diameter" => "the shape of T2 against T1 changes with the capstan diameter",
            _ => "T2 departs from the fitted model at particular steps, along none of T1, time, step direction, wrap or diameter",
        };
        let mut s = format!("{what}; no catalogue effect explains it");
        if let Some(l) = lof {
            s += &format!(
                " (lack of fit against the replicate runs F = {}, p {}; the systematic part is {:.2}× the noise)",
                f_shown(l.f, 1), lof_p_equals(l.p), l.systematic_ratio
            );
        }
        s + "."
    } else {
        match lof {
            Some(l) if l.p < 1e-3 => format!(
                "What remains is detectable but small (lack of fit F = {}, p {}; the systematic part is {:.2}× the noise, under the rule's size): the fitted effects explain the data.",
                f_shown(l.f, 1), lof_p_equals(l.p), l.systematic_ratio
            ),
            Some(l) => format!(
                "No structure is left beyond the noise (lack of fit against the replicate runs F = {:.2}, p = {:.2}).",
                l.f, l.p
            ),
            None => {
                let p_min = directed.iter().map(|t| t.p).fold(1.0, f64::min);
                format!(
                    "No replicate runs give a pure error; no test of the residuals against T1, time, step direction, wrap or diameter finds structure that matters (smallest p = {}).",
                    p_shown(p_min)
                )
            }
        }
    }
}

/// A lack-of-fit test that found nothing significant while its estimate of the systematic
/// part is as large as the rule calls large: too few replicate runs to tell.
pub fn underpowered(l: &LackOfFit, rule: AdequacyRule) -> bool {
    l.saturated || (l.p >= rule.alpha && l.systematic_ratio >= rule.min_ratio)
}

/// A p-value for a sentence: two decimals down to 0.01, then two significant digits (0.004
/// must not read "0.00").
pub fn p_shown(p: f64) -> String {
    if p < 1e-15 {
        // Below what a double resolves in an upper tail: not a measured 0.
        return "< 1e-15".to_string();
    }
    if p >= 0.01 {
        format!("{p:.2}")
    } else {
        format!("{p:.1e}")
    }
}

/// An F statistic: `decimals` decimals, or three significant digits from a million up (a
/// copied run's zero pure error once gave a 34-digit F).
pub fn f_shown(f: f64, decimals: usize) -> String {
    if f.abs() >= 1e6 {
        format!("{f:.2e}")
    } else {
        format!("{f:.decimals$}")
    }
}

/// "= 4.0e-3", or "< 1e-15".
pub fn p_equals(p: f64) -> String {
    let shown = p_shown(p);
    if shown.starts_with('<') {
        shown
    } else {
        format!("= {shown}")
    }
}

/// The lack of fit's p ([`p_equals`]), or "≤ 5.0e-4" at the wild bootstrap's floor: no sign
/// flip was as large, so the bootstrap says p is at most this, not that it is this.
pub fn lof_p_equals(p: f64) -> String {
    if p <= pure_error::P_FLOOR * (1.0 + 1e-9) {
        format!("≤ {:.1e}", pure_error::P_FLOOR)
    } else {
        p_equals(p)
    }
}

/// The selected effects' sizes per wrap (each the mean of its cords' own sizes) and the
/// cords' sizes against the wrap (cords as units; the most significant effect's test). None
/// with no effect selected, one wrap or too few cords.
fn constancy(d: &Design, fit: &WithinFit, c: &CordLevel) -> Option<Constancy> {
    let wraps = d.wraps();
    if fit.k() == 0 || wraps.len() < 2 {
        return None;
    }
    let names: Vec<&'static str> = fit.maps.iter().map(|m| m.kind.name()).collect();
    let test = c
        .patterns
        .iter()
        .filter(|p| p.covariate == "wrap" && names.contains(&p.summary))
        .min_by(|a, b| a.p.total_cmp(&b.p))?;
    let mut spread: f64 = 0.0;
    let mut by_wrap = Vec::new();
    for (j, name) in names.iter().enumerate() {
        let per_cord = &c.per_cord.iter().find(|(n, _)| n == name)?.1;
        let common = fit.value(j);
        let scale = (common - fit.maps[j].kind.neutral_value()).abs();
        let vals: Vec<(f64, f64)> = wraps
            .iter()
            .map(|&wr| {
                let v: Vec<f64> = (0..d.cords.len())
                    .filter(|&g| d.cords[g].wrap_deg == wr && per_cord[g].is_finite())
                    .map(|g| per_cord[g])
                    .collect();
                (wr, v.iter().sum::<f64>() / v.len() as f64)
            })
            .collect();
        for &(_, x) in &vals {
            if scale > 0.0 && x.is_finite() {
                spread = spread.max((x - common).abs() / scale);
            }
        }
        by_wrap.push((*name, vals));
    }
    Some(Constancy {
        by_wrap,
        f: test.t * test.t,
        df1: 1.0,
        df2: test.df,
        p: test.p_family,
        spread,
    })
}
