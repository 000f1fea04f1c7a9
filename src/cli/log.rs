//! `capstan log`: record runs from the board over defmt/RTT, or decode a saved defmt stream.

mod board;
mod judge;
mod sim;

use anyhow::Context;
use capstan_link::Firmware;
use capstan_log::{LogOptions, Logger, Note, Notes, Outcome, SetupFlags, Stop, Summary};
use judge::{check_args, not_committed, verdict};
use std::io::Read;
use std::path::PathBuf;
use std::sync::atomic::Ordering;
use std::sync::mpsc;
use std::time::Duration;

const AFTER_HELP: &str = "\
LOGGING A RUN ON THE PICO
  1. Wire a debug probe (the Raspberry Pi Debug Probe, or a second Pico running debugprobe)
     to the rig Pico's SWD pins (SWCLK, GND, SWDIO) and plug both into USB. On Linux, install
     the probe-rs udev rules once so the probe can be opened without root.
  2. Build the firmware: cargo build --release -p capstan-board --target thumbv6m-none-eabi
  3. Flash it and log:
       capstan log --chip RP2040 \\
         --elf target/thumbv6m-none-eabi/release/capstan-board --out runs/2026-06-01-a \\
         --wrap-deg 360 --diameter-mm 12.7
     then press the rig's button for each run (or add --start: the first run starts as soon
     as logging does, e.g. with --no-flash after a setup with `capstan rig`). Each record is
     written as it arrives:
       raw.csv       time, T1/T2 in ADC counts and newtons
       pairs.csv     capstan_diameter_mm,wrap_deg,drive_v,run,step,time_s,t1_n,t2_n,boot
                     (boot: 1, then 2 after the board restarts, as its run numbers do)
       faults.csv    safety faults
       messages.txt  the firmware's other log lines, and each command reply (REPLY seq=N ...)
       stream.defmt  the received bytes (decode again with --from)
       summary.json  runs (with their calibration), counts, lost records (sequence gaps),
                     bad frames, why it stopped
     and, when the rig was in setup mode (capstan rig), which belongs to no run:
       settings.csv  each settings report: seq, source (stored, loaded, defaults_..., ...),
                     then every setting by name
       live.csv      setup mode's live values: seq, time_s since boot, counts, N, servo_deg
     A fault in setup mode goes to faults.csv with an empty run and its time since boot.
  4. Stop with Ctrl-C (or --runs N / --duration S). Everything received is kept, files
     flushed; a lost probe (cable pulled) also keeps everything and exits with an error.
     A session becomes DIR's files only with at least one complete run (its run_end came
     and no fault ended it: a run refused at its tare or aborted is not one; or --allow-empty):
     otherwise what was received is kept in DIR/incomplete-<id>, DIR stays as it was (a
     recorded session there is never replaced by an empty or broken one), and the exit
     status is 1 (130 after Ctrl-C).

  Records are numbered by the firmware; a jump in the numbers is reported (how many records,
  after which one, at which byte), on stderr as it happens and in summary.json. --strict
  turns any loss into a failing exit status. A `capstan rig` run while logging reads the
  same RTT channel: the records it takes show here as a gap.

  --no-flash attaches to the firmware already running (it is not reset; a frame cut by the
  attach counts as one bad frame). The ELF must be the exact build that is running: its
  defmt table is what decodes the stream.

DECODING A SAVED STREAM
  capstan log --elf FIRMWARE_ELF --from stream.defmt --out DIR
  capstan log --elf FIRMWARE_ELF --from - --out DIR      (stdin, e.g. piped from QEMU)";

/// Arguments of `capstan log`.
#[derive(clap::Args, Debug)]
#[command(
    long_about = "Record the rig's runs from the board (flash through a debug probe, read the \
                  defmt log over RTT) into CSV files as they arrive, or decode a saved defmt \
                  stream the same way.",
    after_long_help = AFTER_HELP
)]
pub struct Args {
    /// The firmware ELF (the build running on the board): its defmt table decodes the stream.
    /// (Not for --sim: the simulated board runs the firmware's code on the host.)
    #[arg(
        long,
        value_name = "FIRMWARE_ELF",
        required_unless_present = "sim",
        conflicts_with = "sim"
    )]
    pub elf: Option<PathBuf>,

    /// The simulated board instead (`--sim DIR`, as `capstan rig --sim DIR`).
    #[command(flatten)]
    pub sim: super::simboard::SimArgs,

    /// Output directory (created if missing).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,

    /// Board: the probe-rs chip name (RP2040 for the Pico). Flashes the ELF, resets, logs.
    #[arg(long, value_name = "CHIP", required_unless_present_any = ["from", "sim"], conflicts_with = "sim")]
    pub chip: Option<String>,

    /// Decode a saved defmt byte stream instead of a board (`-`: stdin).
    #[arg(long, value_name = "FILE|-", conflicts_with_all = ["chip", "probe", "no_flash", "connect_under_reset", "speed", "start", "sim"])]
    pub from: Option<String>,

    /// Board: which probe, as VID:PID[:SERIAL] (needed when several are plugged in).
    #[arg(long, value_name = "VID:PID[:SERIAL]")]
    pub probe: Option<String>,

    /// Board: do not flash or reset; attach to the firmware already running.
    #[arg(long)]
    pub no_flash: bool,

    /// Board: hold the chip in reset while attaching.
    #[arg(long)]
    pub connect_under_reset: bool,

    /// Board: start a run once logging (as the button does, through the firmware's RTT command
    /// channel), so the run is recorded from its first record. Without it, press the button.
    #[arg(long)]
    pub start: bool,

    /// Board: SWD clock, kHz.
    #[arg(long, value_name = "KHZ")]
    pub speed: Option<u32>,

    /// Capstan diameter for pairs.csv, mm (default: the run-start record's, if set there).
    #[arg(long, value_name = "MM", allow_negative_numbers = true)]
    pub diameter_mm: Option<f64>,

    /// Wrap angle for pairs.csv, deg (default: the run-start record's, if set there).
    #[arg(long, value_name = "DEG", allow_negative_numbers = true)]
    pub wrap_deg: Option<f64>,

    /// Drive-motor voltage for pairs.csv, V, 0 to the rig's 13.2 V (default: amplifier gain ×
    /// control voltage).
    #[arg(long, value_name = "V", allow_negative_numbers = true)]
    pub drive_v: Option<f64>,

    /// Stop after this many complete runs (a run a fault ended is not one).
    #[arg(long, value_name = "N")]
    pub runs: Option<usize>,

    /// Stop after this many seconds, whether or not anything arrives: of the wall clock from a
    /// board or a stream; with --sim, of the simulated board's own clock (which runs faster
    /// than the wall clock: a day of it passes in seconds).
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub duration: Option<f64>,

    /// Replace the files of an earlier session in DIR (only by a session with a complete run,
    /// unless --allow-empty).
    #[arg(long)]
    pub overwrite: bool,

    /// Keep a session without a complete run (nothing received, a run cut short by Ctrl-C or
    /// a fault) as DIR's files. Without it such a session replaces nothing: what was received is kept in
    /// DIR/incomplete-<id>, and the exit status is 1 (130 if stopped by a signal).
    #[arg(long)]
    pub allow_empty: bool,

    /// Fail (exit status 1) if any record was lost or any frame did not decode.
    #[arg(long)]
    pub strict: bool,

    /// Only the final summary on stderr (no line per run, pair, fault and gap).
    #[arg(long, short)]
    pub quiet: bool,
}

/// What made a session, for its `summary.json`: program, commit, command line, the saved
/// stream's SHA-256 (a file given to `--from`; a live board or stdin has none: its bytes are in
/// `stream.defmt`) and the ELF's (none for a simulated board).
pub(crate) fn provenance(args: &Args, from: Option<&str>) -> anyhow::Result<serde_json::Value> {
    let p = match from.filter(|f| *f != "-") {
        Some(f) => crate::provenance::of_input(Some(std::path::Path::new(f)))?,
        None => crate::provenance::without_input(),
    };
    let mut v = serde_json::to_value(p)?;
    // A simulated board (`--sim`) runs the firmware's code on the host: no ELF to hash.
    if let Some(elf) = &args.elf {
        let hash = capstan_data::provenance::sha256_file(elf)
            .with_context(|| format!("cannot read {}", elf.display()))?;
        v["elf_sha256"] = hash.into();
    }
    Ok(v)
}

/// Run `capstan log`.
pub fn run(args: Args) -> anyhow::Result<()> {
    check_args(&args)?;
    let opts = LogOptions {
        out_dir: args.out.clone(),
        overwrite: args.overwrite,
        // A board's or stdin's bytes; a simulated board sends records, not bytes: none.
        save_stream: args.sim.sim.is_none() && args.from.as_deref().is_none_or(|f| f == "-"),
        setup: SetupFlags {
            capstan_diameter_mm: args.diameter_mm,
            wrap_deg: args.wrap_deg,
            drive_v: crate::cli::predict::limits::recorded_drive(args.drive_v),
        },
        progress: !args.quiet,
        allow_empty: args.allow_empty,
        kept_after_failure: crate::outputs::say_kept,
    };
    super::signal::stop_flag("log"); // Ctrl-C and SIGTERM end the session, keeping it
    let (summary, stop, outcome) = match (&args.elf, &args.from) {
        (None, _) => sim::from_sim(opts, &args)?,
        (Some(elf), Some(from)) => from_stream(&Firmware::load(elf)?, opts, from, &args)?,
        (Some(elf), None) => board::from_board(&Firmware::load(elf)?, opts, &args)?,
    };
    let at = match &outcome {
        Outcome::Kept(p) => p.clone(),
        _ => args.out.clone(),
    };
    say_summary(&summary, &at);
    if outcome != Outcome::Committed {
        return not_committed(&summary, &stop, &outcome, &args);
    }
    if let (Some(_), Stop::Interrupted(why)) = (&args.sim.sim, &stop) {
        // The simulated board's session plans its runs: a signal stopped it short.
        let complete = summary.runs.iter().filter(|r| r.complete).count();
        return Err(super::signal::Interrupted(format!(
            "interrupted ({why}) after {complete} complete run(s), kept in {}",
            args.out.display()
        ))
        .into());
    }
    verdict(&summary, &stop, &args)
}

/// A session's notes, said on stderr as they arise.
fn notes<'f>() -> Notes<'f> {
    Box::new(|note| match note {
        Note::Recovered(r) => crate::errln!("note: {r}"),
        Note::Session(line) => crate::errln!("capstan log: {line}"),
    })
}

/// The session's closing lines, on stderr; `dir`: where its files are.
fn say_summary(summary: &Summary, dir: &std::path::Path) {
    for line in summary.human(dir) {
        crate::errln!("capstan log: {line}");
    }
}

/// The firmware ELF for messages (or what stands for it with --sim).
fn elf_name(args: &Args) -> String {
    args.elf.as_ref().map_or_else(
        || "the simulated board's".to_string(),
        |e| e.display().to_string(),
    )
}

fn limit_reached(logger: &Logger, args: &Args, started: std::time::Instant) -> Option<Stop> {
    if let Some(n) = args.runs.filter(|&n| logger.completed_runs() >= n) {
        return Some(Stop::Limit(format!("{n} run(s) logged (--runs)")));
    }
    if let Some(d) = args
        .duration
        .filter(|&d| started.elapsed().as_secs_f64() >= d)
    {
        return Some(Stop::Limit(format!("{d} s (--duration)")));
    }
    None
}

/// Feed a chunk; with `--runs`, frame by frame, so the session stops right after the record
/// that completes the last run wanted (a chunk of a saved stream may hold dozens of runs;
/// from a board, records arrive as they are made, so its chunks are small anyway).
fn feed(
    logger: &mut Logger,
    chunk: &[u8],
    args: &Args,
    started: std::time::Instant,
) -> anyhow::Result<Option<Stop>> {
    if args.runs.is_none() {
        logger.feed(chunk)?;
        return Ok(None);
    }
    for frame in chunk.split_inclusive(|&b| b == 0) {
        logger.push(frame)?;
        if let Some(s) = limit_reached(logger, args, started) {
            logger.flush()?;
            return Ok(Some(s));
        }
    }
    logger.flush()?;
    Ok(None)
}

/// Decode a file or stdin. The reading happens on its own thread so that Ctrl-C and the
/// limits are honoured even while a read blocks.
fn from_stream(
    fw: &Firmware,
    opts: LogOptions,
    from: &str,
    args: &Args,
) -> anyhow::Result<(Summary, Stop, Outcome)> {
    let (source, reader): (String, Box<dyn Read + Send>) = if from == "-" {
        ("stdin".to_string(), Box::new(std::io::stdin()))
    } else {
        let file =
            std::fs::File::open(from).with_context(|| format!("cannot open the stream {from}"))?;
        (from.to_string(), Box::new(file))
    };
    let mut logger = Logger::create(fw, opts, &source, notes())?;
    logger.set_provenance(provenance(args, Some(from))?);
    let (tx, rx) = mpsc::sync_channel::<std::io::Result<Vec<u8>>>(16);
    std::thread::spawn(move || {
        let mut reader = reader;
        let mut buf = vec![0u8; 64 * 1024];
        loop {
            let r = match reader.read(&mut buf) {
                Ok(0) => break,
                Ok(n) => Ok(buf[..n].to_vec()),
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(e) => Err(e),
            };
            let failed = r.is_err();
            if tx.send(r).is_err() || failed {
                break;
            }
        }
    });
    let started = std::time::Instant::now();
    let stop = loop {
        if super::signal::stop_flag("log").load(Ordering::SeqCst) {
            break Stop::Interrupted(super::signal::stop_reason().unwrap_or("Ctrl-C"));
        }
        if let Some(s) = limit_reached(&logger, args, started) {
            break s;
        }
        match rx.recv_timeout(Duration::from_millis(100)) {
            Ok(Ok(chunk)) => {
                if let Some(s) = feed(&mut logger, &chunk, args, started)? {
                    break s;
                }
            }
            Ok(Err(e)) => {
                let at = logger.bytes_seen();
                let (summary, outcome) = logger.finish_with(&Stop::EndOfStream)?;
                let place = match &outcome {
                    Outcome::Kept(p) => p.clone(),
                    _ => args.out.clone(),
                };
                say_summary(&summary, &place);
                let kept = match outcome {
                    Outcome::Committed => format!("what was received is in {}", place.display()),
                    Outcome::Kept(p) => format!(
                        "{} is as it was; what was received is kept in {}",
                        args.out.display(),
                        p.display()
                    ),
                    Outcome::Discarded => format!("{} is as it was", args.out.display()),
                };
                return Err(e)
                    .with_context(|| format!("reading {source} failed at byte {at} ({kept})"));
            }
            Err(mpsc::RecvTimeoutError::Timeout) => {}
            Err(mpsc::RecvTimeoutError::Disconnected) => break Stop::EndOfStream,
        }
    };
    let (summary, outcome) = logger.finish_with(&stop)?;
    Ok((summary, stop, outcome))
}
