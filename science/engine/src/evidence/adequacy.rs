//! Is anything left? After the selected effects are fitted, the residuals are tested for the
//! structure no catalogue effect took up.
//!
//! * **Lack of fit against pure error** (Draper & Smith §2.1, with clustered replicates): the
//!   runs of a cord repeat the same steps, so the residuals of a cord × step cell scatter
//!   around their cell mean by the run-to-run error alone. F = MS_LOF/MS_PE with
//!   MS_LOF = Σ n_c·m_c²/(cells − cords − k) (each run's mu removes one mean per cord) and
//!   MS_PE = Σ(z − m_c)²/Σ(n_c − 1), on the standardised residuals z = r·√w; its p from sign
//!   flips of whole runs (the runs' residuals are serially correlated). Its size, the
//!   systematic part's RMS per observation (SS_LOF beyond what the flips give) over the pure
//!   error's, tells a pattern that matters from one that is merely detectable.
//! * **Directed tests**, each a cluster-robust Wald test (runs as clusters, F with (q, G − q)
//!   degrees of freedom) of the run-centred residuals against one structure: the shape along
//!   T1 (asinh(T1/0.5 N) and its square: defined for readings at or below zero), time inside
//!   runs, the step direction, the T1 shape changing with the wrap or with the diameter. They
//!   name the pattern that remains, and decide without replicates.
//!
//! `unexplained` is set when the remaining lack of fit is both significant and large; the
//! sentence is generated from that decision and the pattern found.

use super::design::Design;
use super::within::{fit_strata, Strata, Weights, WithinFit};
use crate::fit::stats::f_p_upper;
use nalgebra::{DMatrix, DVector};
use serde::Serialize;

mod directed;
mod pure_error;

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
}

impl Default for AdequacyRule {
    fn default() -> Self {
        AdequacyRule {
            alpha: 1e-3,
            min_ratio: 0.35,
            min_r2: 0.05,
            min_spread: 0.5,
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
}

/// Do the selected effects have one size for all wraps? The same physics has the same size on
/// every cord; an effect that takes different sizes on different wraps stands in for something
/// else. A cluster-robust Wald test (runs as clusters) of the per-wrap sizes' contrasts.
#[derive(Clone, Debug, Serialize)]
pub struct Constancy {
    /// Per effect: its size on each wrap, (wrap in degrees, value).
    pub by_wrap: Vec<(&'static str, Vec<(f64, f64)>)>,
    /// F of the Wald statistic.
    pub f: f64,
    /// Numerator degrees of freedom: effects × (wraps − 1).
    pub df1: f64,
    /// Denominator degrees of freedom: runs − df1.
    pub df2: f64,
    /// Upper-tail p.
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
    /// Share of the run-centred residual variance the structure explains.
    pub partial_r2: f64,
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
    /// The selected within-run effects refitted with one size per wrap (None with one wrap
    /// or none selected).
    pub constancy: Option<Constancy>,
    /// The pure-error test (None without replicate runs).
    pub lack_of_fit: Option<LackOfFit>,
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
    let lack_of_fit = identified_lack_of_fit(d, &z, fit.k(), &mut not_identified);
    let directed = directed_tests(d, &z);
    let untested = lack_of_fit.is_none() && directed.is_empty();
    if untested {
        not_identified.push(format!(
            "what is left: {} run(s) are too few for any test of the residuals",
            d.units.len()
        ));
    }
    let significant: Vec<&Directed> = directed.iter().filter(|t| t.p < rule.alpha).collect();
    let best = significant
        .iter()
        .min_by(|a, b| a.p.total_cmp(&b.p).then(b.f.total_cmp(&a.f)))
        .copied();
    let at_physical_limit: Vec<(&'static str, f64)> = (0..fit.k())
        .filter(|&j| fit.maps[j].at_physical_limit(fit.theta[j]))
        .map(|j| (fit.maps[j].kind.name(), fit.value(j)))
        .collect();
    let lack = match &lack_of_fit {
        Some(l) => l.p < rule.alpha && l.systematic_ratio >= rule.min_ratio,
        None => {
            let bonferroni = rule.alpha / directed.len().max(1) as f64;
            best.is_some_and(|t| t.p < bonferroni && t.partial_r2 >= rule.min_r2)
        }
    };
    let constancy = constancy(d, fit, w);
    if fit.k() > 0 && d.wraps().len() > MAX_CONSTANCY_WRAPS {
        not_identified.push(format!(
            "one size per wrap: {} wraps are more than the {MAX_CONSTANCY_WRAPS} this test \
             refits",
            d.wraps().len()
        ));
    }
    let inconstant =
        (constancy.as_ref()).filter(|c| c.p < rule.alpha && c.spread >= rule.min_spread);
    let unexplained = lack || !at_physical_limit.is_empty() || inconstant.is_some();
    let pattern = pattern(best, lack_of_fit.as_ref(), &directed, rule);
    let mut sentence = sentence(lack, pattern, lack_of_fit.as_ref(), &directed);
    if let Some(l) = lack_of_fit
        .as_ref()
        .filter(|l| !lack && underpowered(l, rule))
    {
        sentence = format!(
            "The lack of fit against the replicate runs is not significant (F = {:.2}, p = {}), but its systematic part is estimated at {:.2}× the noise, above the rule's {:.2}×: these replicate runs are too few to rule out structure that matters.",
            l.f,
            p_shown(l.p),
            l.systematic_ratio,
            rule.min_ratio
        );
    }
    if untested {
        sentence = format!(
            "What is left is not identified: with {} run(s) no test of it can be made (no \
             replicate runs, and too few runs for a test of the residuals against T1, time or \
             wrap).",
            d.units.len()
        );
    }
    let sentence = with_limits_and_sizes(sentence, lack, &at_physical_limit, inconstant);
    Adequacy {
        unexplained,
        pattern,
        tested: lack_of_fit.is_some() || !directed.is_empty(),
        not_identified,
        sentence,
        at_physical_limit,
        constancy,
        lack_of_fit,
        directed,
        rule,
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
    directed: &[Directed],
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

/// The decision's sentence with what else says the catalogue does not explain the data: the
/// effects pushed to the edge of the physical range, and found effects of different sizes on
/// different wraps (`inconstant`). Each replaces the sentence when nothing before it said so.
fn with_limits_and_sizes(
    mut sentence: String,
    lack: bool,
    at_physical_limit: &[(&'static str, f64)],
    inconstant: Option<&Constancy>,
) -> String {
    if !at_physical_limit.is_empty() {
        let list: Vec<String> = at_physical_limit
            .iter()
            .map(|(k, v)| format!("{k} ({v:.4})"))
            .collect();
        let edge = format!(
            "The data push {} to the edge of the physical range, so the catalogue does not explain them.",
            list.join(" and ")
        );
        sentence = if lack {
            format!("{sentence} {edge}")
        } else {
            edge
        };
    }
    if let Some(c) = inconstant {
        let list: Vec<String> = c
            .by_wrap
            .iter()
            .map(|(k, v)| {
                let vals: Vec<String> = v.iter().map(|(w, x)| format!("{x:.4} at {w}°")).collect();
                format!("{k} ({})", vals.join(", "))
            })
            .collect();
        let text = format!(
            "The found effects take different sizes on different wraps ({}; F = {}, p {}), which the same physics would not: they stand in for something no catalogue effect explains.",
            list.join("; "),
            f_shown(c.f, 1),
            p_equals(c.p)
        );
        sentence = if lack || !at_physical_limit.is_empty() {
            format!("{sentence} {text}")
        } else {
            text
        };
    }
    sentence
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
    l.p >= rule.alpha && l.systematic_ratio >= rule.min_ratio
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

/// The most wraps the constancy test refits one size per wrap for: beyond, it is not
/// identified (a data set of a few rows at each of hundreds of wraps cannot say an effect's
/// size per wrap, and the refit would grow with the square of their number).
pub const MAX_CONSTANCY_WRAPS: usize = 24;

/// Refit the selected effects with one size per wrap and test that the sizes agree.
fn constancy(d: &Design, fit: &WithinFit, w: &Weights) -> Option<Constancy> {
    let k = fit.k();
    let wraps = d.wraps();
    if k == 0 || wraps.len() < 2 || wraps.len() > MAX_CONSTANCY_WRAPS {
        return None;
    }
    // Too few runs for the contrasts: decided before the refit, which it would not change.
    if d.units.len() < k * (wraps.len() - 1) + 2 {
        return None;
    }
    let of_unit: Vec<usize> = d
        .unit_cord
        .iter()
        .map(|&c| {
            wraps
                .iter()
                .position(|&x| x == d.cords[c].wrap_deg)
                .unwrap_or(0)
        })
        .collect();
    let s_n = wraps.len();
    let maps: Vec<_> = (0..s_n).flat_map(|_| fit.maps.iter().copied()).collect();
    let theta0: Vec<f64> = (0..s_n).flat_map(|_| fit.theta.iter().copied()).collect();
    let strata = Strata { k, of_unit };
    let split = fit_strata(d, (&maps, &strata), &theta0, &fit.mu, w);
    let q = k * (s_n - 1);
    let g = d.units.len() as f64;
    if g - (q as f64) < 2.0 {
        return None;
    }
    let qf = q as f64;
    let f = wald_f(&split, k, s_n, g)?;
    let (by_wrap, spread) = sizes_by_wrap(fit, &split, &wraps);
    let finite = spread.is_finite()
        && by_wrap
            .iter()
            .all(|(_, v)| v.iter().all(|x| x.1.is_finite()));
    if !finite {
        return None;
    }
    Some(Constancy {
        by_wrap,
        f,
        df1: qf,
        df2: g - qf,
        p: f_p_upper(f, qf, g - qf),
        spread,
    })
}

/// The F statistic of the Wald test that every effect has one size on every wrap: the
/// contrasts θ[s, j] − θ[0, j] of the split fit (`s_n` wraps of `k` effects, `g` runs) through
/// its robust covariance. None when it cannot be computed.
fn wald_f(split: &WithinFit, k: usize, s_n: usize, g: f64) -> Option<f64> {
    let big_k = k * s_n;
    let q = k * (s_n - 1);
    let mut c = DMatrix::<f64>::zeros(q, big_k);
    for s in 1..s_n {
        for j in 0..k {
            let row = (s - 1) * k + j;
            c[(row, s * k + j)] = 1.0;
            c[(row, j)] = -1.0;
        }
    }
    let theta = DVector::from_column_slice(&split.theta);
    let v = DMatrix::from_row_slice(big_k, big_k, &split.cov_robust);
    let ct = &c * &theta;
    let cvc = &c * v * c.transpose();
    let wald = (ct.transpose() * cvc.try_inverse()? * &ct)[(0, 0)];
    let qf = q as f64;
    let f = wald / qf * (g - qf) / (g - 1.0);
    f.is_finite().then_some(f)
}

/// Each effect's size on each wrap (from the split fit), and the largest departure from the
/// common size relative to the common size's distance from neutral.
#[allow(clippy::type_complexity)]
fn sizes_by_wrap(
    fit: &WithinFit,
    split: &WithinFit,
    wraps: &[f64],
) -> (Vec<(&'static str, Vec<(f64, f64)>)>, f64) {
    let k = fit.k();
    let mut spread: f64 = 0.0;
    let by_wrap = (0..k)
        .map(|j| {
            let common = fit.value(j);
            let scale = (common - fit.maps[j].kind.neutral_value()).abs();
            let vals: Vec<(f64, f64)> = (0..wraps.len())
                .map(|s| (wraps[s], split.value(s * k + j)))
                .collect();
            for &(_, x) in &vals {
                if scale > 0.0 {
                    spread = spread.max((x - common).abs() / scale);
                }
            }
            (fit.maps[j].kind.name(), vals)
        })
        .collect();
    (by_wrap, spread)
}
