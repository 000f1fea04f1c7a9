//! `capstan plan`: the experiment that decides. From a data set's diagnosis, the hypotheses it
//! leaves open ([`hypotheses`]); candidate protocols the rig can run, with or without a
//! physical change ([`candidates`]); and for each, the chance that a fresh campaign names the
//! true hypothesis and only it, estimated by simulating campaigns end to end under every
//! hypothesis and diagnosing them with the same engine ([`trial`]). The recommendation is the
//! protocol with the best worst-case chance (the fewer rig hours between near ties), or the
//! current design when it already decides.

pub mod candidates;
pub mod commands;
pub mod cords;
pub mod design;
mod error;
pub mod hypotheses;
pub mod trial;
pub mod world;

pub use error::PlanError;

use candidates::{candidates, Candidate, Design};
use capstan_data::Dataset;
use capstan_engine::diagnose::{self, Diagnosis};
use hypotheses::{open_hypotheses, untestable_kinds, Hypothesis, NotSimulated};
use serde::Serialize;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;
use trial::{rates_until, Rate, World};

/// A design decides when its worst-case chance of naming the truth alone is at least this.
pub const DECIDES: f64 = 0.9;

/// How to plan.
#[derive(Clone, Debug)]
pub struct Options {
    /// Simulated campaigns per hypothesis and protocol.
    pub reps: usize,
    /// Master seed of the simulated campaigns.
    pub seed: u64,
    /// Worker threads.
    pub threads: usize,
    /// Rig hours available (protocols needing more are ranked but not recommended).
    pub max_hours: Option<f64>,
    /// Also simulate how many cords each open question between cords needs (the larger part
    /// of the planner's time: sets of up to 80 cords).
    pub cords: bool,
    /// Set (by a signal): stop within one campaign ([`PlanError::Stopped`]).
    pub stop: Option<&'static AtomicBool>,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            reps: 8,
            seed: 1,
            threads: std::thread::available_parallelism().map_or(2, |n| n.get()),
            max_hours: None,
            cords: true,
            stop: None,
        }
    }
}

/// One candidate protocol with its chances.
#[derive(Clone, Debug, Serialize)]
pub struct Scored {
    /// The protocol and how to set it.
    #[serde(flatten)]
    pub candidate: Candidate,
    /// Rig time, h.
    pub rig_hours: f64,
    /// The `capstan simulate` arguments that reproduce the campaign's protocol.
    pub simulate_args: Vec<String>,
    /// The chance of naming each hypothesis alone when it is true.
    pub per_hypothesis: Vec<Rate>,
    /// For each pair of hypotheses, the chance of deciding between them: the mean of the two
    /// chances of naming each alone when it is true.
    pub p_decide_pairs: Vec<PairChance>,
    /// The worst chance over the hypotheses.
    pub p_decide_worst: f64,
}

/// The chance of deciding between two hypotheses.
#[derive(Clone, Debug, Serialize)]
pub struct PairChance {
    /// One hypothesis.
    pub a: String,
    /// The other.
    pub b: String,
    /// The chance.
    pub p: f64,
}

/// The current design's chance.
#[derive(Clone, Debug, Serialize)]
pub struct Current {
    /// Its worst chance over the hypotheses.
    pub p_decide_worst: f64,
    /// Its rig time, h.
    pub rig_hours: f64,
}

/// A protocol the hours left out.
#[derive(Clone, Debug, Serialize)]
pub struct Beyond {
    /// Its name.
    pub name: String,
    /// Its worst chance over the hypotheses.
    pub p_decide_worst: f64,
    /// Its rig time, h.
    pub rig_hours: f64,
}

/// What `capstan plan` says.
#[derive(Clone, Debug, Serialize)]
pub struct Plan {
    /// The hypotheses simulated.
    pub hypotheses: Vec<Hypothesis>,
    /// What the data leave open that is not simulated, and why.
    pub not_simulated: Vec<NotSimulated>,
    /// What the planner had to assume.
    pub assumed: Vec<String>,
    /// Every candidate, best first.
    pub candidates: Vec<Scored>,
    /// The recommendation.
    pub recommended: Scored,
    /// The recommended protocol is the data's own: it already decides.
    pub current_decides: bool,
    /// Some candidate named every simulated hypothesis alone in at least one campaign (false:
    /// no protocol here decides, and the recommendation is only the least bad).
    pub any_decides: bool,
    /// Some campaign of some candidate named its hypothesis alone (false: none ever did).
    pub any_named: bool,
    /// The recommendation fits in `--hours` (false: nothing does; it is the shortest).
    pub within_hours: bool,
    /// With `--hours`: the best protocol beyond them, when it does better than the
    /// recommendation (what the hours cost).
    pub better_beyond_hours: Option<Beyond>,
    /// The data's own design.
    pub current_design: Current,
    /// Simulated campaigns per hypothesis and protocol behind each chance.
    pub reps: usize,
    /// How the chances were estimated.
    pub method: String,
    /// How many cords each open between-cord question needs (None: not asked, with why in
    /// `first`).
    pub cords: Option<cords::Cords>,
    /// Which answer comes first: the protocol's or the cords', and why.
    pub first: First,
    /// Wall time, s.
    pub elapsed_s: f64,
}

impl Plan {
    /// The cords question that comes first (the largest stake with a number of cords found),
    /// with its design.
    pub fn cords_first(&self) -> Option<(&cords::Question, &cords::Trial)> {
        let c = self.cords.as_ref()?;
        c.questions
            .iter()
            .find_map(|q| q.needed.as_ref().map(|t| (q, t)))
    }
}

/// Which recommendation comes first.
#[derive(Clone, Debug, Serialize)]
pub struct First {
    /// `cords` (more new cords) or `protocol` (the recommended protocol).
    pub which: &'static str,
    /// Why, with the stakes compared.
    pub why: String,
}

/// What a data set leaves open, without simulating anything (one diagnosis: cheap).
#[derive(Clone, Debug, Serialize)]
pub struct Open {
    /// The hypotheses the planner would simulate.
    pub hypotheses: Vec<Hypothesis>,
    /// What the data leave open that would not be simulated, and why.
    pub not_simulated: Vec<NotSimulated>,
    /// What the planner had to assume.
    pub assumed: Vec<String>,
}

/// The hypotheses `data` leave open (what [`plan`] would simulate), without simulating.
pub fn open(data: &Dataset) -> Open {
    let mut assumed = Vec::new();
    let d = diagnosis(data, &mut assumed);
    let world = world(&d, &mut assumed);
    let current = Design::of(&d, &mut assumed);
    let (hypotheses, not_simulated) = open_hypotheses(&d, &current, &world);
    Open {
        hypotheses,
        not_simulated,
        assumed,
    }
}

/// Plan the next campaign for `data`; `progress(done, total)` before every protocol and at the
/// end: it returns false to stop (the plan is then [`PlanError::Stopped`]).
pub fn plan(
    data: &Dataset,
    opts: &Options,
    progress: &mut dyn FnMut(usize, usize) -> bool,
) -> Result<Plan, PlanError> {
    let t0 = Instant::now();
    let mut assumed = Vec::new();
    let d = diagnosis(data, &mut assumed);
    let world = world(&d, &mut assumed);
    let current = Design::of(&d, &mut assumed);
    world::check(&current, &world, &d)?;
    let (hyps, not_simulated) = open_hypotheses(&d, &current, &world);
    let as_data = current.is_the_datas(&d);
    let cands = candidates(&current, &untestable_kinds(&d, &current, &world), as_data);
    // A protocol that cannot test some hypothesis cannot decide (worst case 0): when another
    // can test them all, it is not simulated (the data's own design always is).
    let blind = |c: &Candidate| {
        hyps.iter()
            .find_map(|h| trial::untestable(&c.design, h, &world))
    };
    let some_tests_all = cands.iter().any(|c| blind(c).is_none());
    let total = cands.len();
    let mut scored = Vec::new();
    for (i, c) in cands.into_iter().enumerate() {
        if !progress(i, total) {
            return Err(PlanError::Stopped);
        }
        let r = match blind(&c).filter(|_| i > 0 && some_tests_all) {
            Some(why) => trial::not_simulated(
                &hyps,
                &format!(
                    "{why}: this protocol cannot decide, and another can test every hypothesis"
                ),
            ),
            None => rates_until(
                &c.design,
                &hyps,
                &world,
                opts.reps,
                (opts.seed, i as u64),
                opts.threads,
                opts.stop,
            )?,
        };
        scored.push(score(c, r, &world));
    }
    // A stop asked for during the last protocol stops too: nothing is written.
    if !progress(total, total) {
        return Err(PlanError::Stopped);
    }
    let current_design = Current {
        p_decide_worst: scored[0].p_decide_worst,
        rig_hours: scored[0].rig_hours,
    };
    let current_decides = current_design.p_decide_worst >= DECIDES;
    let recommended = recommend(&scored, opts, current_decides).clone();
    let any_decides = scored.iter().any(|s| s.p_decide_worst > 0.0);
    let any_named = (scored.iter()).any(|s| s.per_hypothesis.iter().any(|r| r.decided > 0));
    let within_hours = opts.max_hours.is_none_or(|h| recommended.rig_hours <= h);
    let better_beyond_hours = better_beyond(&scored, &recommended, opts);
    scored.sort_by(|a, b| {
        (b.p_decide_worst.total_cmp(&a.p_decide_worst)).then(a.rig_hours.total_cmp(&b.rig_hours))
    });
    let (cords, first) = cords_first(data, &d, &current, &hyps, current_decides, opts, &world)?;
    if opts.stop.is_some_and(|s| s.load(Ordering::SeqCst)) {
        return Err(PlanError::Stopped);
    }
    Ok(Plan {
        hypotheses: hyps,
        not_simulated,
        assumed,
        candidates: scored,
        recommended,
        current_decides,
        any_decides,
        any_named,
        within_hours,
        better_beyond_hours,
        current_design,
        reps: opts.reps,
        method: method(opts.reps),
        cords,
        first,
        elapsed_s: t0.elapsed().as_secs_f64(),
    })
}

/// How many cords the data's open between-cord questions need, and which answer comes first:
/// the one whose open question moves T2 at the data's rows more (its stake). A rival left open
/// puts the protocol first (the named causes themselves are in question).
fn cords_first(
    data: &Dataset,
    d: &Diagnosis,
    current: &Design,
    hyps: &[Hypothesis],
    current_decides: bool,
    opts: &Options,
    world: &World,
) -> Result<(Option<cords::Cords>, First), PlanError> {
    let protocol = |why: String| First {
        which: "protocol",
        why,
    };
    if !opts.cords {
        return Ok((None, protocol("how many cords was not asked".into())));
    }
    if current.drive_v.len() > 1 {
        return Ok((
            None,
            protocol(
                "the cords question is simulated at one drive voltage; these data have several"
                    .into(),
            ),
        ));
    }
    if d.design.cords > design::MAX_CORDS_ASKED {
        let why = format!(
            "how many cords was not asked: these data hold {} cords, more than the {} \
             up to which the planner analyses them for it",
            d.design.cords,
            design::MAX_CORDS_ASKED
        );
        return Ok((None, protocol(why)));
    }
    if opts.stop.is_some_and(|s| s.load(Ordering::SeqCst)) {
        return Err(PlanError::Stopped);
    }
    let a = capstan_engine::analysis::run(
        data,
        capstan_engine::analysis::Options {
            threads: opts.threads,
            ..Default::default()
        },
    )
    .map_err(PlanError::Analysis)?;
    let c = cords::how_many(
        &a,
        (
            &current.diameters_mm,
            &current.wraps_deg,
            current.runs_per_cord,
        ),
        (opts.reps, opts.seed, opts.threads),
        &world.protocol,
    )?;
    let named: Vec<capstan_physics::EffectKind> =
        d.found_effects().iter().map(|e| e.kind).collect();
    let rival = hyps.iter().any(|h| h.origin.starts_with("rival"));
    let protocol_stake = hyps
        .iter()
        .filter(|h| h.origin != "named")
        .map(|h| {
            let extra: Vec<capstan_physics::Effect> = (h.effects.iter())
                .filter(|e| !named.contains(&e.kind))
                .copied()
                .collect();
            cords::stake_of(&a, &extra)
        })
        .fold(0.0, f64::max);
    let top = c.questions.iter().find(|q| q.needed.is_some());
    let first = match top {
        None => protocol(
            "no open question between cords reaches 80 % with the cords tried (or none is open)"
                .into(),
        ),
        Some(_) if rival => protocol(
            "a rival of a named cause is open: which causes the data hold comes first".into(),
        ),
        Some(q) if q.stake_n > protocol_stake || current_decides => First {
            which: "cords",
            why: format!(
                "{} moves T2 at these data's rows by {:.2} N (RMS), the protocols' open hypotheses by {:.2} N",
                q.question, q.stake_n, protocol_stake
            ),
        },
        Some(q) => protocol(format!(
            "the protocols' open hypotheses move T2 at these data's rows by {:.2} N (RMS), {} by {:.2} N",
            protocol_stake, q.question, q.stake_n
        )),
    };
    Ok((Some(c), first))
}

/// How the chances were estimated, in words.
fn method(reps: usize) -> String {
    format!(
        "simulation: {reps} campaigns per hypothesis and protocol, each run end to end on the \
         simulated rig (the firmware's protocol, sampling and conditioning) and diagnosed by \
         the same evidence engine; no expected-evidence shortcut. A hypothesis with an \
         effect a protocol cannot test scores 0 there without simulation (the engine never \
         names an effect its design cannot test); such a protocol is not simulated at all \
         when another can test every hypothesis"
    )
}

/// With `--hours`: the best protocol beyond them, if it does better than `recommended`.
fn better_beyond(scored: &[Scored], recommended: &Scored, opts: &Options) -> Option<Beyond> {
    let h = opts.max_hours?;
    (scored.iter())
        .filter(|s| s.rig_hours > h && s.p_decide_worst > recommended.p_decide_worst)
        .max_by(|a, b| {
            (a.p_decide_worst.total_cmp(&b.p_decide_worst))
                .then(b.rig_hours.total_cmp(&a.rig_hours))
        })
        .map(|s| Beyond {
            name: s.candidate.name.clone(),
            p_decide_worst: s.p_decide_worst,
            rig_hours: s.rig_hours,
        })
}

/// The data's diagnosis; without a time column, window times from the thesis protocol (so
/// that drift is among the hypotheses a time-ordered design could test), said in `assumed`.
fn diagnosis(data: &Dataset, assumed: &mut Vec<String>) -> Diagnosis {
    let has_time = data.pairs.iter().any(|p| p.time_s.is_some());
    let opts = diagnose::Options {
        protocol_times: !has_time,
        ..diagnose::Options::default()
    };
    let has_step = data.pairs.iter().any(|p| p.step.is_some());
    match (has_time, has_step) {
        (false, true) => assumed.push(
            "no time_s column: window times taken from the step numbers with the thesis \
             protocol (10 s steps)"
                .to_string(),
        ),
        (false, false) => assumed.push(
            "no time_s or step column: these data have no window times, so nothing that \
             changes with time in a run can be tested in them (the simulated campaigns have \
             times)"
                .to_string(),
        ),
        _ => {}
    }
    diagnose::diagnose_with(data, &opts)
}

fn world(d: &Diagnosis, assumed: &mut Vec<String>) -> World {
    assumed.push(
        "within-run noise, the slow wander of mu and the sensors' zero error are the thesis \
         rig's; cord and run scatter are the data's"
            .to_string(),
    );
    assumed.push("the run protocol is the thesis's (12 levels, 10 s each)".to_string());
    let finite = |v: f64, or: f64| if v.is_finite() && v >= 0.0 { v } else { or };
    World {
        mu: finite(d.baseline.mu, 0.115),
        cord_pct: finite(
            d.scatter.cord_pct,
            capstan_sim::noise::thesis::CORD_SCATTER_PCT,
        ),
        run_pct: finite(
            d.scatter.run_pct,
            capstan_sim::noise::thesis::RUN_SCATTER_PCT,
        ),
        protocol: capstan_rig::Protocol::default(),
    }
}

fn score(candidate: Candidate, per_hypothesis: Vec<Rate>, world: &World) -> Scored {
    let mut pairs = Vec::new();
    for (i, a) in per_hypothesis.iter().enumerate() {
        for b in &per_hypothesis[i + 1..] {
            pairs.push(PairChance {
                a: a.hypothesis.clone(),
                b: b.hypothesis.clone(),
                p: (a.p_decide + b.p_decide) / 2.0,
            });
        }
    }
    let worst = (per_hypothesis.iter().map(|r| r.p_decide)).fold(1.0, f64::min);
    Scored {
        rig_hours: candidate.design.rig_hours(&world.protocol),
        simulate_args: candidate.design.simulate_args(),
        candidate,
        per_hypothesis,
        p_decide_pairs: pairs,
        p_decide_worst: worst,
    }
}

/// The current design if it decides; else the best worst-case chance within the hours, the
/// fewer hours between chances one campaign apart.
fn recommend<'a>(scored: &'a [Scored], opts: &Options, current_decides: bool) -> &'a Scored {
    if current_decides {
        return &scored[0];
    }
    let step = 1.0 / opts.reps.max(1) as f64;
    let within = |s: &&Scored| opts.max_hours.is_none_or(|h| s.rig_hours <= h);
    let best = (scored.iter().filter(within))
        .map(|s| s.p_decide_worst)
        .fold(0.0, f64::max);
    let shortest = || {
        (scored.iter())
            .min_by(|a, b| a.rig_hours.total_cmp(&b.rig_hours))
            .unwrap_or(&scored[0])
    };
    if best == 0.0 {
        // No design reaches it: the least bad is the one that named its truth most often over
        // the hypotheses, not the shortest (which favoured the current design at 0 %).
        let named = |s: &Scored| s.per_hypothesis.iter().map(|r| r.decided).sum::<usize>();
        return (scored.iter().filter(within))
            .max_by(|a, b| (named(a).cmp(&named(b))).then(b.rig_hours.total_cmp(&a.rig_hours)))
            .unwrap_or_else(shortest);
    }
    // Near ties (one campaign apart) go to the fewer hours; a 0 % is never a near tie.
    (scored.iter().filter(within))
        .filter(|s| s.p_decide_worst > 0.0 && s.p_decide_worst >= best - step + 1e-9)
        .min_by(|a, b| a.rig_hours.total_cmp(&b.rig_hours))
        .unwrap_or_else(shortest)
}

#[cfg(test)]
mod recommend_tests {
    use super::*;

    fn scored(name: &str, runs: u32, decided: &[usize]) -> Scored {
        let mut c = candidates(
            &Design {
                order: capstan_rig::StepOrder::Monotone,
                runs_per_cord: runs,
                wraps_deg: vec![360.0],
                diameters_mm: vec![25.4],
                drive_v: vec![10.0],
            },
            &[],
            true,
        )
        .remove(0);
        c.name = name.into();
        let rates = (decided.iter().enumerate())
            .map(|(i, &d)| Rate {
                hypothesis: format!("h{i}"),
                campaigns: 8,
                decided: d,
                p_decide: d as f64 / 8.0,
                otherwise: Default::default(),
                not_simulated: None,
            })
            .collect();
        let world = World {
            mu: 0.1,
            cord_pct: 5.0,
            run_pct: 2.0,
            protocol: capstan_rig::Protocol::default(),
        };
        score(c, rates, &world)
    }

    #[test]
    fn a_zero_is_no_near_tie_and_a_tie_at_zero_goes_to_the_most_named() {
        let opts = Options::default();
        // 1 of 8 (12.5 %) against the shorter current design's 0 %: the 12.5 % is chosen (it
        // was the current design: 0 % within one campaign of 12.5 %, and fewer hours).
        let s = [
            scored("current design", 6, &[0, 8]),
            scored("longer", 12, &[1, 8]),
        ];
        assert_eq!(recommend(&s, &opts, false).candidate.name, "longer");
        // Everything at 0 %: the design naming its truth most often (7 of 16 campaigns), not
        // the shortest.
        let s = [
            scored("current design", 6, &[0, 2]),
            scored("longer", 12, &[0, 7]),
        ];
        assert_eq!(recommend(&s, &opts, false).candidate.name, "longer");
    }
}
