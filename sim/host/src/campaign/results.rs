//! What a campaign produced: its pairs (the rows of `pairs.csv`), its runs, and a summary of
//! every fault.

use crate::run::{RunFailure, RunLog};
use capstan_physics::Model;
use capstan_plant::{InjectionKind, InjectionReport};
use capstan_rig::record::{RunEnd, StepPair};
use capstan_rig::FaultKind;

/// One cord: a (diameter, drive voltage, wrap) group, reused for its repeat runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CordKey {
    /// Capstan diameter, mm.
    pub diameter_mm: f64,
    /// Wrap, deg.
    pub wrap_deg: f64,
    /// Drive voltage, V.
    pub drive_v: f64,
}

impl CordKey {
    /// A file-name-safe label, e.g. `d12.7_w270_v10`.
    pub fn label(&self) -> String {
        format!("d{}_w{}_v{}", self.diameter_mm, self.wrap_deg, self.drive_v)
    }
}

/// One row of `pairs.csv`: exactly its columns.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairRow {
    /// Capstan diameter, mm.
    pub capstan_diameter_mm: f64,
    /// Wrap, deg.
    pub wrap_deg: f64,
    /// Drive voltage, V.
    pub drive_v: f64,
    /// Repeat run on this cord, from 1.
    pub run: u32,
    /// Step in time order, from 1.
    pub step: u32,
    /// Middle of the conditioning window, s since the trigger.
    pub time_s: f64,
    /// Conditioned T1, N.
    pub t1_n: f64,
    /// Conditioned T2, N.
    pub t2_n: f64,
}

impl PairRow {
    /// The row of one conditioned pair of a run on `cord` (its means to the shortest decimal
    /// of their f32, as the logger writes them).
    pub fn new(cord: CordKey, run: u32, pair: &StepPair) -> PairRow {
        PairRow {
            capstan_diameter_mm: cord.diameter_mm,
            wrap_deg: cord.wrap_deg,
            drive_v: cord.drive_v,
            run,
            step: pair.step,
            time_s: pair.t_mid_ms as f64 / 1000.0,
            t1_n: f32_to_f64(pair.t1.mean_n),
            t2_n: f32_to_f64(pair.t2.mean_n),
        }
    }
}

/// One run of a campaign.
#[derive(Clone, Debug)]
pub struct RunResult {
    /// Position in the campaign, from 1 (the `#RUN` of a fault spec).
    pub index: u32,
    /// Its cord.
    pub cord: CordKey,
    /// Repeat run on the cord, from 1.
    pub run: u32,
    /// The friction model the plant used (scatter and effects applied).
    pub model: Model,
    /// The firmware's records.
    pub log: RunLog,
    /// How the run ended.
    pub end: Result<RunEnd, RunFailure>,
    /// What became of the injections.
    pub injections: Vec<InjectionReport>,
    /// Trigger rising edge, plant µs.
    pub trigger_rise_us: Option<u64>,
    /// When the rig last went to its safe state, plant µs.
    pub safe_since_us: Option<u64>,
    /// Virtual time simulated, s.
    pub simulated_s: f64,
}

/// A fault in a run: injected, raised by the firmware, or both.
#[derive(Clone, Debug, PartialEq)]
pub struct FaultSummary {
    /// Campaign run (1-based).
    pub run: u32,
    /// Its cord.
    pub cord: CordKey,
    /// Repeat run on the cord.
    pub repeat: u32,
    /// What the plant suffered, if injected.
    pub injected: Option<InjectionKind>,
    /// The fault the firmware raised (`None`: it did not notice).
    pub fault: Option<FaultKind>,
    /// When it happened, s after the trigger: the injection time, or the firmware's detection.
    pub at_s: f64,
    /// When the firmware raised it, s after the trigger.
    pub detected_s: Option<f64>,
    /// From `at_s` to the plant seeing the servo commanded to rest and the amplifier at 0 V, ms.
    pub safe_after_ms: Option<f64>,
    /// Pairs the run had emitted when it ended.
    pub pairs_kept: u32,
}

/// What a campaign produced.
#[derive(Clone, Debug)]
pub struct CampaignResult {
    /// Every conditioned pair, in run order.
    pub rows: Vec<PairRow>,
    /// Every run, in campaign order.
    pub runs: Vec<RunResult>,
    /// Every run that had an injection or a fault.
    pub faults: Vec<FaultSummary>,
    /// Virtual time simulated over all runs, s.
    pub simulated_s: f64,
    /// Wall time of the simulation, s.
    pub wall_s: f64,
    /// Worker threads used.
    pub threads: usize,
}

impl CampaignResult {
    /// Simulated seconds per wall second.
    pub fn realtime_factor(&self) -> f64 {
        self.simulated_s / self.wall_s.max(1e-9)
    }
}

fn f32_to_f64(x: f32) -> f64 {
    // Through the shortest decimal, so 2.05f32 is written 2.05, not 2.049999952316284.
    format!("{x}").parse().unwrap_or(f64::NAN)
}

/// The faults of a run: one row per injection that happened, or the fault the firmware
/// raised by itself.
pub fn summarise_faults(r: &RunResult) -> Vec<FaultSummary> {
    let fault = r.log.faults.first().copied();
    let pairs_kept = r.log.end.map_or(r.log.pairs.len() as u32, |e| e.pairs);
    let detected_s = fault.map(|f| f.t_us as f64 * 1e-6);
    let rise = r.trigger_rise_us;
    let since_trigger_s = |t_us: u64| rise.map(|x| (t_us as f64 - x as f64) * 1e-6);
    let mut out = Vec::new();
    for inj in &r.injections {
        let Some(at) = inj.at_us else { continue };
        out.push(FaultSummary {
            run: r.index,
            cord: r.cord,
            repeat: r.run,
            injected: Some(inj.injection.kind),
            fault: fault.map(|f| f.kind),
            at_s: since_trigger_s(at).unwrap_or(f64::NAN),
            detected_s,
            safe_after_ms: fault.and(inj.safe_after_us()).map(|us| us as f64 / 1000.0),
            pairs_kept,
        });
    }
    if out.is_empty() {
        if let Some(f) = fault {
            // Raised without an injection (e.g. over-force on a stiff cord).
            let at_us = rise.map(|x| (x as i64 + f.t_us) as u64);
            let safe = match (r.safe_since_us, at_us) {
                (Some(s), Some(a)) if s >= a => Some((s - a) as f64 / 1000.0),
                _ => None,
            };
            out.push(FaultSummary {
                run: r.index,
                cord: r.cord,
                repeat: r.run,
                injected: None,
                fault: Some(f.kind),
                at_s: f.t_us as f64 * 1e-6,
                detected_s,
                safe_after_ms: safe,
                pairs_kept,
            });
        }
    }
    out
}
