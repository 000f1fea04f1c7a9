//! Every gate's statistic for every testable term at the search's first step (a diagnostic for
//! the calibration of docs/README-discover.md, not part of the answer).
//!
//! The search applies its gates in order and stops at the first term that passes them all; the
//! calibration needs each gate as a test of its own: its false-positive rate on null sets and
//! its power on planted kinds, for the term the screen ranks first and for the term of the
//! right dependence. So here every testable term of the first step (the catalogue as the
//! engine selected it; swaps are not profiled) gets its screen, its replicate evidence, its
//! stability over whole-cord resamples, its held-out ratio and the share of the lack of fit it
//! removes, each computed as the search computes it.

use crate::checks::{candidates, held_out, lack_of_fit_with};
use crate::columns::Base;
use crate::heldout::Ratio;
use crate::library::LIBRARY;
use crate::model::{catalogue_covariate, classify, runs_of, screen_all, state_of};
use crate::replicate::Replicate;
use crate::screen::{Level, Projector};
use crate::stability::{self, Hit};
use crate::verdict::{Bar, Options};
use capstan_data::Dataset;
use capstan_engine::evidence;

/// One term's gates at the first step.
#[derive(Clone, Debug, serde::Serialize)]
pub struct GateRow {
    /// Library name.
    pub name: &'static str,
    /// Where its evidence comes from.
    pub level: Level,
    /// ΔBIC given the catalogue (before the search's penalty).
    pub delta_bic: f64,
    /// θ̂.
    pub theta: f64,
    /// θ̂ keeps its physical sign.
    pub sign_ok: bool,
    /// 1 − 1/VIF within runs.
    pub r2_model: f64,
    /// Its replicate evidence (within-run terms with replicate cells).
    pub replicate: Option<Replicate>,
    /// Share of whole-cord resamples in which it is the pick and passes the first bar.
    pub stability: f64,
    /// ... in which a term of its dependence is.
    pub stability_dependence: f64,
    /// Its held-out ratio (None: not computable).
    pub heldout: Option<Ratio>,
    /// Share of the lack of fit's systematic variance it removes (None: no lack of fit to
    /// judge, or a between-level term, which leaves it as it was).
    pub lof_share: Option<f64>,
    /// The lack of fit with it in is still significant (p < 0.01).
    pub lof_open_after: Option<bool>,
    /// The share it removes beside every within-run catalogue effect, selected or not.
    pub lof_share_saturated: Option<f64>,
}

/// The first step's gates of every testable term of `data`, best screen first, with the first
/// bar and the rows. Nothing when the data have fewer than 3 cords.
pub fn profile(data: &Dataset, opts: &Options) -> (f64, usize, Vec<GateRow>) {
    let a = evidence::assess(data, &opts.engine);
    let d = &a.design;
    let base = Base::new(d, &a.fit, &a.weights.w);
    let (testable, _) = classify(&base, opts.bump_centres);
    let alts = if opts.joint {
        crate::joint::alternatives(&a, opts.restore)
    } else {
        Vec::new()
    };
    let bar = Bar {
        threshold: opts.engine.within_threshold.max(0.0),
        gamma: opts.gamma,
        models: crate::model::models_of(&testable, opts.bump_centres).max(1) as f64
            * (1 + alts.len()) as f64,
    }
    .at(1);
    if d.cords.len() < crate::verdict::MIN_CORDS {
        return (bar, d.n(), Vec::new());
    }
    let covs: Vec<Vec<f64>> = a
        .selected
        .iter()
        .filter_map(|&k| catalogue_covariate(&a, k))
        .collect();
    let st = state_of(&base, &covs);
    let proj = Projector::new(&base, &st.shared);
    let runs = runs_of(&a, &a.fit);
    let screens = screen_all(&base, &testable, &proj, &st, &runs, opts.gate(bar));
    let cands = candidates(&testable, &st, &screens, &[]);
    let problem = stability::Problem {
        base: &base,
        shared: &st.shared,
        e: &base.e,
        candidates: &cands,
        runs: &runs,
        covs: &st.covs,
        bar,
    };
    let lof0 = &a.adequacy.lack_of_fit;
    let rows = screens
        .iter()
        .map(|s| {
            let tst = testable
                .iter()
                .find(|c| c.term == s.term)
                .expect("testable");
            let seed = 0x26_57ab + 1;
            let stab = stability::stability(&problem, s.term, opts.resamples, seed, Hit::Term);
            let stab_dep =
                stability::stability(&problem, s.term, opts.resamples, seed, Hit::Dependence);
            let xt = tst.column.as_ref().map(|x| proj.project(&base, x));
            let after = lack_of_fit_with((d, &base), &st, s.theta, xt.as_deref(), lof0);
            let share = match (lof0, &after, &xt) {
                (Some(b), Some(l), Some(_)) => {
                    Some(1.0 - (l.systematic_ratio / b.systematic_ratio).powi(2))
                }
                _ => None,
            }
            .filter(|v| v.is_finite());
            GateRow {
                name: LIBRARY[s.term].name,
                level: s.level,
                delta_bic: s.delta_bic,
                theta: s.theta,
                sign_ok: s.sign_ok,
                r2_model: s.r2_model,
                replicate: s.replicate.clone(),
                stability: stab,
                stability_dependence: stab_dep,
                heldout: held_out(&base, &a.fit, &st, tst, None),
                lof_share: share,
                lof_open_after: after.as_ref().map(|l| l.p < crate::answer::LOF_ALPHA),
                lof_share_saturated: tst.column.as_ref().and_then(|x| {
                    crate::reselect::share_beside_every_effect(&a, &base, &st.shared, x)
                }),
            }
        })
        .collect();
    (bar, d.n(), rows)
}
