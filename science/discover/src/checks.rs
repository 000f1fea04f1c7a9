//! The checks a picked term must pass beyond its screen, computed: its stability's candidates,
//! its held-out ratio, the lack of fit with it in, and its rivals.

use crate::answer::Rival;
use crate::columns::Base;
use crate::heldout::{self, Ratio};
use crate::library::{Sign, LIBRARY};
use crate::model::{State, Testable};
use crate::screen::{self, Projector};
use crate::stability::Candidate;
use capstan_engine::evidence::adequacy::{lack_of_fit, LackOfFit};
use capstan_engine::evidence::design::Design;
use capstan_engine::evidence::within::WithinFit;
use capstan_engine::evidence::RIVAL_GAP;

/// The stability's candidates: every testable term not yet in the model and not already
/// failed at this step (`failed`), with its overdispersion from this step's screen.
pub(crate) fn candidates(
    testable: &[Testable],
    st: &State,
    screens: &[screen::Screen],
    failed: &[usize],
) -> Vec<Candidate> {
    testable
        .iter()
        .filter(|c| !st.used.contains(&c.term) && !failed.contains(&c.term))
        .map(|c| Candidate {
            term: c.term,
            column: c.column.clone(),
            g_run: c.g_run.clone(),
            c_hat: screens
                .iter()
                .find(|s| s.term == c.term)
                .map_or(1.0, |s| s.c_hat),
            sign_ok: match LIBRARY[c.term].sign {
                Sign::Free => |_| true,
                Sign::NonNegative => |t| t >= 0.0,
            },
        })
        .collect()
}

/// The lack of fit against the replicate runs with a within-run term in at `theta` (`xt`: its
/// column projected off the model; within-run terms change what the replicates share). A
/// between-level term leaves it as it was (`before`).
pub(crate) fn lack_of_fit_with(
    (d, base): (&Design, &Base),
    st: &State,
    theta: f64,
    xt: Option<&[f64]>,
    before: &Option<LackOfFit>,
) -> Option<LackOfFit> {
    match xt {
        Some(xt) => {
            let z: Vec<f64> = (0..d.n())
                .map(|i| (st.e[i] - theta * xt[i]) * base.w[i].sqrt())
                .collect();
            lack_of_fit(d, &z, st.shared.len() + 1)
        }
        None => before.clone(),
    }
}

/// The held-out ratio matched to the term's level.
pub(crate) fn held_out(
    base: &Base,
    fit: &WithinFit,
    st: &State,
    c: &Testable,
    without: Option<Vec<f64>>,
) -> Option<Ratio> {
    let rows = heldout::rows_per_cord(base);
    match (&c.column, &c.g_run) {
        (Some(x), _) => {
            let without = without.unwrap_or_else(|| heldout::shape_sse(base, &st.shared));
            let mut cols = st.shared.clone();
            cols.push(x.clone());
            let with = heldout::shape_sse(base, &cols);
            heldout::ratio(
                &with,
                &without,
                &rows,
                "each held-out run keeps its own mu; the shape comes from the other cords",
            )
        }
        (None, Some(g)) => {
            let x0: Vec<Vec<f64>> = (0..g.len())
                .map(|u| {
                    std::iter::once(1.0)
                        .chain(st.covs.iter().map(|cv| cv[u]))
                        .collect()
                })
                .collect();
            let x1: Vec<Vec<f64>> = x0
                .iter()
                .zip(g)
                .map(|(r, gv)| {
                    let mut r = r.clone();
                    r.push(*gv);
                    r
                })
                .collect();
            let without = heldout::population_sse(base, fit, &x0);
            let with = heldout::population_sse(base, fit, &x1);
            heldout::ratio(
                &with,
                &without,
                &rows,
                "the held-out cord's mu predicted from the other cords",
            )
        }
        _ => None,
    }
}

/// The terms within the engine's rival gap of the pick, with their columns' correlation with
/// its column (within-run terms).
pub(crate) fn rivals_of(
    base: &Base,
    proj: &Projector,
    screens: &[screen::Screen],
    best: &screen::Screen,
    testable: &[Testable],
    threshold: f64,
) -> Vec<Rival> {
    let col = |term: usize| {
        testable
            .iter()
            .find(|c| c.term == term)
            .and_then(|c| c.column.as_ref())
            .map(|x| proj.project(base, x))
    };
    let xb = col(best.term);
    screens
        .iter()
        .filter(|s| s.term != best.term && s.sign_ok)
        .filter(|s| s.delta_bic < -threshold && s.delta_bic - best.delta_bic <= RIVAL_GAP)
        .map(|s| {
            let correlation = match (&xb, col(s.term)) {
                (Some(a), Some(b)) => {
                    let w = &base.w;
                    let ab: f64 = (0..a.len()).map(|i| w[i] * a[i] * b[i]).sum();
                    let aa: f64 = (0..a.len()).map(|i| w[i] * a[i] * a[i]).sum();
                    let bb: f64 = (0..a.len()).map(|i| w[i] * b[i] * b[i]).sum();
                    Some(ab / (aa * bb).sqrt())
                }
                _ => None,
            };
            Rival {
                name: LIBRARY[s.term].name,
                depends_on: LIBRARY[s.term].depends_on,
                delta_bic: s.delta_bic,
                correlation,
            }
        })
        .collect()
}

/// How a later term repairs the catalogue's selection rather than adding to it (D4).
pub(crate) enum Repair {
    /// Without the catalogue's effect it is not past the engine's bar: it only corrects what
    /// that effect does (ΔBIC of the term on the catalogue without it).
    LeansOn(&'static str, f64),
    /// In place of the catalogue's effect it explains at least what the effect did (the swap
    /// beats the catalogue as selected, or does as well as the term beside the effect; ΔBIC of
    /// that swap): it stands in for the effect.
    StandsIn(&'static str, f64),
}

/// A later term that repairs the catalogue's selection rather than adding to it (D4). For
/// each within-run catalogue effect k, the term is screened on the catalogue without k (with
/// the terms proposed before it). If it is not past the engine's bar there (`threshold`), its
/// evidence exists only beside k: it corrects what k does, as `t2_offset_wrap` beside a
/// T1 offset the engine took for the planted T2 offset (the T1 offset, amplified by
/// e^(mu beta), leaves a pattern in wrap that the term undoes; up-down hysteresis sets). If
/// "catalogue − k + term" beats the catalogue as selected, or is as good as "catalogue +
/// term", it stands in for k (`t2_lowforce` in place of that T1 offset: 4 of 12 seed-26
/// hysteresis sets got it as a second term; no other seed-26 set changed).
pub(crate) fn catalogue_repair(
    a: &capstan_engine::evidence::Assessment,
    alts: &[crate::joint::Alternative<'_>],
    st: &State,
    best: &screen::Screen,
    (threshold, gate, centres): (f64, crate::replicate::Gate, usize),
) -> Option<Repair> {
    use crate::model::{classify, runs_of, screen_all};
    for alt in alts
        .iter()
        .filter(|x| x.change == crate::joint::Change::Dropped)
    {
        let (testable, _) = classify(&alt.base, centres);
        let col = |term: usize| testable.iter().find(|c| c.term == term);
        let mut shared = alt.base.b.clone();
        for &u in &st.used {
            if let Some(x) = col(u).and_then(|c| c.column.clone()) {
                shared.push(x);
            }
        }
        let e = Projector::new(&alt.base, &shared).project(&alt.base, &alt.base.e);
        let st_alt = State {
            shared,
            covs: st.covs.clone(),
            e,
            used: st.used.clone(),
            theta_used: st.theta_used.clone(),
        };
        let Some(c) = col(best.term) else { continue };
        let proj = Projector::new(&alt.base, &st_alt.shared);
        let sc = screen_all(
            &alt.base,
            std::slice::from_ref(c),
            &proj,
            &st_alt,
            &runs_of(a, &alt.fit),
            gate,
        );
        let Some(s) = sc.first().filter(|s| s.delta_bic.is_finite()) else {
            continue;
        };
        let k = alt.dropped.name();
        if s.delta_bic >= -threshold {
            return Some(Repair::LeansOn(k, s.delta_bic));
        }
        let swap = s.delta_bic + alt.cost();
        if swap <= best.delta_bic.max(0.0) {
            return Some(Repair::StandsIn(k, swap));
        }
    }
    None
}
