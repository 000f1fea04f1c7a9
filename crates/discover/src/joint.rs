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

use crate::columns::Base;
use capstan_engine::evidence::within::{self, WithinFit};
use capstan_engine::evidence::{Assessment, Level};
use capstan_friction::EffectKind;

/// The catalogue without one of its within-run effects, refitted and linearised.
pub struct Alternative<'a> {
    /// The effect dropped.
    pub dropped: EffectKind,
    /// The engine's evidence for it given the other selected effects (ΔBIC, negative: wanted).
    pub dropped_delta_bic: f64,
    /// The refit without it.
    pub fit: WithinFit,
    /// Its linearisation.
    pub base: Base<'a>,
}

/// One alternative per within-run effect the engine selected (with finite evidence).
pub fn alternatives(a: &Assessment) -> Vec<Alternative<'_>> {
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
    bar: f64,
    max_r2_model: f64,
    best_addition: f64,
) -> Option<Swap> {
    let mut best: Option<Swap> = None;
    for (i, (alt, sc)) in alts.iter().zip(screens).enumerate() {
        for s in sc.iter().filter(|s| {
            s.level == crate::screen::Level::WithinRun
                && s.sign_ok
                && s.r2_model <= max_r2_model
                && s.replicate.as_ref().is_none_or(|r| r.delta_bic < bar)
        }) {
            let swap = s.delta_bic - alt.dropped_delta_bic;
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
