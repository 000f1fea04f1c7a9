//! `capstan simulate`: the rig's firmware against the simulated plant, a whole campaign in
//! virtual time (or the two-control, single-drive rig with `--two-control`).//!
//! * this module: the arguments, and a campaign run from them;
//! * `checks`: the arguments against the physical ranges, and the files a campaign writes;
//! * `output`: a campaign's files (`pairs.csv`, raw logs, `faults.csv`), JSON and summary;
//! * `two`: the two-control rig (`--two-control`) and its files.

mod checks;
mod force;
mod output;
mod two;
mod two_force;

use anyhow::{bail, Context};
use capstan_physics::{Effect, Model};
use capstan_rig::StepOrder;
use capstan_sim::campaign::{stream_campaign, CampaignConfig, StreamError};
use capstan_sim::noise::NoiseProfile;
use std::io::IsTerminal;
use std::path::PathBuf;

/// Step orders on the command line.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Order {
    /// Levels 1, 2, ..., 12: tension rises with time (the thesis).
    Monotone,
    /// Odd levels up, even levels down: level decorrelated from time.
    Updown,
    /// Level 1 and level 12 alternately (for the two-control rig).
    Pulse,
}

impl From<Order> for StepOrder {
    fn from(o: Order) -> StepOrder {
        match o {
            Order::Monotone => StepOrder::Monotone,
            Order::Updown => StepOrder::UpDown,
            Order::Pulse => StepOrder::Pulse,
        }
    }
}

/// What the simulated runs do.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// The test protocol: the servo steps through its angles (a campaign).
    Protocol,
    /// Force control: the servo holds T2 at a target (one rig; docs/README-force.md).
    Force,
}

/// Force mode's target profiles on the command line.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Profile {
    /// One level a segment (--levels-n, up to four).
    Steps,
    /// Hold the first level, ramp to the second over a dwell, hold it.
    Ramp,
    /// Hold the mean (first level), then a sine of the second's amplitude at each frequency of
    /// --sine-hz.
    Sine,
}

impl From<Profile> for capstan_rig::ForceProfile {
    fn from(p: Profile) -> capstan_rig::ForceProfile {
        match p {
            Profile::Steps => capstan_rig::ForceProfile::Steps,
            Profile::Ramp => capstan_rig::ForceProfile::Ramp,
            Profile::Sine => capstan_rig::ForceProfile::Sine,
        }
    }
}

/// Arguments of `capstan simulate`.
#[derive(clap::Args, Debug)]
#[command(after_help = "\
Defaults are the thesis's campaign: 2 diameters x 5 wraps x 6 runs of 131.5 s at 10 V, \
monotone steps, Euler-Eytelwein with mu = 0.115, no effect, no scatter, sensor noise on.

Writes DIR/pairs.csv (capstan_diameter_mm,wrap_deg,drive_v,run,step,time_s,t1_n,t2_n), \
DIR/raw/<cord>_run<k>.csv (the firmware's 100 Hz raw log) and DIR/faults.csv.

--two-control runs one firmware per wrap given (default 720,720) on one capstan and one \
drive motor (orders from --orders, default monotone,pulse; --delays-ms 0,5000) and writes \
DIR/two_control.csv (drive and tensions over time), DIR/crosstalk.csv and \
DIR/pairs_ch<k>.csv.

--mode force: the servo holds T2 at a target (steps 5,10,20,30 N by default; --profile \
steps,ramp,sine) on the thesis rig (720°, 12.7 mm, 10 V), the board's feedforward through the \
thesis fit (or --model-from metrics.json); pairs.csv and raw/ carry t2_target_n, and capstan \
analyze DIR/pairs.csv reports the tracking. --compare: open loop against feedback on cords whose \
mu is off. With --two-control: every channel in force mode. See docs/README-force.md.")]
pub struct Args {
    /// Output directory (created if needed).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Capstan diameters, mm [default: 12.7,25.4; two-control: 12.7].
    #[arg(
        long,
        value_delimiter = ',',
        value_name = "MM",
        allow_negative_numbers = true
    )]
    pub diameters: Option<Vec<f64>>,
    /// Wrap angles, deg [default: 270,360,450,630,720; two-control: 720,720, one per channel].
    #[arg(
        long,
        value_delimiter = ',',
        value_name = "DEG",
        allow_negative_numbers = true
    )]
    pub wraps: Option<Vec<f64>>,
    /// Repeat runs per cord [default: 6].
    #[arg(long, allow_negative_numbers = true)]
    pub runs: Option<u32>,
    /// Drive voltages, V (at most 13.2: 3.3 V of control x the amplifier's gain of 4).
    #[arg(long = "drive-v", value_delimiter = ',', value_name = "V", default_values_t = [10.0], allow_negative_numbers = true)]
    pub drive_v: Vec<f64>,
    /// Order of the tension levels [default: monotone]. (Two-control: --orders, one per
    /// channel.)
    #[arg(long, value_enum)]
    pub order: Option<Order>,
    /// A catalogue effect, NAME=VALUE (repeatable), e.g. pressure_friction=0.85; each value
    /// within what a real rig can hold (t2_offset -3 to 5 N, sensor_gain 0.5 to 2, ...).
    #[arg(long = "effect", value_name = "NAME=VALUE")]
    pub effects: Vec<String>,
    /// Friction coefficient of the base model.
    #[arg(long, default_value_t = 0.115, allow_negative_numbers = true)]
    pub mu: f64,
    /// Cord-to-cord sd of mu, % [default: 0; with --noise thesis, the thesis rig's].
    #[arg(long, value_name = "PCT", allow_negative_numbers = true)]
    pub scatter: Option<f64>,
    /// Run-to-run sd of mu within a cord, % [default: half of --scatter; with --noise thesis,
    /// the thesis rig's].
    #[arg(long, value_name = "PCT", allow_negative_numbers = true)]
    pub run_scatter: Option<f64>,
    /// Noise profile: `quiet` (sensor white noise only) or `thesis` (the thesis rig's scatter
    /// of mu between cords and runs, a slow wander of mu within runs, a zero error per run).
    #[arg(long, default_value = "quiet", value_name = "PROFILE")]
    pub noise: String,
    /// Physics outside the effect catalogue, NAME=VALUE (repeatable): hysteresis (mu larger by
    /// this fraction while the tension falls), t2_nonlinearity (the T2 sensor's S-shaped calibration error, its largest deviation in N),
    /// regime_change (mu changes by this fraction above T1 ≈ 4 N), t2_lowforce (the T2 hook
    /// seats at low force: T2 reads q(1 − e^(−T2/1 N)) more, N), t1_tare_diameter (T1 reads
    /// −q(D − 19.05 mm)/19.05 mm more, N), t2_offset_wrap (T2 reads q(β − 540°)/360° more, N
    /// per turn), settling (mu·(1 − c·e^(−t/10 s)) after the trigger), t2_range_step (T2 reads
    /// q more above 15 N: an amplifier range switch, N). See docs/README-discover.md.
    #[arg(long = "unmodelled", value_name = "NAME=VALUE")]
    pub unmodelled: Vec<String>,
    /// Seed of every random number (noise, scatter, sensor zeros).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Inject a fault, NAME@SECONDS after the trigger in every run, or NAME@SECONDS#RUN in
    /// one run (1.. over the campaign); NAME: cord_break, sensor_unplugged[_t1|_t2], over_force,
    /// abort, sensor_frozen[_t1|_t2], servo_stall.
    #[arg(long = "fault", value_name = "NAME@SECONDS[#RUN]")]
    pub faults: Vec<String>,
    /// Noiseless sensors.
    #[arg(long)]
    pub no_noise: bool,
    /// Protocol: time per step, ms.
    #[arg(long, value_name = "MS", allow_negative_numbers = true)]
    pub dwell_ms: Option<u32>,
    /// Protocol: conditioning starts this long after a change, ms.
    #[arg(long, value_name = "MS", allow_negative_numbers = true)]
    pub window_after_ms: Option<u32>,
    /// Protocol: conditioning ends this long before the next change, ms.
    #[arg(long, value_name = "MS", allow_negative_numbers = true)]
    pub window_before_ms: Option<u32>,
    /// Worker threads [default: one per core].
    #[arg(long)]
    pub threads: Option<usize>,
    /// Do not write the raw logs.
    #[arg(long)]
    pub no_raw: bool,
    /// Print one JSON object (and no progress bar).
    #[arg(long)]
    pub json: bool,
    /// The two-control, single-drive rig instead of a campaign.
    #[arg(long)]
    pub two_control: bool,
    /// Two-control: step order of each channel [default: monotone,pulse].
    #[arg(long, value_enum, value_delimiter = ',')]
    pub orders: Option<Vec<Order>>,
    /// Two-control: extra wait before each channel's trigger, ms [default: 0,5000].
    #[arg(
        long = "delays-ms",
        value_delimiter = ',',
        value_name = "MS",
        allow_negative_numbers = true
    )]
    pub delays_ms: Option<Vec<u32>>,
    /// Drive motor winding resistance, Ω [default: 4.65; the thesis m-file says 46.5].
    #[arg(long, value_name = "OHM", allow_negative_numbers = true)]
    pub motor_ohm: Option<f64>,
    /// What the runs do: protocol (a campaign of servo steps) or force (the servo holds T2 at
    /// a target: one rig, default 720° on the 12.7 mm capstan at 10 V).
    #[arg(long, value_enum, default_value = "protocol")]
    pub mode: Mode,
    /// Force mode: the target profile, or a list of them for consecutive runs (steps,sine: run
    /// 1 steps, run 2 a sine sweep) [default: steps].
    #[arg(long, value_enum, value_delimiter = ',')]
    pub profile: Option<Vec<Profile>>,
    /// Force mode: T2 targets, N [default: steps 5,10,20,30; ramp 5,25 (from, to); sine 15,5
    /// (mean, amplitude)].
    #[arg(
        long = "levels-n",
        value_delimiter = ',',
        value_name = "N",
        allow_negative_numbers = true
    )]
    pub levels_n: Option<Vec<f64>>,
    /// Force mode, sine: F, F0:F1 or F0:F1:STEPS, Hz, log-spaced, one frequency a dwell
    /// [default: 0.3:20:10].
    #[arg(long = "sine-hz", value_name = "F0:F1:STEPS")]
    pub sine_hz: Option<String>,
    /// Force mode: the fitted model (`capstan analyze`'s metrics.json) whose law the board's
    /// feedforward goes through, and the cord's [default: the thesis fit, built in].
    #[arg(long = "model-from", value_name = "METRICS_JSON")]
    pub model_from: Option<PathBuf>,
    /// Force mode: the cord's mu over the model's (1.2: a new cord with 20 % more friction).
    #[arg(
        long = "cord-mu-factor",
        value_name = "X",
        allow_negative_numbers = true
    )]
    pub cord_mu_factor: Option<f64>,
    /// Force mode: the cord without the model's contact heating.
    #[arg(long)]
    pub no_heating: bool,
    /// Force mode: no feedback on T2 (the feedforward through the law alone).
    #[arg(long)]
    pub open_loop: bool,
    /// Force mode: give the board Euler-Eytelwein with this one mu instead of the fitted law.
    #[arg(long = "ee-mu", value_name = "MU", allow_negative_numbers = true)]
    pub ee_mu: Option<f64>,
    /// Force mode: proportional gain on the T2 error [default: the firmware's, 1].
    #[arg(long, allow_negative_numbers = true)]
    pub kp: Option<f64>,
    /// Force mode: integral gain, 1/s [default: the firmware's, 5].
    #[arg(long, allow_negative_numbers = true)]
    pub ki: Option<f64>,
    /// Force mode: open loop with Euler-Eytelwein and one mu, open loop with the fitted law,
    /// and the law with feedback, side by side on the model's cord, cords whose mu is off by
    /// ±--compare-mu-pct and the model's cord without heating: compare.csv.
    #[arg(long)]
    pub compare: bool,
    /// Force mode, --compare: how far the new cords' mu is off the model's, %.
    #[arg(
        long = "compare-mu-pct",
        default_value_t = 20.0,
        allow_negative_numbers = true
    )]
    pub compare_mu_pct: f64,
}

fn model(args: &Args) -> anyhow::Result<(Model, Vec<Effect>)> {
    if !(args.mu.is_finite() && args.mu >= 0.0 && args.mu <= 2.0) {
        bail!("--mu {}: must be 0 to 2", args.mu);
    }
    let mut effects: Vec<Effect> = Vec::new();
    for e in &args.effects {
        let eff: Effect = e
            .parse()
            .map_err(|err| anyhow::anyhow!("--effect {e}: {err}"))?;
        if effects.iter().any(|x| x.kind == eff.kind) {
            bail!("--effect {e}: {} is given twice", eff.kind);
        }
        effects.push(eff);
    }
    Ok((Model::euler_eytelwein(args.mu), effects))
}

/// What made this campaign, for `summary.json`: the program, commit and command line, the
/// master seed, the plant's mu, the effects, the noise and the unmodelled physics.
fn provenance(args: &Args, cfg: &CampaignConfig) -> serde_json::Value {
    let u = &cfg.unmodelled;
    let mut p = provenance_of(
        cfg.seed,
        &cfg.model,
        &cfg.effects,
        serde_json::json!({
            "profile": args.noise,
            "sensor_noise": cfg.sensor_noise,
            "cord_scatter_pct": cfg.scatter_pct,
            "run_scatter_pct": cfg.run_scatter(),
        }),
    );
    p["unmodelled"] = serde_json::json!({
        "hysteresis": u.hysteresis,
        "t2_nonlinearity": u.t2_nonlinearity,
        "regime_change": u.regime_change,
    });
    p["faults"] = serde_json::json!(args.faults);
    p
}

/// What every simulation's provenance says: the program, commit and command line, the master
/// seed, the plant's mu, the effects (name and value) and `noise`.
fn provenance_of(
    seed: u64,
    model: &Model,
    effects: &[Effect],
    noise: serde_json::Value,
) -> serde_json::Value {
    let p = crate::provenance::without_input();
    serde_json::json!({
        "program": p.program,
        "commit": p.commit,
        "command_line": p.command_line,
        "seed": seed,
        "mu": model.law.mu,
        "effects": effects.iter().map(|e| serde_json::json!({"name": e.kind.name(), "value": e.value})).collect::<Vec<_>>(),
        "noise": noise,
    })
}

/// The physics outside the catalogue given by `--unmodelled`.
fn unmodelled(args: &Args) -> anyhow::Result<capstan_sim::plant::Unmodelled> {
    let mut u = capstan_sim::plant::Unmodelled::default();
    let mut seen: Vec<&str> = Vec::new();
    for item in &args.unmodelled {
        let known = capstan_sim::plant::Unmodelled::ALL_NAMES.join(", ");
        let (name, value) = item
            .split_once('=')
            .ok_or_else(|| anyhow::anyhow!("--unmodelled {item}: expected NAME=VALUE"))?;
        let name = name.trim();
        let value: f64 = value
            .trim()
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite())
            .ok_or_else(|| anyhow::anyhow!("--unmodelled {item}: the value is not a number"))?;
        if seen.contains(&name) {
            bail!("--unmodelled {item}: {name} is given twice");
        }
        if !u.set(name, value) {
            bail!("--unmodelled {item}: unknown (known: {known})");
        }
        seen.push(name);
    }
    Ok(u)
}

/// The protocol, refused with the values in force (the defaults where none was given) when
/// the firmware would refuse it.
fn checked_protocol(args: &Args) -> anyhow::Result<capstan_rig::Protocol> {
    let p = protocol(args);
    if let Err(e) = p.validate() {
        bail!(
            "the firmware refuses the protocol: {e} (in force: --dwell-ms {}, --window-after-ms \
             {}, --window-before-ms {}; defaults where not given)",
            p.dwell_ms,
            p.window_after_change_ms,
            p.window_before_next_ms
        );
    }
    Ok(p)
}

fn protocol(args: &Args) -> capstan_rig::Protocol {
    let mut p = capstan_rig::Protocol::default();
    if let Some(v) = args.dwell_ms {
        p.dwell_ms = v;
    }
    if let Some(v) = args.window_after_ms {
        p.window_after_change_ms = v;
    }
    if let Some(v) = args.window_before_ms {
        p.window_before_next_ms = v;
    }
    p
}

fn plant(args: &Args) -> anyhow::Result<capstan_sim::plant::PlantConfig> {
    let mut plant = capstan_sim::plant::PlantConfig::default();
    if let Some(r) = args.motor_ohm {
        if !(r.is_finite() && r > 0.0) {
            bail!("--motor-ohm {r}: must be a positive resistance");
        }
        plant.motor.resistance_ohm = r;
    }
    Ok(plant)
}

/// Run `capstan simulate`.
pub fn run(args: Args) -> anyhow::Result<()> {
    checks::check_ranges(&args)?;
    if args.mode == Mode::Force && !args.two_control {
        return force::run_force(&args);
    }
    if args.two_control {
        return two::run_two(&args);
    }
    for (flag, given) in [
        ("--profile", args.profile.is_some()),
        ("--levels-n", args.levels_n.is_some()),
        ("--sine-hz", args.sine_hz.is_some()),
        ("--model-from", args.model_from.is_some()),
        ("--cord-mu-factor", args.cord_mu_factor.is_some()),
        ("--no-heating", args.no_heating),
        ("--open-loop", args.open_loop),
        ("--ee-mu", args.ee_mu.is_some()),
        ("--kp", args.kp.is_some()),
        ("--ki", args.ki.is_some()),
        ("--compare", args.compare),
    ] {
        if given {
            bail!("{flag} is for --mode force");
        }
    }
    if args.two_control {
        return two::run_two(&args);
    }
    for (flag, given) in [
        ("--orders", args.orders.is_some()),
        ("--delays-ms", args.delays_ms.is_some()),
    ] {
        if given {
            bail!("{flag} is for --two-control (a campaign uses --order)");
        }
    }
    let cfg = campaign_config(&args)?;
    // Every file the campaign will write is checked before it runs: none may be the user's
    // own (or a link), `raw` must be a directory of ours.
    let writes = |rel: &str| checks::writes_raw(&cfg, rel);
    let out = capstan_outdir::OutputDir::open_with(
        &args.out,
        "simulate",
        &["pairs.csv", "faults.csv", "summary.json"],
        &[("raw", &writes)],
    )?;
    crate::outputs::say_recovered(&out);
    // An interrupted campaign replaces no complete one: it is kept beside it instead.
    let had_previous = (out.path())
        .join(capstan_outdir::manifest_name("simulate"))
        .exists();
    let mut files = output::CampaignWriter::new(out, !args.no_raw)?;
    let stats = stream(&args, &cfg, &mut files)?;
    if stats.done == 0 {
        // Stopped before a single run was made: nothing to replace the previous results with.
        drop(files);
        return Err(super::signal::Interrupted(format!(
            "interrupted before the first run was made; {} is as it was",
            args.out.display()
        ))
        .into());
    }
    let mut summary = output::campaign_json(&stats, files.rows, &files.faults, files.faults_total);
    summary["provenance"] = provenance(&args, &cfg);
    let (rows, faults, faults_total) = (
        files.rows,
        std::mem::take(&mut files.faults),
        files.faults_total,
    );
    // A campaign that made no usable pair (every run ended with a fault) replaces nothing.
    let empty = rows == 0;
    let kept = files.finish(&summary, empty || (stats.interrupted && had_previous))?;
    if let (true, Some(at)) = (empty && !stats.interrupted, &kept) {
        anyhow::bail!(
            "no usable pair was made: all {} runs ended with a fault (why: {}); {} is as it was",
            stats.done,
            at.join("faults.csv").display(),
            args.out.display()
        );
    }
    let at = kept.clone().unwrap_or_else(|| args.out.clone());
    if args.json {
        crate::outln!("{summary}");
    } else {
        output::print_summary(&at, &stats, rows, &faults, faults_total, !args.no_raw);
    }
    if stats.interrupted {
        return Err(interrupted(
            &stats,
            &at,
            kept.is_some() && had_previous,
            &args.out,
        ));
    }
    Ok(())
}

/// The error of a campaign stopped by a signal: what was made and where it is, and whether
/// the complete campaign already in `out` is as it was (`kept_beside`).
fn interrupted(
    stats: &capstan_sim::campaign::CampaignStats,
    at: &std::path::Path,
    kept_beside: bool,
    out: &std::path::Path,
) -> anyhow::Error {
    let previous = if kept_beside {
        format!("; the complete campaign in {} is as it was", out.display())
    } else {
        String::new()
    };
    super::signal::Interrupted(format!(
        "interrupted: {} of {} runs made; they are in {} (summary.json says \"interrupted\"){previous}",
        stats.done,
        stats.planned,
        at.display()
    ))
    .into()
}

/// The campaign the options describe (the noise profile's defaults where none is given),
/// validated.
fn campaign_config(args: &Args) -> anyhow::Result<CampaignConfig> {
    let (model, effects) = model(args)?;
    let mut faults = Vec::new();
    for f in &args.faults {
        faults.push(checks::fault(f)?);
    }
    let noise: NoiseProfile = args
        .noise
        .parse()
        .map_err(|e| anyhow::anyhow!("--noise {e}"))?;
    let mut defaults = CampaignConfig::default();
    noise.apply(&mut defaults);
    let mut cfg = CampaignConfig {
        diameters_mm: args.diameters.clone().unwrap_or(defaults.diameters_mm),
        wraps_deg: args.wraps.clone().unwrap_or(defaults.wraps_deg),
        drive_vs: args.drive_v.clone(),
        runs: args.runs.unwrap_or(6),
        order: args.order.unwrap_or(Order::Monotone).into(),
        effects,
        model,
        scatter_pct: args.scatter.unwrap_or(defaults.scatter_pct),
        run_scatter_pct: args.run_scatter.or(defaults.run_scatter_pct),
        unmodelled: unmodelled(args)?,
        sensor_noise: !args.no_noise,
        seed: args.seed,
        faults,
        protocol: checked_protocol(args)?,
        plant: plant(args)?,
        threads: args.threads.unwrap_or(0),
        keep_raw: !args.no_raw,
        ..defaults
    };
    cfg.plant.disturbances = noise.disturbances();
    cfg.validate().map_err(|e| anyhow::anyhow!("{e}"))?;
    Ok(cfg)
}

/// Run the campaign, each run into `files` as it is made, with a progress bar on a terminal;
/// stops early on Ctrl-C (the stats say so).
fn stream(
    args: &Args,
    cfg: &CampaignConfig,
    files: &mut output::CampaignWriter,
) -> anyhow::Result<capstan_sim::campaign::CampaignStats> {
    let bar = progress_bar(args, cfg.run_count());
    let stop = super::signal::stop_flag("simulate");
    let streamed = stream_campaign(cfg, stop, &mut |r| {
        files
            .add(&r)
            .with_context(|| format!("writing run {} into {}", r.index, args.out.display()))?;
        if let Some(pb) = &bar {
            pb.set_position(r.index as u64);
        }
        Ok::<(), anyhow::Error>(())
    });
    if let Some(pb) = bar {
        pb.finish_and_clear();
    }
    match streamed {
        Ok(s) => Ok(s),
        Err(StreamError::Campaign(e)) => bail!("{e}"),
        Err(StreamError::Sink(e)) => Err(e),
    }
}

fn progress_bar(args: &Args, runs: usize) -> Option<indicatif::ProgressBar> {
    (!args.json && std::io::stderr().is_terminal()).then(|| {
        let pb = indicatif::ProgressBar::new(runs as u64);
        pb.set_style(
            indicatif::ProgressStyle::with_template(
                "simulating {bar:40} {pos}/{len} runs [{elapsed_precise}]",
            )
            .expect("a valid template"),
        );
        pb
    })
}
