//! The joint search: a library term may *displace* a catalogue effect instead of only adding to
//! what the engine's selection chose.
//!
//! The engine's forward selection runs first and takes the credit for anything a catalogue
//! effect can mimic (note-26: `bending_stiffness` for a T1 tare per capstan, the T2 offset for a
//! low-force error, a spurious `thermal_drift` for settling). So, for every within-run
//! catalogue effect k the engine selected, the catalogue is refitted without it (the engine's
//! own within-run fit, exactly, from the selected fit's θ and mu), linearised again, and every
//! within-run library term is screened on that model. The swap's evidence is the BIC of
//! "catalogue − k + term" against the catalogue, by the same statistics:
//!
//! ΔBIC_swap = ΔBIC(term | catalogue − k) − ΔBIC(k | the other effects),
//!
//! the second being the engine's own evidence for k (negative: the data want k). The search
//! pays for every model it tries: the extended-BIC bar counts p terms × (1 + K) models, K the
//! droppable effects, for additions and swaps alike. A swap is taken only when it beats the
//! best addition and passes that bar; the term must then pass everything an added term must
//! (its physical sign, separability, the replicate runs, stability, held-out cords, lack of
//! fit), on the model without k, and its held-out gain is against the engine's catalogue.
//!
//! **Restores** (since s41, `Options::restore`): the outside physics can also hide a catalogue
//! effect from the engine (a T2 cell bowed upwards cancels the curvature of contact heating,
//! and the engine leaves heating out). So for every within-run catalogue effect k′ the engine
//! tested and did not select, the catalogue is refitted with it too, and every within-run term
//! screened on "catalogue + k′": ΔBIC = ΔBIC(term | catalogue + k′) + ΔBIC(k′ | catalogue), the
//! second the engine's own evidence for k′ given its selection (positive: not wanted alone).
//! They are models tried like the others: the bar counts p·(1 + K + K′).

use crate::columns::Base;
use capstan_engine::evidence::candidates::ThetaMap;
use capstan_engine::evidence::within::{self, WithinFit};
use capstan_engine::evidence::{Assessment, Level};
use capstan_physics::EffectKind;

/// How an alternative changes the catalogue.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Change {
    /// One of its within-run effects taken out.
    Dropped,
    /// A within-run effect the engine did not select put in.
    Restored,
}

/// The catalogue without one of its within-run effects (or with one it did not select),
/// refitted and linearised.
pub struct Alternative<'a> {
    /// The effect dropped or restored.
    pub dropped: EffectKind,
    /// Dropped or restored.
    pub change: Change,
    /// The engine's evidence for it: given the other selected effects when dropped (ΔBIC,
    /// negative: wanted), given the catalogue when restored (positive: not wanted alone).
    pub dropped_delta_bic: f64,
    /// The refit without it.
    pub fit: WithinFit,
    /// Its linearisation.
    pub base: Base<'a>,
}

impl Alternative<'_> {
    /// ΔBIC of the changed catalogue against the catalogue as selected (before any term).
    pub fn cost(&self) -> f64 {
        match self.change {
            Change::Dropped => -self.dropped_delta_bic,
            Change::Restored => self.dropped_delta_bic,
        }
    }
}

/// One alternative per within-run effect the engine selected (with finite evidence), and with
/// `restore` one per within-run effect it tested and did not select.
pub fn alternatives(a: &Assessment, restore: bool) -> Vec<Alternative<'_>> {
    let mut out = dropped(a);
    if restore {
        out.extend(restored(a));
    }
    out
}

/// The catalogue with each within-run effect the engine tested and left out.
fn restored(a: &Assessment) -> Vec<Alternative<'_>> {
    let d = &a.design;
    let fit = &a.fit;
    a.evidence
        .iter()
        .filter(|ev| !ev.selected && ev.level == Level::WithinRun && ev.delta_bic.is_finite())
        .filter(|ev| !fit.maps.iter().any(|m| m.kind == ev.kind))
        .filter_map(|ev| {
            let mut maps = fit.maps.clone();
            maps.push(ThetaMap::for_kind(ev.kind, d));
            let mut theta = fit.theta.clone();
            theta.push(maps.last()?.theta(ev.value));
            let refit = within::fit(d, &maps, &theta, &fit.mu, &a.weights);
            let ok = refit.wrss.is_finite() && refit.mu.iter().all(|m| m.is_finite() && *m > 0.0);
            ok.then_some((ev.kind, ev.delta_bic, refit))
        })
        .map(|(kind, delta_bic, fit)| {
            let base = Base::new(d, &fit, &a.weights.w);
            Alternative {
                dropped: kind,
                change: Change::Restored,
                dropped_delta_bic: delta_bic,
                fit,
                base,
            }
        })
        .collect()
}

/// The catalogue without each of its within-run effects.
fn dropped(a: &Assessment) -> Vec<Alternative<'_>> {
    let d = &a.design;
    let fit = &a.fit;
    (0..fit.k())
        .filter_map(|j| {
            let kind = fit.maps[j].kind;
            let ev = a.evidence_of(kind)?;
            if ev.level != Level::WithinRun || !ev.delta_bic.is_finite() {
                return None;
            }
            let keep: Vec<usize> = (0..fit.k()).filter(|&i| i != j).collect();
            let maps: Vec<_> = keep.iter().map(|&i| fit.maps[i]).collect();
            let theta: Vec<f64> = keep.iter().map(|&i| fit.theta[i]).collect();
            let refit = within::fit(d, &maps, &theta, &fit.mu, &a.weights);
            if !(refit.wrss.is_finite() && refit.mu.iter().all(|m| m.is_finite() && *m > 0.0)) {
                return None;
            }
            Some((kind, ev.delta_bic, refit))
        })
        .map(|(dropped, dropped_delta_bic, fit)| {
            // The linearisation borrows the design only; the fit is kept beside it.
            let base = Base::new(d, &fit, &a.weights.w);
            Alternative {
                dropped,
                change: Change::Dropped,
                dropped_delta_bic,
                fit,
                base,
            }
        })
        .collect()
}

/// The swap the search takes: alternative `alt`, library term `term`.
#[derive(Clone, Copy, Debug)]
pub struct Swap {
    /// Index into the alternatives.
    pub alt: usize,
    /// Index into the library.
    pub term: usize,
    /// ΔBIC of "catalogue − dropped + term" against the catalogue.
    pub delta_bic: f64,
}

/// A displaced catalogue effect, as the answer states it.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Displaced {
    /// The catalogue effect the term replaces.
    pub effect: &'static str,
    /// The engine's evidence for that effect given the other selected ones (ΔBIC).
    pub effect_delta_bic: f64,
    /// ΔBIC of the catalogue with the term in its place against the catalogue as selected.
    pub delta_bic_swap: f64,
}

/// The best swap over `alts` whose term is past `bar` as a swap, keeps its physical sign, is
/// separable, is shared by the replicate runs (on the model without the effect), and beats
/// `best_addition` (the best addition's ΔBIC against the catalogue); None if there is none.
pub fn best_swap(
    alts: &[Alternative<'_>],
    screens: &[Vec<crate::screen::Screen>],
    gate: crate::replicate::Gate,
    max_r2_model: f64,
    best_addition: f64,
) -> Option<Swap> {
    let bar = gate.bar;
    let mut best: Option<Swap> = None;
    for (i, (alt, sc)) in alts.iter().zip(screens).enumerate() {
        for s in sc.iter().filter(|s| {
            s.level == crate::screen::Level::WithinRun
                && s.sign_ok
                && s.r2_model <= max_r2_model
                && gate.lets_through(s.replicate.as_ref())
        }) {
            let swap = s.delta_bic + alt.cost();
            if swap < bar && swap < best_addition && best.is_none_or(|b| swap < b.delta_bic) {
                best = Some(Swap {
                    alt: i,
                    term: s.term,
                    delta_bic: swap,
                });
            }
        }
    }
    best
}
