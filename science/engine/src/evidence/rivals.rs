//! Rival explanations: a selected within-run effect that another candidate, put in its place,
//! explains almost as well.
//!
//! Forward selection names the best-fitting set, but two shapes can be nearly alike on a given
//! design: a drift with time and contact heating when every run's tension only rises (time and
//! the friction load grow together), a T1 and a T2 zero offset when the wraps are close (they
//! differ only in how the wrap amplifies them). The wander of mu inside runs then decides
//! between them by chance. The engine compares the final set with each selected effect
//! swapped for each other candidate (both sets have as many parameters, so the comparison is
//! the quasi-likelihood ratio alone, on the χ²₁ scale as every other ΔBIC here): a candidate
//! whose swapped set is within [`RIVAL_GAP`] of the found one, and that the data support on
//! its own, is reported beside the found effect as a rival the data cannot rule out.

use super::candidates::{practically_relevant, ThetaMap};
use super::design::Design;
use super::select::Swap;
use super::within::WithinFit;
use super::Evidence;
use crate::fit::stats::chi2_of_f;
use capstan_physics::{EffectKind, Rivalry};
use serde::Serialize;
use std::collections::BTreeMap;

/// A swapped set within this many BIC units of the found one is a rival (calibrated on
/// generated data sets, `docs/README-diagnose.md`).
pub const RIVAL_GAP: f64 = 6.0;

/// A candidate that, in place of a found effect, explains the data almost as well.
#[derive(Clone, Debug, Serialize)]
pub struct Rival {
    /// The found effect it could replace.
    pub instead_of: &'static str,
    /// The rival candidate.
    pub effect: &'static str,
    /// Its fitted catalogue parameter in the found effect's place.
    pub parameters: BTreeMap<&'static str, f64>,
    /// How much less the data support the set with the rival (ΔBIC; 0 to [`RIVAL_GAP`]: not
    /// enough to rule it out; below 0: it fits better but is not supported beside the others).
    pub delta_bic: f64,
    /// Why this design cannot separate the two, where the design says so.
    pub reason: Option<String>,
    /// The found effect.
    #[serde(skip)]
    pub instead_of_kind: EffectKind,
    /// The rival.
    #[serde(skip)]
    pub kind: EffectKind,
}

/// The rivals of the found within-run effects of `fit` among its `swaps`; `alone` holds every
/// candidate's evidence on its own (a rival must be supported there).
pub fn rivals(
    d: &Design,
    fit: &WithinFit,
    swaps: &[Swap],
    alone: &[Evidence],
    gap: f64,
) -> Vec<Rival> {
    let n = d.n() as f64;
    let dof = (d.units.len() as f64 - 1.0).max(1.0);
    let mut out: Vec<Rival> = swaps
        .iter()
        .filter_map(|s| {
            let found = fit.maps.get(s.slot)?.kind;
            let supported_alone = alone.iter().any(|e| e.kind == s.kind && e.supported);
            let map = ThetaMap::for_kind(s.kind, d);
            let plausible = practically_relevant(s.kind, s.value, d)
                && !map.at_physical_limit(map.theta(s.value));
            // A swap whose fit failed (a non-finite WRSS) is no evidence either way.
            let lr = n * (s.wrss / fit.wrss).ln();
            if !(lr.is_finite() && fit.wrss > 0.0) {
                return None;
            }
            let scaled = lr.abs() / fit.c_hat(s.slot);
            let delta_bic = chi2_of_f(scaled, 1.0, dof).copysign(lr);
            (supported_alone && plausible && delta_bic < gap).then(|| {
                let mut parameters = BTreeMap::new();
                if let Some(p) = s.kind.parameter() {
                    parameters.insert(p, s.value);
                }
                Rival {
                    instead_of: found.name(),
                    effect: s.kind.name(),
                    parameters,
                    delta_bic,
                    reason: reason(found, s.kind, d, &fit.mu),
                    instead_of_kind: found,
                    kind: s.kind,
                }
            })
        })
        .collect();
    out.sort_by(|a, b| a.delta_bic.total_cmp(&b.delta_bic));
    out
}

/// Why the design cannot tell `a` from `b`, for the pairs whose reason is known
/// ([`capstan_physics::rivalry`]; `mu`: the runs' mu, for the wraps' amplification).
fn reason(a: EffectKind, b: EffectKind, d: &Design, mu: &[f64]) -> Option<String> {
    match capstan_physics::rivalry(a, b)? {
        Rivalry::OneWay(why) => (!d.has_both_directions()).then(|| why.to_string()),
        Rivalry::Amplified { before, after } => {
            let mu_bar = crate::fit::stats::mean(mu);
            let wraps = d.wraps();
            let amp = |deg: f64| (mu_bar * deg.to_radians()).exp();
            let (lo, hi) = (wraps.first()?, wraps.last()?);
            Some(format!("{before}{:.1} to {:.1}{after}", amp(*lo), amp(*hi)))
        }
    }
}
