//! The catalogue re-selected around a term: neither absorbs the other.
//!
//! The engine's forward selection runs before the search and sees the outside physics too: a
//! bump of mu in tension or a bowed T2 cell makes it take effects the truth does not hold
//! (bending stiffness, a sensor gain) or leave out one it does (contact heating, whose
//! curvature a bowed cell of the other sign cancels). The term found is then judged beside the
//! wrong catalogue, and the lack of fit they leave together stays open: the term looks like a
//! partial mimic although it is the physics.
//!
//! So once a within-run term has passed its screen, the replicate runs, stability and held-out
//! cords, the term (and any proposed before it) is taken out of the data to first order,
//! T2 − θ̃·x (x = ∂T2/∂θ, the search's own column), and the engine selects its catalogue on
//! what is left, as `diagnose` would on data without the term. θ̃ is the term's estimate beside
//! every within-run effect of the catalogue, selected or not (their columns at no effect): the
//! screen's θ̂ beside a wrong catalogue carries what the missing effects would have explained
//! (a bump of mu estimated beside no heating takes some of the heating's curvature). If it selects another set, that
//! catalogue is refitted on the data as measured, the term screened again beside it (with the
//! earlier terms), and the lack of fit read from the two together. The term must still be past
//! the engine's bar there: if the re-selected catalogue explains it, it is declined (the
//! catalogue absorbs it). The effects the engine selects given the terms are the answer's
//! `catalogue_given_terms`.

use crate::checks::lack_of_fit_with;
use crate::columns::Base;
use crate::model::{catalogue_covariate, classify, runs_of, screen_all, state_of, State};
use crate::replicate::Gate;
use crate::screen::{Projector, Screen};
use capstan_data::Dataset;
use capstan_engine::evidence::adequacy::LackOfFit;
use capstan_engine::evidence::candidates::ThetaMap;
use capstan_engine::evidence::{self, within, Assessment};
use capstan_physics::EffectKind;

/// The catalogue the engine selects with the terms taken out of the data, and the term beside it.
pub(crate) struct Reselected {
    /// The effects the engine selects on the data without the terms.
    pub(crate) selected: Vec<EffectKind>,
    /// The term's screen on the data as measured, beside that catalogue and the earlier terms
    /// (None: not testable there).
    pub(crate) screen: Option<Screen>,
    /// The lack of fit against the replicate runs with that catalogue and the terms.
    pub(crate) lof_after: Option<LackOfFit>,
}

/// A term taken out of the data: its library index, θ̂ and raw column.
pub(crate) type Taken<'x> = (usize, f64, &'x [f64]);

/// Rounds of re-selection: take the term out, select, re-estimate the term beside the new
/// catalogue, take it out again, until the selection repeats.
const ROUNDS: usize = 3;

/// The catalogue re-selected with `terms` taken out of `data` (the last one is judged), or None
/// when the engine selects the same effects (nothing changes). The last term's θ starts from
/// its estimate beside every within-run effect and is re-estimated beside each new selection
/// (up to [`ROUNDS`]).
pub(crate) fn reselect(
    data: &Dataset,
    (a, base0, shared): (&Assessment, &Base, &[Vec<f64>]),
    engine: &evidence::Options,
    terms: &[Taken<'_>],
    (gate, centres): (Gate, usize),
) -> Option<Reselected> {
    let &(_, theta0, x0) = terms.last()?;
    let earlier = &terms[..terms.len() - 1];
    let mut theta = theta_beside_every_effect(a, base0, shared, x0).unwrap_or(theta0);
    let mut x: Vec<f64> = x0.to_vec();
    let mut prev: Vec<EffectKind> = a.selected.clone();
    let mut out: Option<Reselected> = None;
    for _ in 0..ROUNDS {
        let mut without = data.clone();
        for &(_, th, col) in earlier.iter().chain(std::iter::once(&(0, theta, &x[..]))) {
            for (p, xi) in without.pairs.iter_mut().zip(col) {
                p.t2_n -= th * xi;
            }
        }
        let b = evidence::assess(&without, engine);
        if same(&b.selected, &prev) {
            break;
        }
        let Some((r, column)) = beside(a, &b, terms, (gate, centres)) else {
            break;
        };
        prev = b.selected.clone();
        let next = r.screen.as_ref().map(|s| s.theta);
        out = Some(r);
        match (next, column) {
            (Some(th), Some(col)) => (theta, x) = (th, col),
            _ => break,
        }
    }
    out.filter(|r| !same(&r.selected, &a.selected))
}

/// The same effects, in any order?
fn same(x: &[EffectKind], y: &[EffectKind]) -> bool {
    x.len() == y.len() && x.iter().all(|k| y.contains(k))
}

/// The catalogue `b` selected refitted on the data as measured, the last of `terms` screened
/// beside it (and the earlier ones), the lack of fit with them; and the term's raw column on
/// that catalogue's linearisation.
fn beside(
    a: &Assessment,
    b: &Assessment,
    terms: &[Taken<'_>],
    (gate, centres): (Gate, usize),
) -> Option<(Reselected, Option<Vec<f64>>)> {
    let &(target, _, _) = terms.last()?;
    let d = &a.design;
    let fit = within::fit(d, &b.fit.maps, &b.fit.theta, &b.fit.mu, &a.weights);
    if !(fit.wrss.is_finite() && fit.mu.iter().all(|m| m.is_finite() && *m > 0.0)) {
        return None;
    }
    let base = Base::new(d, &fit, &a.weights.w);
    let (testable, _) = classify(&base, centres);
    let covs: Vec<Vec<f64>> = b
        .selected
        .iter()
        .filter_map(|&k| catalogue_covariate(b, k))
        .collect();
    let mut st = state_of(&base, &covs);
    earlier_in(&base, &mut st, &terms[..terms.len() - 1], &testable);
    let proj = Projector::new(&base, &st.shared);
    let c = testable.iter().find(|c| c.term == target);
    let screen = c.and_then(|c| {
        screen_all(
            &base,
            std::slice::from_ref(c),
            &proj,
            &st,
            &runs_of(a, &fit),
            gate,
        )
        .into_iter()
        .next()
    });
    let column = c.and_then(|c| c.column.clone());
    let lof_after = match (&column, &screen) {
        (Some(x), Some(s)) => {
            let xt = proj.project(&base, x);
            lack_of_fit_with((d, &base), &st, s.theta, Some(&xt), &None)
        }
        _ => None,
    };
    let r = Reselected {
        selected: b.selected.clone(),
        screen,
        lof_after,
    };
    Some((r, column))
}

/// The term's θ (column `x`) fitted beside the model's shared columns `shared` and the column
/// of every within-run catalogue effect the engine tested and did not select (at no effect):
/// weighted least squares on the residuals of `base`, every run's mu projected out.
fn theta_beside_every_effect(
    a: &Assessment,
    base: &Base,
    shared: &[Vec<f64>],
    x: &[f64],
) -> Option<f64> {
    let cols = every_effect(a, base, shared);
    let proj = Projector::new(base, &cols);
    let xt = proj.project(base, x);
    let et = proj.project(base, &base.e);
    let sxx: f64 = (0..xt.len()).map(|i| base.w[i] * xt[i] * xt[i]).sum();
    let sxe: f64 = (0..xt.len()).map(|i| base.w[i] * xt[i] * et[i]).sum();
    let theta = sxe / sxx;
    theta.is_finite().then_some(theta)
}

/// The share of the lack of fit's systematic variance a term (column `x`) removes beside every
/// within-run effect of the catalogue (the model's `shared` columns and the column of every
/// effect the engine tested and did not select, linearised at no effect): what the term adds
/// to a catalogue that cannot be missing an effect. None without a lack of fit to judge.
pub(crate) fn share_beside_every_effect(
    a: &Assessment,
    base: &Base,
    shared: &[Vec<f64>],
    x: &[f64],
) -> Option<f64> {
    let d = &a.design;
    let cols = every_effect(a, base, shared);
    let proj = Projector::new(base, &cols);
    let et = proj.project(base, &base.e);
    let z0: Vec<f64> = (0..d.n()).map(|i| et[i] * base.w[i].sqrt()).collect();
    let before = capstan_engine::evidence::adequacy::lack_of_fit(d, &z0, cols.len())?;
    let xt = proj.project(base, x);
    let sxx: f64 = (0..xt.len()).map(|i| base.w[i] * xt[i] * xt[i]).sum();
    let sxe: f64 = (0..xt.len()).map(|i| base.w[i] * xt[i] * et[i]).sum();
    let theta = sxe / sxx;
    let z1: Vec<f64> = (0..d.n())
        .map(|i| (et[i] - theta * xt[i]) * base.w[i].sqrt())
        .collect();
    let after = capstan_engine::evidence::adequacy::lack_of_fit(d, &z1, cols.len() + 1)?;
    let share = 1.0 - (after.systematic_ratio / before.systematic_ratio).powi(2);
    (share.is_finite() && before.systematic_ratio > 0.0).then_some(share)
}

/// The model's shared columns and the column of every within-run catalogue effect the engine
/// tested and did not select (at no effect).
fn every_effect(a: &Assessment, base: &Base, shared: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let d = &a.design;
    let mut fit = a.fit.clone();
    let mut extra = 0;
    for ev in a
        .evidence
        .iter()
        .filter(|ev| !ev.selected && ev.level == evidence::Level::WithinRun)
        .filter(|ev| !a.fit.maps.iter().any(|m| m.kind == ev.kind))
    {
        let map = ThetaMap::for_kind(ev.kind, d);
        fit.theta.push(map.theta(ev.kind.neutral_value()));
        fit.maps.push(map);
        extra += 1;
    }
    let ext = Base::new(d, &fit, &base.w);
    let k0 = ext.b.len() - extra;
    let mut cols: Vec<Vec<f64>> = shared.to_vec();
    cols.extend(ext.b[k0..].iter().cloned());
    cols
}

/// The earlier terms in the state (their columns on this catalogue's linearisation).
fn earlier_in(
    base: &Base,
    st: &mut State,
    earlier: &[Taken<'_>],
    testable: &[crate::model::Testable],
) {
    for &(term, _, _) in earlier {
        if let Some(x) = testable
            .iter()
            .find(|c| c.term == term)
            .and_then(|c| c.column.clone())
        {
            st.shared.push(x);
            st.used.push(term);
            st.theta_used.push(0.0);
        }
    }
    st.e = Projector::new(base, &st.shared).project(base, &base.e);
}
