//! `capstan simulate`: the rig's firmware against the simulated plant, a whole campaign in
//! virtual time (or the two-control, single-drive rig with `--two-control`).

use crate::data::{write_pairs, Pair};
use anyhow::{bail, Context};
use capstan_friction::{Effect, Model};
use firmware::StepOrder;
use host_sim::campaign::{
    run_campaign_with_progress, CampaignConfig, CampaignResult, FaultSpec, PairRow, RunResult,
};
use host_sim::two_control::{run_two_control, ChannelSpec, TwoControlConfig, TwoControlResult};
use serde_json::json;
use std::fs::File;
use std::io::{BufWriter, IsTerminal, Write};
use std::path::{Path, PathBuf};

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
DIR/pairs_ch<k>.csv.")]
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
    /// Repeat runs per cord.
    #[arg(long, default_value_t = 6)]
    pub runs: u32,
    /// Drive voltages, V (at most 13.2: 3.3 V of control x the amplifier's gain of 4).
    #[arg(long = "drive-v", value_delimiter = ',', value_name = "V", default_values_t = [10.0], allow_negative_numbers = true)]
    pub drive_v: Vec<f64>,
    /// Order of the tension levels.
    #[arg(long, value_enum, default_value = "monotone")]
    pub order: Order,
    /// A catalogue effect, NAME=VALUE (repeatable), e.g. pressure_friction=0.85.
    #[arg(long = "effect", value_name = "NAME=VALUE")]
    pub effects: Vec<String>,
    /// Friction coefficient of the base model.
    #[arg(long, default_value_t = 0.115, allow_negative_numbers = true)]
    pub mu: f64,
    /// Cord-to-cord sd of mu, % (run-to-run: half of it).
    #[arg(
        long,
        default_value_t = 0.0,
        value_name = "PCT",
        allow_negative_numbers = true
    )]
    pub scatter: f64,
    /// Seed of every random number (noise, scatter, sensor zeros).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Inject a fault, NAME@SECONDS after the trigger in every run, or NAME@SECONDS#RUN in
    /// one run (1.. over the campaign); NAME: cord_break, sensor_unplugged, over_force, abort.
    #[arg(long = "fault", value_name = "NAME@SECONDS[#RUN]")]
    pub faults: Vec<String>,
    /// Noiseless sensors.
    #[arg(long)]
    pub no_noise: bool,
    /// Protocol: time per step, ms.
    #[arg(long, value_name = "MS")]
    pub dwell_ms: Option<u32>,
    /// Protocol: conditioning starts this long after a change, ms.
    #[arg(long, value_name = "MS")]
    pub window_after_ms: Option<u32>,
    /// Protocol: conditioning ends this long before the next change, ms.
    #[arg(long, value_name = "MS")]
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
    #[arg(long = "delays-ms", value_delimiter = ',', value_name = "MS")]
    pub delays_ms: Option<Vec<u32>>,
    /// Drive motor winding resistance, Ω [default: 4.65; the thesis m-file says 46.5].
    #[arg(long, value_name = "OHM")]
    pub motor_ohm: Option<f64>,
}

fn model(args: &Args) -> anyhow::Result<(Model, Vec<Effect>)> {
    if !(args.mu.is_finite() && args.mu >= 0.0 && args.mu <= 2.0) {
        bail!("--mu {}: must be 0 to 2", args.mu);
    }
    let mut effects = Vec::new();
    for e in &args.effects {
        let eff: Effect = e
            .parse()
            .map_err(|err| anyhow::anyhow!("--effect {e}: {err}"))?;
        effects.push(eff);
    }
    Ok((Model::euler_eytelwein(args.mu), effects))
}

fn protocol(args: &Args) -> firmware::Protocol {
    let mut p = firmware::Protocol::default();
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

fn plant(args: &Args) -> anyhow::Result<host_sim::plant::PlantConfig> {
    let mut plant = host_sim::plant::PlantConfig::default();
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
    if args.two_control {
        return run_two(&args);
    }
    for (flag, given) in [
        ("--orders", args.orders.is_some()),
        ("--delays-ms", args.delays_ms.is_some()),
    ] {
        if given {
            bail!("{flag} is for --two-control (a campaign uses --order)");
        }
    }
    let (model, effects) = model(&args)?;
    let mut faults = Vec::new();
    for f in &args.faults {
        faults.push(
            f.parse::<FaultSpec>()
                .map_err(|e| anyhow::anyhow!("--fault {e}"))?,
        );
    }
    let defaults = CampaignConfig::default();
    let cfg = CampaignConfig {
        diameters_mm: args.diameters.clone().unwrap_or(defaults.diameters_mm),
        wraps_deg: args.wraps.clone().unwrap_or(defaults.wraps_deg),
        drive_vs: args.drive_v.clone(),
        runs: args.runs,
        order: args.order.into(),
        effects,
        model,
        scatter_pct: args.scatter,
        sensor_noise: !args.no_noise,
        seed: args.seed,
        faults,
        protocol: protocol(&args),
        plant: plant(&args)?,
        threads: args.threads.unwrap_or(0),
        keep_raw: !args.no_raw,
        ..defaults
    };
    cfg.validate().map_err(|e| anyhow::anyhow!("{e}"))?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;

    let bar = (!args.json && std::io::stderr().is_terminal()).then(|| {
        let pb = indicatif::ProgressBar::new(cfg.run_count() as u64);
        pb.set_style(
            indicatif::ProgressStyle::with_template(
                "simulating {bar:40} {pos}/{len} runs [{elapsed_precise}]",
            )
            .expect("a valid template"),
        );
        pb
    });
    let progress = |done: usize, _total: usize| {
        if let Some(pb) = &bar {
            pb.set_position(done as u64);
        }
    };
    let result = run_campaign_with_progress(&cfg, &progress).map_err(|e| anyhow::anyhow!("{e}"))?;
    if let Some(pb) = bar {
        pb.finish_and_clear();
    }

    let pairs_path = args.out.join("pairs.csv");
    write_pairs(&pairs_path, &to_pairs(&result.rows))?;
    if !args.no_raw {
        write_raw_logs(&args.out.join("raw"), &result.runs)?;
    }
    write_faults(&args.out.join("faults.csv"), &result)?;

    // An injection after its run had ended never happened: say so rather than list it.
    for r in &result.runs {
        if let Err(e) = r.end {
            eprintln!(
                "warning: run {} ({} run {}) did not end: {e:?}",
                r.index,
                r.cord.label(),
                r.run
            );
        }
        for inj in r.injections.iter().filter(|i| i.at_us.is_none()) {
            eprintln!(
                "warning: run {}: {}@{} s never took effect (the run ended {:.1} s after its \
                 trigger)",
                r.index,
                inj.injection.kind.name(),
                inj.injection.after_trigger_us as f64 / 1e6,
                r.log.end.map_or(f64::NAN, |e| e.t_us as f64 / 1e6)
            );
        }
    }
    if args.json {
        println!("{}", campaign_json(&result));
    } else {
        print_summary(&args.out, &result, !args.no_raw);
    }
    Ok(())
}

fn to_pairs(rows: &[PairRow]) -> Vec<Pair> {
    rows.iter()
        .map(|r| Pair {
            capstan_diameter_mm: Some(r.capstan_diameter_mm),
            wrap_deg: r.wrap_deg,
            drive_v: Some(r.drive_v),
            run: Some(r.run as f64),
            step: Some(r.step as f64),
            time_s: Some(r.time_s),
            t1_n: r.t1_n,
            t2_n: r.t2_n,
            extra: Vec::new(),
        })
        .collect()
}

fn create(path: &Path) -> anyhow::Result<BufWriter<File>> {
    let f = File::create(path).with_context(|| format!("cannot write {}", path.display()))?;
    Ok(BufWriter::new(f))
}

fn raw_name(r: &RunResult) -> String {
    format!("{}_run{}.csv", r.cord.label(), r.run)
}

fn write_raw_logs(dir: &Path, runs: &[RunResult]) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    // Raw logs of an earlier simulation into the same directory would mix with these.
    if let Ok(entries) = std::fs::read_dir(dir) {
        for e in entries.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            let ours = name.starts_with('d') && name.contains("_run") && name.ends_with(".csv");
            if ours && !runs.iter().any(|r| raw_name(r) == name) {
                let _ = std::fs::remove_file(e.path());
            }
        }
    }
    for r in runs {
        let path = dir.join(raw_name(r));
        let mut w = create(&path)?;
        writeln!(w, "t_s,t1_counts,t2_counts,t1_n,t2_n")?;
        for s in &r.log.raw {
            writeln!(
                w,
                "{},{},{},{},{}",
                s.t_us as f64 / 1e6,
                s.counts[0],
                s.counts[1],
                s.force_n[0],
                s.force_n[1]
            )?;
        }
        w.flush()
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    Ok(())
}

fn opt<T: ToString>(v: Option<T>) -> String {
    v.map_or(String::new(), |x| x.to_string())
}

fn write_faults(path: &Path, r: &CampaignResult) -> anyhow::Result<()> {
    let mut w = create(path)?;
    writeln!(
        w,
        "run,capstan_diameter_mm,wrap_deg,drive_v,repeat,injected,fault,at_s,detected_s,safe_after_ms,pairs_kept"
    )?;
    for f in &r.faults {
        writeln!(
            w,
            "{},{},{},{},{},{},{},{},{},{},{}",
            f.run,
            f.cord.diameter_mm,
            f.cord.wrap_deg,
            f.cord.drive_v,
            f.repeat,
            opt(f.injected.map(|k| k.name())),
            opt(f.fault.map(|k| k.name())),
            f.at_s,
            opt(f.detected_s),
            opt(f.safe_after_ms),
            f.pairs_kept
        )?;
    }
    w.flush()?;
    Ok(())
}

fn campaign_json(r: &CampaignResult) -> serde_json::Value {
    let faults: Vec<_> = r
        .faults
        .iter()
        .map(|f| {
            json!({
                "run": f.run,
                "fault": f.fault.map(|k| k.name()),
                "at_s": f.at_s,
                "safe_after_ms": f.safe_after_ms,
                "pairs_kept": f.pairs_kept,
            })
        })
        .collect();
    json!({
        "runs": r.runs.len(),
        "pairs": r.rows.len(),
        "simulated_s": r.simulated_s,
        "wall_s": r.wall_s,
        "realtime_factor": r.realtime_factor(),
        "faults": faults,
    })
}

fn print_summary(out: &Path, r: &CampaignResult, raw: bool) {
    println!(
        "{} runs, {:.0} s of rig time simulated in {:.2} s on {} threads ({:.0}x real time)",
        r.runs.len(),
        r.simulated_s,
        r.wall_s,
        r.threads,
        r.realtime_factor()
    );
    println!(
        "{} pairs -> {}",
        r.rows.len(),
        out.join("pairs.csv").display()
    );
    if raw {
        println!("raw logs -> {}", out.join("raw").display());
    }
    for f in &r.faults {
        let injected = f.injected.map_or("-".into(), |k| k.name().to_string());
        let seen = f
            .fault
            .map_or("NOT DETECTED".into(), |k| k.name().to_string());
        let safe = f
            .safe_after_ms
            .map_or("never".into(), |ms| format!("{ms} ms"));
        println!(
            "run {} ({} run {}): injected {injected} at {} s, firmware: {seen}, safe after \
             {safe}, {} pairs kept",
            f.run,
            f.cord.label(),
            f.repeat,
            f.at_s,
            f.pairs_kept
        );
    }
    if !r.faults.is_empty() {
        println!("faults -> {}", out.join("faults.csv").display());
    }
}

fn run_two(args: &Args) -> anyhow::Result<()> {
    let (model, effects) = model(args)?;
    if !effects.is_empty() {
        bail!("--effect is for campaigns; the two-control rig runs the base model (--mu)");
    }
    if !args.faults.is_empty() {
        bail!("--fault is for campaigns, not --two-control");
    }
    let wraps = args.wraps.clone().unwrap_or_else(|| vec![720.0, 720.0]);
    let n = wraps.len();
    if !(1..=host_sim::plant::MAX_CORDS).contains(&n) {
        bail!(
            "--two-control: give 1 to {} wraps (one per channel), not {n}",
            host_sim::plant::MAX_CORDS
        );
    }
    let orders = args.orders.clone().unwrap_or_else(|| {
        (0..n)
            .map(|i| {
                if i % 2 == 0 {
                    Order::Monotone
                } else {
                    Order::Pulse
                }
            })
            .collect()
    });
    let delays = args
        .delays_ms
        .clone()
        .unwrap_or_else(|| (0..n as u32).map(|i| 5_000 * (i % 2)).collect());
    if orders.len() != n || delays.len() != n {
        bail!(
            "--two-control: {n} channels (--wraps) but {} --orders and {} --delays-ms",
            orders.len(),
            delays.len()
        );
    }
    let diameter = match args.diameters.as_deref() {
        None => 12.7,
        Some([d]) => *d,
        Some(_) => bail!("--two-control: one capstan, one --diameters value"),
    };
    let drive_v = match args.drive_v.as_slice() {
        [v] => *v,
        _ => bail!("--two-control: one drive motor, one --drive-v value"),
    };
    if !(diameter.is_finite() && diameter > 0.0) {
        bail!("--diameters {diameter}: must be positive");
    }
    if !(drive_v.is_finite() && (0.0..=13.2).contains(&drive_v)) {
        bail!("--drive-v {drive_v}: must be 0 to 13.2 V");
    }
    for &w in &wraps {
        if !(w.is_finite() && w > 0.0 && w <= 3600.0) {
            bail!("--wraps {w}: must be in (0, 3600]");
        }
    }
    let cfg = TwoControlConfig {
        diameter_mm: diameter,
        drive_v,
        channels: wraps
            .iter()
            .zip(&orders)
            .zip(&delays)
            .map(|((&wrap_deg, &o), &delay_ms)| ChannelSpec {
                wrap_deg,
                order: o.into(),
                delay_ms,
            })
            .collect(),
        model,
        protocol: protocol(args),
        plant: plant(args)?,
        seed: args.seed,
        sensor_noise: !args.no_noise,
        ..TwoControlConfig::default()
    };
    let r = run_two_control(&cfg).map_err(|e| anyhow::anyhow!("{e}"))?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    write_two(&args.out, &cfg, &r)?;
    let pairs: usize = r.channels.iter().map(|c| c.log.pairs.len()).sum();
    let (t2_rel, rpm_rel) = r.worst_crosstalk();
    let faults: Vec<_> = r
        .channels
        .iter()
        .enumerate()
        .filter_map(|(i, c)| {
            let f = c.log.faults.first()?;
            Some(json!({
                "channel": i + 1,
                "fault": f.kind.name(),
                "at_s": f.t_us as f64 * 1e-6,
                "pairs_kept": c.log.pairs.len(),
            }))
        })
        .collect();
    if args.json {
        println!(
            "{}",
            json!({
                "channels": n,
                "pairs": pairs,
                "simulated_s": r.simulated_s,
                "wall_s": r.wall_s,
                "realtime_factor": r.simulated_s / r.wall_s.max(1e-9),
                "peak_current_a": r.peak_current_a(),
                "peak_power_w": r.peak_power_w(),
                "mean_power_w": r.mean_power_w(),
                "crosstalk_events": r.crosstalk.len(),
                "worst_t2_crosstalk_rel": t2_rel,
                "worst_speed_crosstalk_rel": rpm_rel,
                "faults": faults,
            })
        );
    } else {
        println!(
            "{n} channels on one {diameter} mm capstan at {drive_v} V: {:.0} s simulated in {:.3} s",
            r.simulated_s, r.wall_s
        );
        println!(
            "drive: peak {:.2} A / {:.1} W (spin-up), mean {:.2} W while on",
            r.peak_current_a(),
            r.peak_power_w(),
            r.mean_power_w()
        );
        println!(
            "cross-talk over {} steps: holding channel's T2 moved at most {:.3} %, capstan \
             speed at most {:.1} %",
            r.crosstalk.len(),
            t2_rel * 100.0,
            rpm_rel * 100.0
        );
        println!(
            "-> {}, {}, pairs_ch1..{n}.csv",
            args.out.join("two_control.csv").display(),
            args.out.join("crosstalk.csv").display()
        );
    }
    Ok(())
}

fn write_two(out: &Path, cfg: &TwoControlConfig, r: &TwoControlResult) -> anyhow::Result<()> {
    let n = cfg.channels.len();
    let mut w = create(&out.join("two_control.csv"))?;
    let mut header = String::from("t_s,drive_v,capstan_rpm,current_a,power_w,load_nm,transmission");
    for k in 1..=n {
        header += &format!(",ch{k}_angle_deg,ch{k}_t1_n,ch{k}_t2_n");
    }
    writeln!(w, "{header}")?;
    for row in &r.series {
        write!(
            w,
            "{},{},{},{},{},{},{}",
            row.t_s,
            row.drive_v,
            row.capstan_rpm,
            row.current_a,
            row.power_w,
            row.load_nm,
            row.transmission
        )?;
        for c in &row.channels {
            write!(w, ",{},{},{}", c.angle_deg, c.t1_n, c.t2_n)?;
        }
        writeln!(w)?;
    }
    w.flush()?;
    let mut w = create(&out.join("crosstalk.csv"))?;
    writeln!(
        w,
        "t_s,stepping_channel,from_deg,to_deg,stepping_d_t2_n,observer_channel,\
         observer_t2_before_n,observer_t2_after_n,observer_d_t2_rel,rpm_before,rpm_after,\
         d_rpm_rel,current_before_a,current_after_a"
    )?;
    for c in &r.crosstalk {
        writeln!(
            w,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            c.t_s,
            c.stepping + 1,
            c.from_deg,
            c.to_deg,
            c.stepping_d_t2_n,
            c.observer + 1,
            c.observer_t2_before_n,
            c.observer_t2_after_n,
            c.observer_d_t2_rel(),
            c.rpm_before,
            c.rpm_after,
            c.d_rpm_rel(),
            c.current_before_a,
            c.current_after_a
        )?;
    }
    w.flush()?;
    for (k, ch) in r.channels.iter().enumerate() {
        let rows: Vec<PairRow> = ch
            .log
            .pairs
            .iter()
            .map(|p| PairRow {
                capstan_diameter_mm: cfg.diameter_mm,
                wrap_deg: cfg.channels[k].wrap_deg,
                drive_v: cfg.drive_v,
                run: 1,
                step: p.step,
                time_s: p.t_mid_ms as f64 / 1000.0,
                t1_n: format!("{}", p.t1.mean_n).parse().unwrap_or(f64::NAN),
                t2_n: format!("{}", p.t2.mean_n).parse().unwrap_or(f64::NAN),
            })
            .collect();
        write_pairs(
            &out.join(format!("pairs_ch{}.csv", k + 1)),
            &to_pairs(&rows),
        )?;
    }
    Ok(())
}
