//! `capstan log --sim DIR`: record runs from the simulated board in DIR, as from a board
//! through a probe. The person at the simulated bench starts each run in turn by a press of
//! the rig's button; with --start the first is armed by the `run` command first (as `capstan
//! log --start` sends it: the host never starts the drive). The firmware's own rules apply (a
//! run after a fault needs `ack`, and a press acknowledges a fault instead of starting a run).

use super::Args;
use crate::logger::{LogOptions, Logger, Outcome, Stop, Summary};
use crate::simboard::steps::PRESS_MS;
use crate::simboard::{SimBoard, IDLE_MS};
use capstan_link::frame::Event;
use firmware::record::Record;
use host_sim::session::Step;

/// Runs recorded when neither --runs nor --duration is given (a simulated session must end
/// on its own: there is no Ctrl-C in virtual time).
pub const DEFAULT_RUNS: usize = 1;

/// Record from the simulated board the arguments name.
pub(super) fn from_sim(opts: LogOptions, args: &Args) -> anyhow::Result<(Summary, Stop, Outcome)> {
    let mut board = SimBoard::open(&args.sim, &mut |l| crate::errln!("{l}"))?;
    let source = format!("the simulated board in {}", board.dir().display());
    let (steps, runs) = plan(args);
    let mut logger = Logger::create_for_records(opts, &source)?;
    logger.set_provenance(super::provenance(args, None)?);
    if args.start {
        crate::errln!(
            "capstan log: run armed (--start); the person at the simulated rig presses its \
             button; the reply and the records follow"
        );
    }
    let done = board.advance(&steps)?;
    let (events, stop) = cut(done.events, runs, args);
    logger.take_records(events)?;
    let (summary, outcome) = logger.finish_with(&stop)?;
    Ok((summary, stop, outcome))
}

/// The bench's steps: each run started in turn and waited for, or --duration of the board's
/// time; and how many runs to keep (`None`: all in the time).
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
        steps.push(Step::Wait((d * 1e3).round() as u32));
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

/// The records up to the end of the `runs`-th complete run (a run a fault ended is not one:
/// `logger::completes`), and why the session stopped.
fn cut(mut events: Vec<Event>, runs: Option<usize>, args: &Args) -> (Vec<Event>, Stop) {
    if let Some(n) = runs {
        let mut seen = 0;
        let end = events.iter().position(|e| {
            let done = matches!(
                e,
                Event::Record {
                    record: Record::RunEnd(end),
                    ..
                } if crate::logger::completes(end)
            );
            seen += done as usize;
            seen == n
        });
        if let Some(i) = end {
            events.truncate(i + 1);
            return (events, Stop::Limit(format!("{n} run(s) logged (--runs)")));
        }
        return (events, Stop::EndOfStream);
    }
    let d = args.duration.unwrap_or(0.0);
    (
        events,
        Stop::Limit(format!("{d} s of the board's time (--duration)")),
    )
}
