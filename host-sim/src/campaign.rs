//! Campaigns: every (diameter, drive voltage, wrap) cord, each run `runs` times, through the
//! firmware's own protocol, sampling and conditioning, in parallel threads.
//!
//! Results do not depend on the thread count or on which other cords are in the campaign:
//! every random number of a run comes from a seed derived from the campaign seed and the
//! cord's (diameter, voltage, wrap) values and the run number.

use crate::run::{self, RunFailure, RunLog, RunSpec, SetupError};
use capstan_friction::{Effect, Model};
use capstan_plant::rng::{derive_seed, Rng};
use capstan_plant::{CordSetup, Injection, InjectionKind, InjectionReport, PlantConfig};
use firmware::record::RunEnd;
use firmware::safety::SafetyLimits;
use firmware::{Calibration, FaultKind, Protocol, StepOrder};
use std::fmt;
use std::str::FromStr;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// A fault to inject: `NAME@SECONDS` (every run) or `NAME@SECONDS#RUN` (one run, numbered
/// 1.. over the whole campaign in its run order). Seconds count from the run's trigger.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaultSpec {
    /// What happens to the plant.
    pub kind: InjectionKind,
    /// When, s after the trigger's rising edge (the pairs' `time_s` timebase).
    pub at_s: f64,
    /// Only this run of the campaign (1-based), or every run.
    pub run: Option<u32>,
}

impl FromStr for FaultSpec {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let (name, rest) = s
            .split_once('@')
            .ok_or_else(|| format!("`{s}`: expected NAME@SECONDS (e.g. cord_break@40)"))?;
        let kind = InjectionKind::from_name(name.trim()).ok_or_else(|| {
            format!(
                "`{name}`: unknown fault (known: {})",
                InjectionKind::NAMES.join(", ")
            )
        })?;
        let (secs, run) = match rest.split_once('#') {
            Some((a, r)) => {
                let run: u32 = r
                    .trim()
                    .parse()
                    .ok()
                    .filter(|&r| r >= 1)
                    .ok_or_else(|| format!("`{s}`: the run after `#` must be 1 or more"))?;
                (a, Some(run))
            }
            None => (rest, None),
        };
        let at_s: f64 = secs
            .trim()
            .parse()
            .map_err(|_| format!("`{s}`: `{secs}` is not a number of seconds"))?;
        if !(at_s.is_finite() && at_s >= 0.0) {
            return Err(format!(
                "`{s}`: the time must be 0 or more seconds after the trigger"
            ));
        }
        Ok(FaultSpec { kind, at_s, run })
    }
}

/// A campaign. `Default` is the thesis's: 2 diameters × 5 wraps × 6 runs at 10 V, monotone
/// steps, Euler-Eytelwein with mu = 0.115, no effect, no scatter, sensor noise on.
#[derive(Clone, Debug)]
pub struct CampaignConfig {
    /// Capstan diameters, mm.
    pub diameters_mm: Vec<f64>,
    /// Wrap angles, deg.
    pub wraps_deg: Vec<f64>,
    /// Drive voltages, V (the firmware commands drive/`amp_gain` of control voltage: at most
    /// 3.3 V × 4 = 13.2 V).
    pub drive_vs: Vec<f64>,
    /// Repeat runs per cord.
    pub runs: u32,
    /// Order of the tension levels.
    pub order: StepOrder,
    /// Catalogue effects switched on (in order) on top of `model`.
    pub effects: Vec<Effect>,
    /// The base friction model (and sensor artefacts).
    pub model: Model,
    /// Cord-to-cord standard deviation of mu, % (run-to-run: half of it). A cord is one
    /// (diameter, drive voltage, wrap) group.
    pub scatter_pct: f64,
    /// Gaussian sensor noise (the plant's `sensor.noise_sd_n`); off = noiseless conversions.
    pub sensor_noise: bool,
    /// Campaign seed.
    pub seed: u64,
    /// Faults to inject.
    pub faults: Vec<FaultSpec>,
    /// The protocol (dwell, windows, sample rate, ...); `order`, `amp_control_v`, diameter and
    /// wrap are set per run from the fields above.
    pub protocol: Protocol,
    /// The calibration the firmware starts each run from.
    pub calibration: Calibration,
    /// The firmware's safety limits.
    pub limits: SafetyLimits,
    /// The rig's constants (`capstan_diameter_mm` is set per cord).
    pub plant: PlantConfig,
    /// Worker threads (0 = one per core).
    pub threads: usize,
    /// Keep every run's decimated raw samples in the result.
    pub keep_raw: bool,
}

impl Default for CampaignConfig {
    fn default() -> Self {
        CampaignConfig {
            diameters_mm: vec![12.7, 25.4],
            wraps_deg: vec![270.0, 360.0, 450.0, 630.0, 720.0],
            drive_vs: vec![10.0],
            runs: 6,
            order: StepOrder::Monotone,
            effects: Vec::new(),
            model: Model::euler_eytelwein(capstan_plant::THESIS_MU),
            scatter_pct: 0.0,
            sensor_noise: true,
            seed: 1,
            faults: Vec::new(),
            protocol: Protocol::default(),
            calibration: Calibration::default(),
            limits: SafetyLimits::default(),
            plant: PlantConfig::default(),
            threads: 0,
            keep_raw: true,
        }
    }
}

/// Why a campaign cannot run.
#[derive(Clone, Debug, PartialEq)]
pub enum CampaignError {
    /// A list is empty.
    Empty(&'static str),
    /// A value is out of range: which, the value, and what is allowed.
    Bad(&'static str, f64, &'static str),
    /// A fault names a run the campaign does not have.
    FaultRun(u32, u32),
    /// The firmware or the plant refuses the setup.
    Setup(SetupError),
}

impl fmt::Display for CampaignError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CampaignError::Empty(what) => write!(f, "{what}: give at least one value"),
            CampaignError::Bad(what, v, allowed) => write!(f, "{what} = {v}: {allowed}"),
            CampaignError::FaultRun(r, n) => {
                write!(f, "fault on run {r}, but the campaign has {n} runs")
            }
            CampaignError::Setup(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for CampaignError {}

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

/// One run to make, before it is made.
#[derive(Clone, Debug)]
struct Job {
    index: u32,
    cord: CordKey,
    run: u32,
    spec: RunSpec,
}

fn f32_to_f64(x: f32) -> f64 {
    // Through the shortest decimal, so 2.05f32 is written 2.05, not 2.049999952316284.
    format!("{x}").parse().unwrap_or(f64::NAN)
}

impl CampaignConfig {
    /// Number of runs the campaign makes.
    pub fn run_count(&self) -> usize {
        self.diameters_mm.len() * self.drive_vs.len() * self.wraps_deg.len() * self.runs as usize
    }

    /// Check everything that can be checked before running.
    pub fn validate(&self) -> Result<(), CampaignError> {
        self.jobs().map(|_| ())
    }

    fn jobs(&self) -> Result<Vec<Job>, CampaignError> {
        use CampaignError::*;
        for (what, list) in [
            ("diameters_mm", &self.diameters_mm),
            ("wraps_deg", &self.wraps_deg),
            ("drive_vs", &self.drive_vs),
        ] {
            if list.is_empty() {
                return Err(Empty(what));
            }
        }
        if self.runs == 0 {
            return Err(Bad("runs", 0.0, "at least 1"));
        }
        for &d in &self.diameters_mm {
            if !(d.is_finite() && d > 0.0 && d <= 1000.0) {
                return Err(Bad("capstan diameter (mm)", d, "must be in (0, 1000]"));
            }
        }
        for &w in &self.wraps_deg {
            if !(w.is_finite() && w > 0.0 && w <= 3600.0) {
                return Err(Bad("wrap (deg)", w, "must be in (0, 3600]"));
            }
        }
        let gain = self.calibration.amp.amp_gain as f64;
        let max_v = self.calibration.amp.full_scale_v as f64 * gain;
        for &v in &self.drive_vs {
            if !(v.is_finite() && v >= 0.0 && v <= max_v + 1e-9) {
                return Err(Bad(
                    "drive voltage (V)",
                    v,
                    "must be 0 to 13.2 V (3.3 V of control × the amplifier's gain of 4)",
                ));
            }
        }
        if !(self.scatter_pct.is_finite() && (0.0..=50.0).contains(&self.scatter_pct)) {
            return Err(Bad("scatter (%)", self.scatter_pct, "must be 0 to 50"));
        }
        let n = self.run_count() as u32;
        for f in &self.faults {
            if let Some(r) = f.run.filter(|&r| r > n) {
                return Err(FaultRun(r, n));
            }
        }
        let mut model = self.model;
        for e in &self.effects {
            e.apply(&mut model);
        }
        let mut jobs = Vec::with_capacity(n as usize);
        let mut index = 0;
        for &d in &self.diameters_mm {
            for &v in &self.drive_vs {
                for &w in &self.wraps_deg {
                    let cord = CordKey {
                        diameter_mm: d,
                        wrap_deg: w,
                        drive_v: v,
                    };
                    let cord_seed =
                        derive_seed(self.seed, &[d.to_bits(), v.to_bits(), w.to_bits()]);
                    let cord_z = Rng::new(cord_seed).normal();
                    for run in 1..=self.runs {
                        index += 1;
                        let run_seed = derive_seed(cord_seed, &[run as u64]);
                        let run_z = Rng::new(run_seed).normal();
                        let sc = self.scatter_pct / 100.0;
                        let mut m = model;
                        m.law.mu =
                            (m.law.mu * (1.0 + sc * cord_z) * (1.0 + 0.5 * sc * run_z)).max(0.0);
                        let mut plant = self.plant;
                        plant.capstan_diameter_mm = d;
                        if !self.sensor_noise {
                            plant.sensor.noise_sd_n = 0.0;
                        }
                        let protocol = Protocol {
                            order: self.order,
                            amp_control_v: (v / gain) as f32,
                            capstan_diameter_mm: d as f32,
                            wrap_deg: w as f32,
                            ..self.protocol
                        };
                        let injections = self
                            .faults
                            .iter()
                            .filter(|f| f.run.is_none_or(|r| r == index))
                            .map(|f| Injection {
                                kind: f.kind,
                                cord: 0,
                                after_trigger_us: (f.at_s * 1e6).round() as u64,
                            })
                            .collect();
                        let mut cs = CordSetup::new(w, m);
                        cs.run = run;
                        let spec = RunSpec {
                            plant,
                            cord: cs,
                            protocol,
                            calibration: self.calibration,
                            limits: self.limits,
                            seed: derive_seed(run_seed, &[0x0070_6c61_6e74]),
                            injections,
                            keep_raw: self.keep_raw,
                            trace_every_ms: 0,
                        };
                        jobs.push(Job {
                            index,
                            cord,
                            run,
                            spec,
                        });
                    }
                }
            }
        }
        // Let the firmware and the plant refuse a bad setup before any thread starts.
        if let Some(j) = jobs.first() {
            firmware::Rig::new(j.spec.protocol, j.spec.calibration, j.spec.limits)
                .map_err(|e| Setup(SetupError::Protocol(e)))?;
            capstan_plant::Plant::new_at(j.spec.plant, &[j.spec.cord], 0, 0)
                .map_err(|e| Setup(SetupError::Plant(e)))?;
            if self.faults.len() > capstan_plant::MAX_INJECTIONS {
                return Err(Setup(SetupError::Plant(
                    capstan_plant::PlantError::BadInjection,
                )));
            }
        }
        Ok(jobs)
    }
}

/// Run a campaign.
pub fn run_campaign(cfg: &CampaignConfig) -> Result<CampaignResult, CampaignError> {
    run_campaign_with_progress(cfg, &|_, _| {})
}

/// Run a campaign, calling `progress(done, total)` (from worker threads) after each run.
pub fn run_campaign_with_progress(
    cfg: &CampaignConfig,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<CampaignResult, CampaignError> {
    let jobs = cfg.jobs()?;
    let total = jobs.len();
    let threads = match cfg.threads {
        0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
        n => n,
    }
    .min(total.max(1));
    let wall = std::time::Instant::now();
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let slots: Mutex<Vec<Option<Result<RunResult, SetupError>>>> =
        Mutex::new((0..total).map(|_| None).collect());
    std::thread::scope(|s| {
        for _ in 0..threads {
            s.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some(job) = jobs.get(i) else { break };
                let r = run_job(job);
                slots.lock().unwrap()[i] = Some(r);
                progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
            });
        }
    });
    let wall_s = wall.elapsed().as_secs_f64();
    let mut runs = Vec::with_capacity(total);
    for r in slots.into_inner().unwrap() {
        runs.push(r.expect("every job ran").map_err(CampaignError::Setup)?);
    }
    let mut rows = Vec::new();
    let mut faults = Vec::new();
    for r in &runs {
        for p in &r.log.pairs {
            if !(p.t1.mean_n.is_finite() && p.t2.mean_n.is_finite()) {
                continue;
            }
            rows.push(PairRow {
                capstan_diameter_mm: r.cord.diameter_mm,
                wrap_deg: r.cord.wrap_deg,
                drive_v: r.cord.drive_v,
                run: r.run,
                step: p.step,
                time_s: p.t_mid_ms as f64 / 1000.0,
                t1_n: f32_to_f64(p.t1.mean_n),
                t2_n: f32_to_f64(p.t2.mean_n),
            });
        }
        faults.extend(summarise_faults(r));
    }
    Ok(CampaignResult {
        rows,
        simulated_s: runs.iter().map(|r| r.simulated_s).sum(),
        runs,
        faults,
        wall_s,
        threads,
    })
}

fn run_job(job: &Job) -> Result<RunResult, SetupError> {
    let out = run::run(&job.spec)?;
    Ok(RunResult {
        index: job.index,
        cord: job.cord,
        run: job.run,
        model: job.spec.cord.model,
        log: out.log,
        end: out.end,
        injections: out.injections,
        trigger_rise_us: out.trigger_rise_us,
        safe_since_us: out.safe_since_us,
        simulated_s: out.simulated_us as f64 * 1e-6,
    })
}

fn summarise_faults(r: &RunResult) -> Vec<FaultSummary> {
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
