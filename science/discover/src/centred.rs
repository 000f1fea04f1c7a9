//! A term centred in T1 (`mu_tension_bump`, [`crate::library::centred`]): its centre profiled
//! (`Options::bump_centres`), and its shape checked against a step.
//!
//! Where a contact regime peaks is not known before the data. With `bump_centres` = n > 1 the
//! column is built at n centres T̃1·e^{k/4} (k = −(n−1)/2 … (n−1)/2, T̃1 the design's
//! geometric-mean T1), the one that fits the model's residuals best (beside its columns) is
//! kept, and the search pays for all n (each a model tried at every step). With n = 1 the
//! centre is T̃1, as in s41. On seed 26 the bump planted at 6 N (the designs' T̃1 3.8–4.7 N)
//! removes 12–61 % of the lack of fit with its centre at T̃1 and 25–100 % at 6 N: with n = 1
//! the search declines it as a partial mimic in 11 of 12 sets.
//!
//! A free centre also lets a bump stand in for a step of mu in tension (a regime change: mu
//! changes at a tension and stays changed), which the library cannot express: with 3 centres
//! a term was proposed in 5 of the 12 regime-change sets of seed 26 (s41: 2). What makes a bump
//! a bump is that mu comes back on both sides. So a profiled bump is proposed only if it stays
//! past the engine's bar, paid for the steps tried (extended BIC), beside the best-fitting
//! step of mu (logistic in ln T1, at the same centres, of the bump's width down to a quarter of
//! it): that declined the bump in those 3 sets, in 2 of the 12 bump sets and in 1 mixed set.

use crate::columns::Base;
use crate::library::{centres, Term};
use crate::screen::{within_evidence, Projector};

/// A centred term's column at the centre that fits `base`'s residuals best beside the model's
/// columns (the projector `proj`), and that centre.
pub(crate) fn best_centre(base: &Base, t: &Term, proj: &Projector, n: usize) -> (Vec<f64>, f64) {
    let t1_ref = base.rows.first().map_or(1.0, |r| r.t1_ref);
    if n <= 1 {
        return (base.column(t), t1_ref);
    }
    let e = proj.project(base, &base.e);
    let cols = centres(t1_ref, n).map(|c| (base.column_at(t, Some(c)), c));
    best_of(base, proj, &e, cols).unwrap_or_else(|| (base.column(t), t1_ref))
}

/// The column (and its centre) among `cols` that removes most of the projected residuals `e`.
fn best_of(
    base: &Base,
    proj: &Projector,
    e: &[f64],
    cols: impl Iterator<Item = (Vec<f64>, f64)>,
) -> Option<(Vec<f64>, f64)> {
    let dot = |u: &[f64], v: &[f64]| -> f64 { (0..u.len()).map(|i| base.w[i] * u[i] * v[i]).sum() };
    let mut best: Option<(f64, Vec<f64>, f64)> = None;
    for (x, c) in cols {
        let xt = proj.project(base, &x);
        let (sxe, sxx) = (dot(&xt, e), dot(&xt, &xt));
        let gain = if sxx > 0.0 { sxe * sxe / sxx } else { 0.0 };
        if gain.is_finite() && best.as_ref().is_none_or(|b| gain > b.0) {
            best = Some((gain, x, c));
        }
    }
    best.map(|(_, x, c)| (x, c))
}

/// The widths of the steps of mu tried against a profiled bump (logistic scale ×1.7 in ln T1):
/// the bump's, down to a quarter of it (a regime change may be sharp).
const STEP_WIDTHS_LN: [f64; 3] = [0.5, 0.25, 0.125];

/// The column of a step of mu in tension at `centre` (N): mu·(1 + θ·L(ln(T1/centre)/width)),
/// L the logistic of scale 1/1.7 (close to the normal CDF).
fn step_column(base: &Base, centre: f64, width_ln: f64) -> Vec<f64> {
    (0..base.d.n())
        .map(|i| {
            let z = (base.rows[i].t1.max(0.05) / centre).ln() / width_ln;
            let v = base.a[i] * base.mu_row[i] / (1.0 + (-1.7 * z).exp());
            if v.is_finite() {
                v
            } else {
                0.0
            }
        })
        .collect()
}

/// A profiled bump's column `x` beside the best-fitting step of mu (every width of
/// [`STEP_WIDTHS_LN`] at each of the `n` centres), given the model's columns `shared` and its
/// residuals `e` (projected off them): its ΔBIC there, the steps tried, and the step's centre.
/// None when it cannot be computed.
pub(crate) fn beside_step(
    base: &Base,
    (shared, e): (&[Vec<f64>], &[f64]),
    x: &[f64],
    n: usize,
) -> Option<(f64, usize, f64)> {
    let t1_ref = base.rows.first().map_or(1.0, |r| r.t1_ref);
    let proj = Projector::new(base, shared);
    let steps = STEP_WIDTHS_LN
        .iter()
        .flat_map(|&w| centres(t1_ref, n).map(move |c| (step_column(base, c, w), c)));
    let (step, at) = best_of(base, &proj, e, steps)?;
    let mut cols = shared.to_vec();
    cols.push(step);
    let proj = Projector::new(base, &cols);
    let (xt, et) = (proj.project(base, x), proj.project(base, e));
    let (_, _, dbic, _) = within_evidence(base, &xt, &et, cols.len())?;
    dbic.is_finite()
        .then_some((dbic, STEP_WIDTHS_LN.len() * n.max(1), at))
}
