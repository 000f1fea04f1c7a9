//! A design's chance of deciding: campaigns simulated end to end under each hypothesis
//! (`host-sim`: the firmware's protocol, sampling and conditioning against the plant, with the
//! data's own cord and run scatter and the thesis rig's within-run noise), diagnosed by the same
//! engine as the data, and scored by the planted-truth scorer (`capstan-validation`). A campaign
//! *decides* when it names its hypothesis's effects and nothing else, with no rival left and
//! nothing unexplained.

use crate::design::Design;
use crate::hypotheses::Hypothesis;
use crate::world::campaign;
pub use crate::world::World;
use capstan_sim::campaign::CampaignConfig;
use capstan_sim::plant::rng::derive_seed;
use capstan_validation::cases::{Case, Class};
use capstan_validation::score::{self, Outcome};
use serde::Serialize;
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, Ordering};

/// How often campaigns under one hypothesis decided, and what they said otherwise.
#[derive(Clone, Debug, Serialize)]
pub struct Rate {
    /// The hypothesis (its label).
    pub hypothesis: String,
    /// Campaigns simulated.
    pub campaigns: usize,
    /// Campaigns that named the hypothesis alone.
    pub decided: usize,
    /// `decided / campaigns`.
    pub p_decide: f64,
    /// The other answers, with how often each was given.
    pub otherwise: BTreeMap<String, usize>,
    /// Why no campaign was simulated, if none was: the design cannot test one of the
    /// hypothesis's effects (the engine never names an effect its design cannot test, so the
    /// chance is 0 without one), or it cannot test another hypothesis's and so cannot decide.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub not_simulated: Option<String>,
}

/// The simulator's configuration of `design` under `h`.
pub fn config(design: &Design, h: &Hypothesis, world: &World, seed: u64) -> CampaignConfig {
    campaign(design, &h.effects, world, seed)
}

/// `reps` campaigns of `design` under each hypothesis, seeds from `seed` and `salt`; rates in
/// hypothesis order. A hypothesis with an effect the design cannot test gets 0 without
/// simulation.
pub fn rates(
    design: &Design,
    hypotheses: &[Hypothesis],
    world: &World,
    reps: usize,
    (seed, salt): (u64, u64),
    threads: usize,
) -> Result<Vec<Rate>, crate::PlanError> {
    rates_until(design, hypotheses, world, reps, (seed, salt), threads, None)
}

/// [`rates`], checking `stop` before every `threads` campaigns: set, it returns
/// [`crate::PlanError::Stopped`] within one campaign's time (a protocol's campaigns took minutes on a
/// large design, and a signal waited for all of them).
pub fn rates_until(
    design: &Design,
    hypotheses: &[Hypothesis],
    world: &World,
    reps: usize,
    (seed, salt): (u64, u64),
    threads: usize,
    stop: Option<&AtomicBool>,
) -> Result<Vec<Rate>, crate::PlanError> {
    let mut cases = Vec::new();
    let untestable = |h: &Hypothesis| untestable(design, h, world);
    let simulated: Vec<&Hypothesis> = hypotheses
        .iter()
        .filter(|h| untestable(h).is_none())
        .collect();
    for (i, h) in hypotheses.iter().enumerate() {
        if untestable(h).is_some() {
            continue;
        }
        for r in 0..reps {
            let s = derive_seed(seed, &[salt, i as u64, r as u64]);
            cases.push(Case {
                seed: s,
                class: if h.effects.is_empty() {
                    Class::Clean
                } else {
                    Class::Single
                },
                effects: h.effects.clone(),
                outside: None,
                config: config(design, h, world, s),
                drop_columns: Vec::new(),
            });
        }
    }
    let mut outcomes = Vec::with_capacity(cases.len());
    for chunk in cases.chunks(threads.max(1)) {
        if stop.is_some_and(|s| s.load(Ordering::SeqCst)) {
            return Err(crate::PlanError::Stopped);
        }
        outcomes.extend(
            score::run(chunk, threads, capstan_engine::diagnose::diagnose)
                .map_err(crate::PlanError::Validation)?,
        );
    }
    let mut chunks = outcomes.chunks(reps.max(1));
    debug_assert_eq!(chunks.len(), simulated.len());
    Ok((hypotheses.iter())
        .map(|h| match untestable(h) {
            Some(why) => Rate {
                hypothesis: h.label(),
                campaigns: 0,
                decided: 0,
                p_decide: 0.0,
                otherwise: BTreeMap::new(),
                not_simulated: Some(why),
            },
            None => rate(h, chunks.next().unwrap_or(&[])),
        })
        .collect())
}

/// Why `design` cannot test one of the effects of `h`, if it cannot.
pub fn untestable(design: &Design, h: &Hypothesis, world: &World) -> Option<String> {
    (h.effects.iter()).find_map(|e| {
        (design.untestable(e.kind, &world.protocol))
            .map(|why| format!("{} not testable: {why}", e.kind.name()))
    })
}

/// The rates of a design not simulated because it cannot test `why` (0: it cannot decide).
pub fn not_simulated(hypotheses: &[Hypothesis], why: &str) -> Vec<Rate> {
    (hypotheses.iter())
        .map(|h| Rate {
            hypothesis: h.label(),
            campaigns: 0,
            decided: 0,
            p_decide: 0.0,
            otherwise: BTreeMap::new(),
            not_simulated: Some(why.to_string()),
        })
        .collect()
}

fn rate(h: &Hypothesis, outcomes: &[Outcome]) -> Rate {
    let mut otherwise = BTreeMap::new();
    let mut decided = 0;
    for o in outcomes {
        if decides(o) {
            decided += 1;
        } else {
            *otherwise.entry(answer(o)).or_insert(0) += 1;
        }
    }
    Rate {
        hypothesis: h.label(),
        campaigns: outcomes.len(),
        decided,
        p_decide: decided as f64 / outcomes.len().max(1) as f64,
        otherwise,
        not_simulated: None,
    }
}

/// Named the truth alone: right set, no rival, nothing unexplained.
pub fn decides(o: &Outcome) -> bool {
    o.correct() && o.rivals.is_empty()
}

/// A diagnosis's answer in a few words: the set named, its rivals, unexplained.
fn answer(o: &Outcome) -> String {
    let mut names: Vec<&str> = o.found_kinds().iter().map(|k| k.name()).collect();
    if names.is_empty() {
        names.push("euler_eytelwein");
    }
    let mut s = names.join("+");
    for (of, rival, _) in &o.rivals {
        s += &format!(" (rival {rival} for {of})");
    }
    if o.unexplained {
        s += " + unexplained";
    }
    s
}
