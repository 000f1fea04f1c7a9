//! `capstan rig`: set the rig up from the host. One command line of the firmware's
//! (`firmware/rig/src/command.rs`) per call, checked here first, sent to the board (RTT down
//! channel through a debug probe), and answered from the `reply` record the firmware logs;
//! plus two host verbs, `live` and `keys`. (The simulated rig takes the same lines through
//! `capstan_sim::session`, in the tests.)
//!
//! The link to the rig is `capstan_link::rig`: the check that refuses bad input before
//! anything is sent, the [`RigLink`] trait and the wait for an answer, the board through a
//! probe. Here: `say` what is printed, `live` the live view, and the command itself.

mod live;
pub mod model;
mod say;

pub use live::{watch as watch_live, NotInSetup};
pub use say::{answer_lines, key_lines, live_line, Refused};

use anyhow::bail;
use capstan_link::rig::{check_set, command_line, exchange, CheckError, RigLink};
use capstan_link::Firmware;
use capstan_rig::command::Command;
use std::path::{Path, PathBuf};

const AFTER_HELP: &str = "\
SETTING UP THE RIG AT THE BENCH
  The board runs this repository's firmware, with a debug probe wired as for `capstan log`.
  Options first, then one command as separate words:
    R=\"capstan rig --chip RP2040 --elf target/thumbv6m-none-eabi/release/capstan-board\"
    $R setup                    setup mode: amplifier at 0 V, the servo moves only when told
    $R live 10                  T1/T2 in N and counts, servo angle, ~10 a second (Ctrl-C stops)
    $R jog 5                    move the servo 5° (jog -5 back)
    $R zero                     cord slack, nothing hanging: both zeros (0.5 s mean)
    $R weigh t1 9.80665         a 1 kg weight hanging on T1: its N/count (after a zero
                                in this setup session)
    $R weigh t2 9.80665         the same weight on T2
    $R servo 125                check the rest angle, then servo 65 for the final one
    $R set diameter_mm 12.7     and set wrap_deg 360 (capstan rig keys: every key, its unit)
    $R show                     every setting with its unit, and where it came from
    $R store                    keep the settings in flash (they survive a power-off)
    $R leave                    leave setup mode: the servo homes to rest
    $R run                      arm a run: a press of the rig's button within 30 s starts it
                                (the host never starts the drive). NOTHING RECORDS IT. To
                                record it: capstan log ... --no-flash --start (arms and logs)

  FORCE CONTROL (the servo holds T2 at a target; docs/README-force.md):
    $R load-model --from report/metrics.json   the fitted law at the rig's wrap, diameter and
                                drive (set them first); refused outside the fitted data
    $R set mode force           runs hold T2: steps of force_level1_n .. force_level4_n (set
                                force_profile ramp|sine, force_sine_hz ... for the others)

  Every command is checked here first, with the firmware's own parser and settings rules: a
  typo never reaches the board. Then it waits for the board's reply (3 s; store 5 s) and
  says it, with the numbers the board sent. Faults and firmware messages go to stderr.
  Exit status: 0 done; 1 refused by the board, no reply, or no probe; 2 refused here.

  capstan rig never flashes or resets the board. It reads the RTT channel `capstan log`
  reads: the records it takes are not seen by a `capstan log` running at the same time
  (that log reports them as a sequence gap). Stop the log while setting up, or accept the gap.

REHEARSING WITHOUT HARDWARE
  R=\"capstan rig --sim DIR\": the same commands to a simulated board, the firmware's own code
  on the host, its settings flash and state kept in DIR between commands (a new DIR is a new,
  unconfigured board; --sim-seed N etc. describe its rig when it is made). Its sensors have
  hidden zero and sensitivity errors: the truth is in DIR/sim-truth.json. What a person does
  by hand at a real rig is a command here:
    $R bench load t1 9.80665    hang 9.80665 N on T1 (then: weigh t1 9.80665)
    $R bench unload             take every weight off
    $R bench press              press the rig's button (200 ms; bench press MS): starts a run
                                (an armed one too), acknowledges a fault, leaves setup mode
    $R bench wait 3             let 3 s pass (a servo reaching rest)
    $R bench power-cycle        unplug the board and plug it back
  After each command 2 s pass at the bench. `live SECONDS` prints that much of the board's
  time at once. capstan log --sim DIR --start --runs N --out SESSION records N runs.";

/// Arguments of `capstan rig`.
#[derive(clap::Args, Debug)]
#[command(
    long_about = "Set up the rig from the host: live forces, jog the servo, calibrate, set the \
                  protocol, store it on the board, start a run. Sends one of the firmware's \
                  command lines and prints the board's answer.",
    after_long_help = AFTER_HELP
)]
pub struct Args {
    /// Board: the probe-rs chip name (RP2040 for the Pico). Attaches without flashing.
    #[arg(long, value_name = "CHIP", requires = "elf", conflicts_with = "sim")]
    pub chip: Option<String>,

    /// The simulated board instead (`--sim DIR`, see REHEARSING WITHOUT HARDWARE).
    #[command(flatten)]
    pub sim: super::simboard::SimArgs,

    /// The firmware ELF running on the board: its defmt table decodes the replies.
    #[arg(long, value_name = "FIRMWARE_ELF")]
    pub elf: Option<PathBuf>,

    /// Board: which probe, as VID:PID[:SERIAL] (needed when several are plugged in).
    #[arg(long, value_name = "VID:PID[:SERIAL]")]
    pub probe: Option<String>,

    /// Board: hold the chip in reset while attaching (this restarts the firmware: it leaves
    /// setup mode).
    #[arg(long)]
    pub connect_under_reset: bool,

    /// Board: SWD clock, kHz.
    #[arg(long, value_name = "KHZ")]
    pub speed: Option<u32>,

    /// load-model: the `metrics.json` of the fitted model (`capstan analyze`) whose law force
    /// control's feedforward goes through.
    #[arg(long, value_name = "METRICS_JSON")]
    pub from: Option<PathBuf>,

    /// The command: setup | leave | jog DEG | servo DEG | zero | weigh t1|t2 NEWTONS |
    /// set KEY VALUE | show | store | defaults | run | abort | ack; or on the host:
    /// live [SECONDS] | keys | load-model --from METRICS_JSON; or at a simulated board
    /// (--sim): bench load t1|t2 NEWTONS | bench unload | bench press [MS] | bench wait
    /// SECONDS | bench power-cycle.
    #[arg(value_name = "COMMAND", required = true, num_args = 1.., allow_negative_numbers = true)]
    pub words: Vec<String>,
}

/// Run `capstan rig`. A command refused here exits with status 2, one the board refuses with
/// status 1 (`refused: REASON` on stderr).
pub fn run(args: Args) -> anyhow::Result<()> {
    let e = match rig(&args) {
        Ok(()) => return Ok(()),
        Err(e) => e,
    };
    if let Some(c) = e.downcast_ref::<CheckError>() {
        crate::errln!("error: {c}");
        std::process::exit(2);
    }
    if let Some(r) = e.downcast_ref::<Refused>() {
        crate::errln!("{r}");
        std::process::exit(1);
    }
    Err(e)
}

fn rig(args: &Args) -> anyhow::Result<()> {
    let (verb, rest) = args.words.split_first().ok_or(CheckError::Empty)?;
    if args.from.is_some() != (verb == "load-model") {
        bail!(CheckError::Usage(
            "--from goes with load-model, and load-model needs it: capstan rig ... load-model \
             --from report/metrics.json"
                .into()
        ));
    }
    match verb.as_str() {
        "load-model" => {
            if !rest.is_empty() {
                bail!(CheckError::Usage(
                    "load-model takes no words, only --from METRICS_JSON".into()
                ));
            }
            let path = args.from.clone().unwrap_or_default();
            with_link(args, |link| load_model(link, &path, &mut out, &mut note))
        }
        "keys" => {
            if !rest.is_empty() {
                bail!(CheckError::Usage("keys takes no words".into()));
            }
            for line in key_lines() {
                crate::outln!("{line}");
            }
            Ok(())
        }
        "bench" => {
            if args.sim.sim.is_none() {
                bail!(CheckError::Usage(
                    "bench actions are for a simulated board (--sim DIR); at a real rig, do \
                     them by hand"
                        .into()
                ));
            }
            let (steps, said) = capstan_simboard::steps::bench(rest)
                .map_err(|e| CheckError::Usage(e.to_string()))?;
            let mut board = capstan_simboard::SimBoard::open(&args.sim.options(), &mut note)?;
            let done = board.advance(&steps)?;
            out(said);
            for e in super::simboard::link_events(done.events) {
                note_event(e);
            }
            Ok(())
        }
        "live" if args.sim.sim.is_some() => {
            let how_long = live::seconds(rest).map_err(CheckError::Usage)?;
            let how_long = how_long.unwrap_or(SIM_LIVE);
            let mut board = capstan_simboard::SimBoard::open(&args.sim.options(), &mut note)?;
            let ms = how_long.as_millis().min(3_600_000) as u32;
            let done = board.advance(&[capstan_sim::session::Step::Wait(ms)])?;
            let events = super::simboard::link_events(done.events);
            live::show(events, &mut out, &mut note).map(|_| ())
        }
        "live" => {
            let how_long = live::seconds(rest).map_err(CheckError::Usage)?;
            with_link(args, |link| {
                let stop = super::signal::stop_flag("rig");
                live::watch(link, how_long, stop, &mut out, &mut note).map(|_| ())
            })
        }
        _ => {
            let (line, cmd) = command_line(&args.words)?;
            if cmd == Command::Run {
                // The probe serves one program at a time and the board's log buffer holds
                // ~0.3 s: a run started here is not recorded unless capstan log arms it.
                let (board, press) = if args.sim.sim.is_some() {
                    ("--sim DIR", "`capstan rig --sim DIR bench press`")
                } else {
                    ("--chip ... --elf ... --no-flash", "the rig's button")
                };
                note(format!(
                    "note: `run` only arms a run: {press} starts it. Nothing records it; to \
                     record it, arm it with `capstan log {board} --start --out SESSION` instead"
                ));
            }
            with_link(args, |link| send(link, &line, &cmd, &mut out, &mut note))
        }
    }
}

/// How much of a simulated board's time `live` without SECONDS shows.
const SIM_LIVE: std::time::Duration = std::time::Duration::from_secs(5);

fn out(line: String) {
    crate::outln!("{line}");
}

/// What a simulated board said during a bench action: faults and replies (e.g. the button
/// leaving setup mode), on stderr.
fn note_event(e: capstan_link::frame::Event) {
    use capstan_rig::record::Record;
    if let capstan_link::frame::Event::Record { record, .. } = e {
        match record {
            Record::Fault(f) => note(capstan_link::words::fault_line(&f)),
            Record::Reply(r) => note(capstan_link::words::reply_line(&r, None)),
            Record::RunStart(s) => note(format!("the board started run {}", s.run)),
            Record::RunEnd(e) => note(format!(
                "the run ended: {} pairs{}",
                e.pairs,
                e.fault
                    .map_or(String::new(), |k| format!(", fault {}", k.name()))
            )),
            _ => {}
        }
    }
}

fn note(line: String) {
    crate::errln!("{line}");
}

/// `load-model`: the fitted model's law at the rig's wrap, diameter and drive voltage (from the
/// settings the board reports), refused outside the fitted data, sent as four `set`s.
pub fn load_model(
    link: &mut dyn RigLink,
    path: &Path,
    out: &mut dyn FnMut(String),
    note: &mut dyn FnMut(String),
) -> anyhow::Result<()> {
    let shown = exchange(link, "show", &Command::Show, note)?;
    let Some(report) = shown.settings else {
        bail!("the board did not report its settings (no answer to show)");
    };
    let (p, c) = (&report.settings.protocol, &report.settings.calibration);
    let f = &p.force;
    let max_target_n = match f.profile {
        capstan_rig::ForceProfile::Sine => f.levels_n[0] + f.levels_n[1],
        _ => f.levels_n.iter().copied().fold(0.0, f32::max),
    };
    // An f32 setting as the decimal it was set as (2.5 V × 4 is 10 V, not 10.000000149).
    let decimal = |v: f32| v.to_string().parse::<f64>().unwrap_or(f64::NAN);
    let point = model::RigPoint {
        wrap_deg: decimal(p.wrap_deg),
        diameter_mm: decimal(p.capstan_diameter_mm),
        drive_v: decimal(c.amp.drive_v(p.amp_control_v)),
        max_target_n: decimal(max_target_n),
    };
    let loaded = model::load(path, &point)?;
    for line in loaded.set_lines() {
        let words: Vec<String> = line.split(' ').map(String::from).collect();
        let (line, cmd) = command_line(&words)?;
        send(link, &line, &cmd, &mut |_| {}, note)?;
    }
    let l = &loaded.law;
    out(format!(
        "loaded {}: mu {} (at {} mm, {} V), heating {} /N, T2 offset {} N, exponent {}; the \
         largest target, {} N, needs T1 = {:.2} N (within the fitted data); store to keep it",
        path.display(),
        l.mu,
        point.diameter_mm,
        point.drive_v,
        l.heat_per_n,
        l.t2_offset_n,
        l.exponent,
        point.max_target_n,
        loaded.t1_max_n
    ));
    Ok(())
}

/// Send one checked command (`line`, from [`command_line`]) and say its answer to `out`;
/// faults and messages meanwhile go to `note`. A `set` is first checked against the settings
/// the rig reports (a `show`), and not sent if it would make them invalid ([`CheckError`]).
/// A refusal by the rig is [`Refused`].
pub fn send(
    link: &mut dyn RigLink,
    line: &str,
    cmd: &Command,
    out: &mut dyn FnMut(String),
    note: &mut dyn FnMut(String),
) -> anyhow::Result<()> {
    if matches!(cmd, Command::Set(..)) {
        let current = exchange(link, "show", &Command::Show, note)?;
        if let Some(s) = current.settings {
            check_set(cmd, &s.settings)?;
        }
    }
    let answer = exchange(link, line, cmd, note)?;
    for l in answer_lines(&answer, cmd)? {
        out(l);
    }
    Ok(())
}

/// Reach the rig the options name and hand it to `work`.
fn with_link(
    args: &Args,
    work: impl FnOnce(&mut dyn RigLink) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    if args.sim.sim.is_some() {
        let board = capstan_simboard::SimBoard::open(&args.sim.options(), &mut note)?;
        let mut link = super::simboard::SimLink::new(board);
        return work(&mut link);
    }
    let (Some(chip), Some(elf)) = (&args.chip, &args.elf) else {
        bail!(
            "say which board: --chip CHIP --elf FIRMWARE_ELF (through a debug probe), or \
             --sim DIR (a simulated one); `capstan rig keys` needs neither"
        );
    };
    let fw = Firmware::load(elf)?;
    board(&fw, chip, elf, args, work)
}

#[cfg(feature = "probe")]
fn board(
    fw: &Firmware,
    chip: &str,
    elf: &Path,
    args: &Args,
    work: impl FnOnce(&mut dyn RigLink) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let opts = capstan_link::probe::ProbeOptions {
        chip: chip.to_string(),
        probe: args.probe.clone(),
        flash: false,
        connect_under_reset: args.connect_under_reset,
        speed_khz: args.speed,
        rtt_channel: 0,
        rtt_timeout: std::time::Duration::from_secs(5),
    };
    let mut link = capstan_link::rig::probe_link::open(fw, elf, opts)?;
    work(&mut link)
}

#[cfg(not(feature = "probe"))]
fn board(
    _fw: &Firmware,
    _chip: &str,
    _elf: &Path,
    _args: &Args,
    _work: impl FnOnce(&mut dyn RigLink) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    bail!(
        "this `capstan` was built without the `probe` feature: it cannot reach a board. \
         Rebuild with default features."
    )
}
