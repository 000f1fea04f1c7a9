//! How many cords? For the held-out gain and each between-cord effect the data show but cannot
//! establish, the number of cords (and runs per cord) that would establish it at the size
//! observed, in 80 % of campaigns: sets of new cords simulated end to end (firmware in the
//! loop, `capstan_validation::cord_cases`: every cord its own mu, T2 zero and heating, scattered as
//! the data's are) under the data's named causes at their fitted sizes plus the effect, and run
//! through the same pipeline as the data (the analysis's whole-procedure gain and its sign-flip
//! test; the engine's cords-as-units tests). Cords are added as new cords on the data's
//! (diameter, wrap) combinations, `k` per combination.
//!
//! Each question carries its stake: how much its answer moves the prediction of T2 at the
//! data's own operating points (the RMS change over the data's rows, N) — the gain's is the
//! held-out RMSE it would save, an effect's the change it makes to the fitted curve. The plan
//! puts first whichever open question, this one or the protocols', has the larger stake.

use capstan_data::Dataset;
use capstan_engine::analysis::gain::GainVerdict;
use capstan_engine::analysis::Analysis;
use capstan_engine::evidence::Level;
use capstan_physics::{Effect, EffectKind};
use capstan_sim::plant::rng::derive_seed;
use capstan_validation::cord_cases::{CordScatter, CordSet, CordWorld};
use serde::Serialize;

/// New cords per (diameter, wrap) combination tried, in order (the data's own count first).
pub const LADDER: [u32; 6] = [1, 2, 3, 4, 6, 8];
/// The power a number of cords must reach.
pub const POWER: f64 = 0.8;

/// One design tried for a question.
#[derive(Clone, Debug, Serialize)]
pub struct Trial {
    /// Cords.
    pub cords: usize,
    /// Runs per cord.
    pub runs_per_cord: u32,
    /// Campaigns simulated.
    pub campaigns: usize,
    /// Of which established the answer.
    pub established: usize,
    /// established / campaigns.
    pub power: f64,
    /// Rig hours of the campaign (the data's run protocol, a new cord set up between cords).
    pub rig_hours: f64,
    /// The held-out gain only: the median over the campaigns of their held-out RMSE ratio
    /// (what the simulated world's gain is, to set beside the data's).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub median_ratio: Option<f64>,
}

/// One open question between cords.
#[derive(Clone, Debug, Serialize)]
pub struct Question {
    /// What is asked (`the held-out gain`, or a catalogue effect's name).
    pub question: String,
    /// What the data show, in words.
    pub observed: String,
    /// The RMS change its answer makes to T2 at the data's rows, N.
    pub stake_n: f64,
    /// The designs tried, fewest cords first.
    pub trials: Vec<Trial>,
    /// The fewest cords (and runs per cord) that establish it in ≥ 80 % of campaigns, if any
    /// tried does.
    pub needed: Option<Trial>,
    /// The held-out gain only: the cords the analysis's own simulation needs, resampling the
    /// data's cords' held-out errors (the gain at its observed size and spread from cord to
    /// cord, which the simulated world under the named causes need not have).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub at_observed_spread: Option<capstan_engine::analysis::gain::CordsNeeded>,
}

/// The answer to "how many cords".
#[derive(Clone, Debug, Serialize)]
pub struct Cords {
    /// The questions, largest stake first.
    pub questions: Vec<Question>,
    /// How the powers were found.
    pub method: String,
}

/// The world the data show, for sets of new cords: their named causes at the engine's sizes,
/// the population-averaged model's mu, and their cord-to-cord scatter.
fn world(a: &Analysis) -> CordWorld {
    let d = &a.evidence;
    let effects: Vec<Effect> = d
        .effects
        .iter()
        .filter_map(|f| {
            let kind = EffectKind::from_name(f.effect)?;
            let value = *f.parameters.values().next()?;
            Some(Effect { kind, value })
        })
        .collect();
    let re = |name: &str| {
        (d.adequacy.cords.random_effects.iter())
            .find(|e| e.parameter == name)
            .map_or(0.0, |e| e.sd_between)
    };
    let heating = effects
        .iter()
        .find(|e| e.kind == EffectKind::ContactHeating)
        .map_or(0.0, |e| e.value);
    let finite = |v: f64, or: f64| if v.is_finite() && v >= 0.0 { v } else { or };
    CordWorld {
        mu: finite(
            a.prediction_model.values.get("mu").copied().unwrap_or(0.12),
            0.12,
        ),
        effects,
        scatter: CordScatter {
            mu_pct: finite(
                d.scatter.cord_pct,
                capstan_sim::noise::thesis::CORD_SCATTER_PCT,
            ),
            run_pct: finite(
                d.scatter.run_pct,
                capstan_sim::noise::thesis::RUN_SCATTER_PCT,
            ),
            t2_zero_sd_n: finite(re("t2_offset"), 0.0),
            heating_rel: if heating > 0.0 {
                finite(re("contact_heating") / heating, 0.0)
            } else {
                0.0
            },
        },
        beyond_turn: 0.0,
        diameter_change: 0.0,
    }
}

/// The stake of a hypothesis that adds `extra` (at their sizes) to the data's population-
/// averaged model: the RMS change over the data's rows of its fitted T2 when the model's own
/// parameters are fitted again with `extra` in (N). 0 where the data's conditions do not move
/// it (a speed dependence at the one drive voltage the data have).
pub fn stake_of(a: &Analysis, extra: &[Effect]) -> f64 {
    use capstan_engine::fit::solve::fit_fixed;
    let mut spec = a.extended_fit.spec.clone();
    spec.random = None;
    let runs = a.obs.all_runs();
    let start = Some(a.extended_fit.theta.as_slice());
    let base = fit_fixed(&spec, &a.obs, &runs, start);
    for e in extra {
        e.apply(&mut spec.base);
    }
    let with = fit_fixed(&spec, &a.obs, &runs, start);
    let (mut ss, mut n) = (0.0, 0usize);
    for (x, y) in with.t2_n.iter().zip(&base.t2_n) {
        let d = x - y;
        if d.is_finite() {
            ss += d * d;
            n += 1;
        }
    }
    (ss / n.max(1) as f64).sqrt()
}

/// The questions between cords `a` leaves open, each with its stake.
fn open_questions(a: &Analysis) -> Vec<(Question, Option<Effect>)> {
    let mut out = Vec::new();
    let g = &a.gain;
    let gain_open = matches!(
        g.verdict,
        GainVerdict::NotEstablished | GainVerdict::TooFewCords
    ) && g.value < 1.0;
    if gain_open {
        let base = a.models.first().and_then(|m| m.loco_rmse_t2_n);
        let ext = a
            .models
            .iter()
            .find(|m| m.name == "extended")
            .and_then(|m| m.loco_rmse_t2_n);
        let stake_n = match (base, ext) {
            (Some(b), Some(e)) => (b - e).max(0.0),
            _ => 0.0,
        };
        out.push((
            Question {
                question: "the held-out gain".into(),
                observed: format!(
                    "{:.2} times Euler-Eytelwein's held-out error over {} cords, p = {:.2} ({})",
                    g.value, g.cords, g.p, g.method
                ),
                stake_n,
                trials: Vec::new(),
                needed: None,
                at_observed_spread: g.cords_needed.clone(),
            },
            None,
        ));
    }
    for e in &a.evidence.candidates {
        if e.level != Level::BetweenCord || e.selected || !e.relevant {
            continue;
        }
        let effect = Effect {
            kind: e.kind,
            value: e.value,
        };
        out.push((
            Question {
                question: e.effect.to_string(),
                observed: format!(
                    "{} = {:.4} between the {} cords, p = {:.2} (t test, cords as units): a size that matters, not established",
                    e.kind.parameter().unwrap_or("value"),
                    e.value,
                    a.obs.groups.len(),
                    e.p
                ),
                stake_n: stake_of(a, &[effect]),
                trials: Vec::new(),
                needed: None,
                at_observed_spread: None,
            },
            Some(effect),
        ));
    }
    out
}

/// Does the simulated set `ds` establish the answer (the gain when `effect` is None, with its
/// held-out ratio)?
fn establishes(ds: &Dataset, effect: Option<Effect>) -> Result<(bool, f64), crate::PlanError> {
    match effect {
        None => {
            let opts = capstan_engine::analysis::Options {
                threads: 1,
                ..Default::default()
            };
            let a = capstan_engine::analysis::run(ds, opts).map_err(crate::PlanError::Analysis)?;
            Ok((a.gain.verdict == GainVerdict::Established, a.gain.value))
        }
        Some(e) => {
            let opts = capstan_engine::diagnose::Options {
                threads: 1,
                ..Default::default()
            };
            let d = capstan_engine::diagnose::diagnose_with(ds, &opts);
            Ok((
                d.effects.iter().any(|f| f.effect == e.kind.name()),
                f64::NAN,
            ))
        }
    }
}

/// Rig hours of `runs` runs on each of `cords` cords: the run protocol's length, a minute
/// between runs, ten minutes to set up each new cord.
fn rig_hours(cords: usize, runs: u32, protocol: &capstan_rig::Protocol) -> f64 {
    let run_s = protocol.end_ms() as f64 / 1000.0 + crate::candidates::BETWEEN_RUNS_S;
    (cords as f64 * (runs as f64 * run_s + 600.0)) / 3600.0
}

/// `reps` sets of `k` new cords per combination, `runs` runs each, under `world` (+ `effect`):
/// how many establish the answer.
#[allow(clippy::too_many_arguments)]
fn trial(
    base: &CordSet,
    (k, runs): (u32, u32),
    effect: Option<Effect>,
    reps: usize,
    (seed, salt): (u64, u64),
    threads: usize,
    protocol: &capstan_rig::Protocol,
) -> Result<Trial, crate::PlanError> {
    let sets: Vec<CordSet> = (0..reps)
        .map(|r| {
            let mut s = base.clone();
            s.replicates = k;
            s.runs = runs;
            s.seed = derive_seed(seed, &[salt, k as u64, runs as u64, r as u64]);
            if let Some(e) = effect {
                s.world.effects.push(e);
            }
            s
        })
        .collect();
    let hits = capstan_engine::fit::par::par_map(&sets, threads, |s: &CordSet| {
        let ds = s.generate().map_err(crate::PlanError::Case)?;
        establishes(&ds, effect)
    });
    let mut established = 0;
    let mut ratios = Vec::new();
    for h in hits {
        let (hit, ratio) = h?;
        established += usize::from(hit);
        if ratio.is_finite() {
            ratios.push(ratio);
        }
    }
    let median_ratio =
        (!ratios.is_empty()).then(|| capstan_engine::fit::stats::median(&mut ratios));
    let cords = base.diameters_mm.len() * base.wraps_deg.len() * k as usize;
    Ok(Trial {
        cords,
        runs_per_cord: runs,
        campaigns: reps,
        established,
        power: established as f64 / reps.max(1) as f64,
        rig_hours: rig_hours(cords, runs, protocol),
        median_ratio,
    })
}

/// How many cords each open between-cord question of the analysis `a` needs; `runs`
/// is the data's runs per cord.
pub fn how_many(
    a: &Analysis,
    (diameters, wraps, runs): (&[f64], &[f64], u32),
    (reps, seed, threads): (usize, u64, usize),
    protocol: &capstan_rig::Protocol,
) -> Result<Cords, crate::PlanError> {
    let base = CordSet {
        seed,
        world: world(a),
        diameters_mm: diameters.to_vec(),
        wraps_deg: wraps.to_vec(),
        replicates: 1,
        runs,
    };
    let mut questions = Vec::new();
    for (i, (mut q, effect)) in open_questions(a).into_iter().enumerate() {
        for &k in LADDER.iter().skip(1) {
            let t = trial(
                &base,
                (k, runs),
                effect,
                reps,
                (seed, i as u64),
                threads,
                protocol,
            )?;
            let enough = t.power >= POWER;
            q.trials.push(t.clone());
            if enough {
                // Half the runs on as many cords: if that is enough too, it is the cheaper.
                let half = (runs / 2).max(2);
                let fewer = if half < runs {
                    let t2 = trial(
                        &base,
                        (k, half),
                        effect,
                        reps,
                        (seed, i as u64),
                        threads,
                        protocol,
                    )?;
                    q.trials.push(t2.clone());
                    (t2.power >= POWER).then_some(t2)
                } else {
                    None
                };
                q.needed = Some(fewer.unwrap_or(t));
                break;
            }
        }
        questions.push(q);
    }
    questions.sort_by(|a, b| b.stake_n.total_cmp(&a.stake_n));
    Ok(Cords {
        questions,
        method: format!(
            "simulation: {reps} sets of new cords per design (k new cords on each of the data's {} (diameter, wrap) combinations, k = {}), each cord its own mu, T2 zero and heating scattered as the data's, simulated end to end and run through the same pipeline (the gain: the whole analysis and its sign-flip test; an effect: the engine's cords-as-units test); the fewest cords with ≥ {:.0} % established",
            diameters.len() * wraps.len(),
            LADDER[1..].iter().map(|k| k.to_string()).collect::<Vec<_>>().join(", "),
            100.0 * POWER
        ),
    })
}
