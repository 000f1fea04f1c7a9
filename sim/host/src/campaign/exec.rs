//! Running a campaign's jobs on worker threads and handing their results over in campaign
//! order, holding only the runs in flight: a campaign of any length runs in bounded memory.

use super::jobs::Job;
use super::results::{summarise_faults, CampaignResult, PairRow, RunResult};
use super::{CampaignConfig, CampaignError};
use crate::run::{self, SetupError};
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{mpsc, Condvar, Mutex};

/// How a streamed campaign went.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CampaignStats {
    /// Runs planned.
    pub planned: usize,
    /// Runs made and handed to the sink, in campaign order from the first.
    pub done: usize,
    /// Whether `stop` ended the campaign before every run was made.
    pub interrupted: bool,
    /// Virtual time simulated over the runs handed over, s.
    pub simulated_s: f64,
    /// Wall time of the simulation, s.
    pub wall_s: f64,
    /// Worker threads used.
    pub threads: usize,
}

impl CampaignStats {
    /// Simulated seconds per wall second.
    pub fn realtime_factor(&self) -> f64 {
        self.simulated_s / self.wall_s.max(1e-9)
    }
}

/// Why a streamed campaign failed.
#[derive(Debug)]
pub enum StreamError<E> {
    /// The campaign could not run.
    Campaign(CampaignError),
    /// The sink refused a run (e.g. its files could not be written); the runs before it
    /// were handed over.
    Sink(E),
}

/// Run a campaign.
pub fn run_campaign(cfg: &CampaignConfig) -> Result<CampaignResult, CampaignError> {
    run_campaign_with_progress(cfg, &|_, _| {})
}

/// Run a campaign, calling `progress(done, total)` after each run, and keep every run.
pub fn run_campaign_with_progress(
    cfg: &CampaignConfig,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<CampaignResult, CampaignError> {
    let mut runs = Vec::with_capacity(cfg.run_count());
    let total = cfg.run_count();
    let never = AtomicBool::new(false);
    let stats = stream_campaign(cfg, &never, &mut |r: RunResult| -> Result<(), ()> {
        runs.push(r);
        progress(runs.len(), total);
        Ok(())
    })
    .map_err(|e| match e {
        StreamError::Campaign(e) => e,
        StreamError::Sink(()) => unreachable!("the collecting sink never fails"),
    })?;
    let mut rows = Vec::new();
    let mut faults = Vec::new();
    for r in &runs {
        rows.extend(pair_rows(r));
        faults.extend(summarise_faults(r));
    }
    Ok(CampaignResult {
        rows,
        simulated_s: stats.simulated_s,
        runs,
        faults,
        wall_s: stats.wall_s,
        threads: stats.threads,
    })
}

/// The rows of `pairs.csv` a run makes (pairs with both means finite).
pub fn pair_rows(r: &RunResult) -> impl Iterator<Item = PairRow> + '_ {
    r.log
        .pairs
        .iter()
        .filter(|p| p.t1.mean_n.is_finite() && p.t2.mean_n.is_finite())
        .map(|p| PairRow::new(r.cord, r.run, p))
}

/// Run a campaign on worker threads, handing each run to `sink` on the calling thread in
/// campaign order as soon as it and every run before it are done. At most two runs per
/// thread are held at any time. Once `stop` is set no run is started; the runs in flight are
/// finished and handed over if every run before them was. A setup error or a sink error stops
/// the campaign the same way and is returned.
pub fn stream_campaign<E>(
    cfg: &CampaignConfig,
    stop: &AtomicBool,
    sink: &mut dyn FnMut(RunResult) -> Result<(), E>,
) -> Result<CampaignStats, StreamError<E>> {
    cfg.check().map_err(StreamError::Campaign)?;
    let total = cfg.run_count();
    let threads = match cfg.threads {
        0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
        n => n,
    }
    .min(total.max(1));
    let window = 2 * threads;
    let wall = std::time::Instant::now();
    let next = AtomicUsize::new(0);
    let halt = AtomicBool::new(false);
    let handed = (Mutex::new(0usize), Condvar::new());
    let stopped = || stop.load(Ordering::Relaxed) || halt.load(Ordering::Relaxed);
    let mut stats = CampaignStats {
        planned: total,
        done: 0,
        interrupted: false,
        simulated_s: 0.0,
        wall_s: 0.0,
        threads,
    };
    let mut failure: Option<StreamError<E>> = None;
    std::thread::scope(|s| {
        // If this thread unwinds (a panicking sink), the workers must stop waiting for room
        // that will never come, or the scope would never end.
        let _halt_on_unwind = HaltOnDrop(&halt);
        let (tx, rx) = mpsc::channel::<(usize, Result<RunResult, RunError>)>();
        for _ in 0..threads {
            let tx = tx.clone();
            let (next, handed, stopped) = (&next, &handed, &stopped);
            s.spawn(move || {
                while !stopped() {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    if i >= total || !wait_for_room(handed, i, window, stopped) {
                        break;
                    }
                    let job: Job = cfg.job(i);
                    if tx.send((i, run_caught(&job))).is_err() {
                        break;
                    }
                }
            });
        }
        drop(tx);
        let mut pending = BTreeMap::new();
        for (i, r) in rx {
            pending.insert(i, r);
            while let Some(r) = pending.remove(&stats.done) {
                if failure.is_some() && r.is_ok() {
                    break;
                }
                match hand_over(r, &stats, sink) {
                    Ok(sim_s) => stats.simulated_s += sim_s,
                    Err(e) => {
                        failure = Some(e);
                        halt.store(true, Ordering::Relaxed);
                        break;
                    }
                }
                stats.done += 1;
                *handed.0.lock().unwrap_or_else(|p| p.into_inner()) = stats.done;
                handed.1.notify_all();
            }
        }
    });
    stats.wall_s = wall.elapsed().as_secs_f64();
    stats.interrupted = stats.done < total;
    match failure {
        Some(e) => Err(e),
        None => Ok(stats),
    }
}

/// The next run's result, in campaign order, to the sink: its simulated time, s, or why the
/// campaign stops.
fn hand_over<E>(
    r: Result<RunResult, RunError>,
    stats: &CampaignStats,
    sink: &mut dyn FnMut(RunResult) -> Result<(), E>,
) -> Result<f64, StreamError<E>> {
    match r {
        Ok(run) => {
            let simulated_s = run.simulated_s;
            sink(run).map(|()| simulated_s).map_err(StreamError::Sink)
        }
        Err(RunError::Setup(e)) => Err(StreamError::Campaign(CampaignError::Setup(e))),
        Err(RunError::Panicked(why)) => Err(StreamError::Campaign(CampaignError::Panicked(
            i_of(stats),
            why,
        ))),
    }
}

/// Wait until run `i` is within `window` runs of the last one handed over; false if the
/// campaign stopped meanwhile.
fn wait_for_room(
    handed: &(Mutex<usize>, Condvar),
    i: usize,
    window: usize,
    stopped: &dyn Fn() -> bool,
) -> bool {
    let mut done = handed.0.lock().unwrap_or_else(|p| p.into_inner());
    while i >= *done + window {
        if stopped() {
            return false;
        }
        done = handed
            .1
            .wait_timeout(done, std::time::Duration::from_millis(50))
            .unwrap_or_else(|p| p.into_inner())
            .0;
    }
    true
}

/// Sets the flag when dropped while its thread unwinds.
struct HaltOnDrop<'a>(&'a AtomicBool);

impl Drop for HaltOnDrop<'_> {
    fn drop(&mut self) {
        if std::thread::panicking() {
            self.0.store(true, Ordering::Relaxed);
        }
    }
}

/// Why a run gave no result.
enum RunError {
    Setup(SetupError),
    /// The simulation panicked (a bug): the message.
    Panicked(String),
}

/// The campaign position (from 1) of the next run to hand over.
fn i_of(stats: &CampaignStats) -> u32 {
    stats.done as u32 + 1
}

/// Run a job; a panic in it is caught and reported as that run's failure, so the campaign
/// stops cleanly and keeps the runs before it instead of hanging its other workers.
fn run_caught(job: &Job) -> Result<RunResult, RunError> {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| run_job(job))) {
        Ok(r) => r.map_err(RunError::Setup),
        Err(p) => Err(RunError::Panicked(
            p.downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| p.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "a panic".into()),
        )),
    }
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
