//! Running a campaign's jobs on worker threads and collecting their results in campaign order.

use super::jobs::Job;
use super::results::{summarise_faults, CampaignResult, PairRow, RunResult};
use super::{CampaignConfig, CampaignError};
use crate::run::{self, SetupError};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

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
            rows.push(PairRow::new(r.cord, r.run, p));
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
