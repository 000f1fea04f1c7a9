//! `capstan log --sim DIR`: record runs from the simulated board in DIR, as from a board
//! through a probe. The person at the simulated bench starts each run in turn by a press of
//! the rig's button; with --start the first is armed by the `run` command first (as `capstan
//! log --start` sends it: the host never starts the drive). The firmware's own rules apply (a
//! run after a fault needs `ack`, and a press acknowledges a fault instead of starting a run).
//!
//! The records are written as each bench step ends (a run, a stretch of waiting), so a signal
//! is honoured between steps: the run in flight finishes, every finished run is kept, and the
//! session replaces no earlier one in `--out` (it is kept beside it, exit status 130). What
//! cannot finish is refused before anything runs: more than [`MAX_SIM_RUNS`] runs, a
//! `--duration` beyond the board's 32-bit millisecond clock.

use super::Args;
use crate::cli::simboard::link_events;
use anyhow::bail;
use capstan_link::frame::Event;
use capstan_log::{LogOptions, Logger, Outcome, Stop, Summary};
use capstan_rig::record::Record;
use capstan_sim::session::Step;
use capstan_simboard::steps::PRESS_MS;
use capstan_simboard::IDLE_MS;
use std::sync::atomic::Ordering;

/// Runs recorded when neither --runs nor --duration is given (a simulated session must end
/// on its own).
pub const DEFAULT_RUNS: usize = 1;

/// Most runs one `log --sim` records: each takes about a second of this machine's time, and
/// every later command on the board replays it (the board is its journal). A campaign of
/// many runs is `capstan simulate`'s.
pub const MAX_SIM_RUNS: usize = 100;

/// `--duration` is waited in steps of at most this, ms of the board's time: a signal is
/// honoured between them.
const WAIT_STEP_MS: u32 = 600_000;

/// The command line's limits for a simulated board, before anything is opened.
pub(super) fn check(args: &Args) -> anyhow::Result<()> {
    if let Some(n) = args.runs.filter(|&n| n > MAX_SIM_RUNS) {
        bail!(
            "--runs {n} with --sim: at most {MAX_SIM_RUNS} runs per command (each takes about a \
             second here, and every later command on this board replays it); log them in \
             several commands, or simulate a campaign with `capstan simulate --runs N`"
        );
    }
    if let Some(d) = args.duration {
        let max_s = u32::MAX as f64 / 1e3;
        if d * 1e3 > u32::MAX as f64 {
            bail!(
                "--duration {} with --sim: the simulated board's clock counts milliseconds in 32 \
                 bits, so at most {max_s} s ({:.1} days) of its time per command",
                capstan_data::ranges::shown(d),
                max_s / 86_400.0
            );
        }
    }
    Ok(())
}

/// Record from the simulated board the arguments name.
pub(super) fn from_sim(opts: LogOptions, args: &Args) -> anyhow::Result<(Summary, Stop, Outcome)> {
    let mut board = args.sim.open()?;
    let source = format!("the simulated board in {}", board.dir().display());
    let (steps, runs) = plan(args);
    let mut logger = Logger::create_for_records(opts, &source, super::notes())?;
    logger.set_provenance(super::provenance(args, None)?);
    logger.keep_interrupted_apart();
    if args.start {
        crate::errln!(
            "capstan log: run armed (--start); the person at the simulated rig presses its \
             button; the reply and the records follow"
        );
    }
    let signal = super::super::signal::stop_flag("log");
    let mut cut = Cut {
        wanted: runs,
        complete: 0,
    };
    let (mut stop, mut failed) = (None, None);
    board.advance_streamed(&steps, &mut |done, events| {
        if let Err(e) = logger.take_records(cut.keep(link_events(events))) {
            failed = Some(e);
            return false;
        }
        // A signal stops the bench after a wait: a run in flight, and the pause after it that
        // lets the rig come to rest, are finished (a press right after a run ends would start
        // the next at a load, and the board's next command goes on from here).
        let at_rest = matches!(steps.get(done.wrapping_sub(1)), Some(Step::Wait(_)));
        if at_rest && signal.load(Ordering::SeqCst) {
            let why = super::super::signal::stop_reason().unwrap_or("Ctrl-C");
            stop = Some(Stop::Interrupted(why));
            return false;
        }
        true
    })?;
    if let Some(e) = failed {
        return Err(e.into());
    }
    let stop = stop.unwrap_or_else(|| match runs {
        Some(n) if cut.complete >= n => Stop::Limit(format!("{n} run(s) logged (--runs)")),
        Some(_) => Stop::EndOfStream,
        None => Stop::Limit(format!(
            "{} s of the board's time (--duration)",
            args.duration.unwrap_or(0.0)
        )),
    });
    let (summary, outcome) = logger.finish_with(&stop)?;
    Ok((summary, stop, outcome))
}

/// The bench's steps: each run started in turn and waited for, or --duration of the board's
/// time (in steps of [`WAIT_STEP_MS`]); and how many runs to keep (`None`: all in the time).
fn plan(args: &Args) -> (Vec<Step>, Option<usize>) {
    let start = |i: usize| {
        if i == 0 && args.start {
            vec![Step::Send("run".into()), Step::PressIfArmed(PRESS_MS)]
        } else {
            vec![Step::Press(PRESS_MS)]
        }
    };
    if let (None, Some(d)) = (args.runs, args.duration) {
        let mut steps = Vec::new();
        if args.start {
            steps.extend(start(0));
        }
        // Checked to fit in u32 ms (`check`).
        let mut left = (d * 1e3).round() as u32;
        while left > 0 {
            let w = left.min(WAIT_STEP_MS);
            steps.push(Step::Wait(w));
            left -= w;
        }
        return (steps, None);
    }
    let runs = args.runs.unwrap_or_else(|| {
        crate::errln!(
            "capstan log: --sim without --runs or --duration records {DEFAULT_RUNS} run \
             (--runs N for more)"
        );
        DEFAULT_RUNS
    });
    let mut steps = Vec::new();
    for i in 0..runs {
        steps.extend(start(i));
        steps.extend([Step::UntilRunEnd, Step::Wait(IDLE_MS)]);
    }
    (steps, Some(runs))
}

/// The records up to the end of the `wanted`-th complete run (a run a fault ended is not one:
/// `capstan_log::completes`), taken batch by batch.
struct Cut {
    wanted: Option<usize>,
    complete: usize,
}

impl Cut {
    fn keep(&mut self, mut events: Vec<Event>) -> Vec<Event> {
        let Some(n) = self.wanted else {
            return events;
        };
        if self.complete >= n {
            return Vec::new();
        }
        let end = events.iter().position(|e| {
            let done = matches!(
                e,
                Event::Record {
                    record: Record::RunEnd(end),
                    ..
                } if capstan_log::completes(end)
            );
            self.complete += done as usize;
            self.complete == n
        });
        if let Some(i) = end {
            events.truncate(i + 1);
        }
        events
    }
}
