//! `capstan log` from a board: reach it through a debug probe (`capstan_link::probe`), start a
//! run if asked, and feed its defmt up-channel to the session until Ctrl-C, a limit, or the
//! probe goes away.

use super::Args;
use capstan_link::Firmware;
#[cfg(feature = "probe")]
use capstan_log::Logger;
use capstan_log::{LogOptions, Outcome, Stop, Summary};
#[cfg(feature = "probe")]
use std::time::Duration;

/// Record from the board the arguments name.
#[cfg(feature = "probe")]
pub(super) fn from_board(
    fw: &Firmware,
    opts: LogOptions,
    args: &Args,
) -> anyhow::Result<(Summary, Stop, Outcome)> {
    use capstan_link::probe::{connect, ProbeOptions};
    let chip = args
        .chip
        .clone()
        .expect("clap requires --chip without --from");
    let popts = ProbeOptions {
        chip: chip.clone(),
        probe: args.probe.clone(),
        flash: !args.no_flash,
        connect_under_reset: args.connect_under_reset,
        speed_khz: args.speed,
        rtt_channel: 0,
        rtt_timeout: Duration::from_secs(5),
    };
    let limits = Limits {
        runs: args.runs,
        duration: args.duration.map(Duration::from_secs_f64),
    };
    // The board first: a missing probe or chip leaves no half-made session directory behind.
    let elf = args
        .elf
        .as_deref()
        .expect("clap requires --elf without --sim");
    let mut board = connect(elf, &popts, &mut |line| crate::errln!("{line}"))?;
    let source = format!("{chip} over RTT (probe: {})", board.probe_name);
    let mut logger = Logger::create(fw, opts, &source, super::notes())?;
    logger.set_provenance(super::provenance(args, None)?);
    if args.start {
        start_run(&mut board)?;
    }
    let stop = stream(
        &mut board,
        limits,
        &mut logger,
        crate::cli::signal::stop_flag("log"),
    )?;
    let (summary, outcome) = logger.finish_with(&stop)?;
    Ok((summary, stop, outcome))
}

/// When to stop on one's own.
#[cfg(feature = "probe")]
#[derive(Clone, Copy, Debug, Default)]
struct Limits {
    /// After this many complete runs.
    runs: Option<usize>,
    /// After this long.
    duration: Option<Duration>,
}

/// Feed the board's defmt up-channel to `logger` until Ctrl-C (`stop`), a limit, or a probe
/// failure, which ends the stream as [`Stop::ProbeLost`] (the logger keeps what it has).
/// Only a failure to write the files is an error.
#[cfg(feature = "probe")]
fn stream(
    board: &mut capstan_link::probe::Connection,
    limits: Limits,
    logger: &mut Logger,
    stop: &std::sync::atomic::AtomicBool,
) -> anyhow::Result<Stop> {
    use std::sync::atomic::Ordering;
    let started = std::time::Instant::now();
    let mut buf = vec![0u8; 16 * 1024];
    loop {
        if stop.load(Ordering::SeqCst) {
            return Ok(Stop::Interrupted(
                crate::cli::signal::stop_reason().unwrap_or("Ctrl-C"),
            ));
        }
        if let Some(n) = limits.runs.filter(|&n| logger.completed_runs() >= n) {
            return Ok(Stop::Limit(format!("{n} run(s) logged (--runs)")));
        }
        if let Some(d) = limits.duration.filter(|&d| started.elapsed() >= d) {
            return Ok(Stop::Limit(format!("{} s (--duration)", d.as_secs_f64())));
        }
        match board.read_up(&mut buf) {
            Ok(0) => std::thread::sleep(Duration::from_millis(5)),
            Ok(n) => logger.feed(&buf[..n])?,
            Err(e) => return Ok(Stop::ProbeLost(e.to_string())),
        }
    }
}

/// `--start`: the `run` command into the firmware's command channel (the firmware answers
/// with a `reply` record, which the log keeps like any other).
#[cfg(feature = "probe")]
fn start_run(board: &mut capstan_link::probe::Connection) -> anyhow::Result<()> {
    if board.down_buffer_size(0).is_none() {
        anyhow::bail!(
            "--start: this firmware has no RTT command channel (down channel 0): rebuild it \
             from this repository, or press the rig's button instead"
        );
    }
    let line = b"run\n";
    let taken = board.write_down(0, line)?;
    if taken != line.len() {
        anyhow::bail!(
            "--start: the firmware's command buffer is full; press the rig's button instead"
        );
    }
    crate::errln!(
        "capstan log: run armed (--start): press the rig's button within 30 s to start it (the \
         host never starts the drive); its reply and records follow"
    );
    Ok(())
}

#[cfg(not(feature = "probe"))]
pub(super) fn from_board(
    _fw: &Firmware,
    _opts: LogOptions,
    _args: &Args,
) -> anyhow::Result<(Summary, Stop, Outcome)> {
    anyhow::bail!(
        "this `capstan` was built without the `probe` feature: it can only decode saved streams \
         (--from). Rebuild with default features to log from a board."
    )
}
