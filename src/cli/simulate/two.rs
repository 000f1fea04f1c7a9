//! `capstan simulate --two-control`: one firmware per channel on one capstan and drive motor;
//! writes `two_control.csv` (the drive and the true tensions over time), `crosstalk.csv` and
//! each channel's `pairs_ch<k>.csv`.

use super::{model, plant, protocol, provenance_of, Args, Order};
use anyhow::bail;
use capstan_data::write_pairs_to;
use capstan_outdir::Staged;
use capstan_sim::campaign::{CordKey, PairRow};
use capstan_sim::two_control::{run_two_control, ChannelSpec, TwoControlConfig, TwoControlResult};
use capstan_validation::pairs::to_pairs;
use serde_json::json;
use std::io::Write;

pub(super) fn run_two(args: &Args) -> anyhow::Result<()> {
    let cfg = two_config(args)?;
    let n = cfg.channels.len();
    let mut names = vec!["two_control.csv".to_string(), "crosstalk.csv".to_string()];
    if !cfg.force.is_empty() {
        names.push("tracking.csv".to_string());
    }
    names.extend((1..=n).map(|k| format!("pairs_ch{k}.csv")));
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    let mut set = crate::outputs::open_out(&args.out, "two-control", &names)?.stage()?;
    let r = run_two_control(&cfg).map_err(|e| anyhow::anyhow!("{e}"))?;
    set.keep_on_failure(crate::outputs::say_kept);
    write_two(&mut set, &cfg, &r)?;
    set.commit()?;
    if args.json {
        let mut v = two_json(&r, n);
        v["provenance"] = two_provenance(&cfg);
        if !cfg.force.is_empty() {
            super::two_force::add_json(&mut v, &r);
        }
        crate::outln!("{v}");
    } else {
        say_two(args, &cfg, &r);
        if !cfg.force.is_empty() {
            super::two_force::say(&r);
        }
    }
    Ok(())
}

/// The two-control rig's configuration from the options, refusing the campaign-only ones.
fn two_config(args: &Args) -> anyhow::Result<TwoControlConfig> {
    if args.mode == super::Mode::Force {
        return force_config(args);
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
    let (model, effects) = model(args)?;
    if args.order.is_some() {
        bail!(
            "--order is for campaigns; --two-control takes one order per channel: use \
             --orders (e.g. --orders updown,pulse; default monotone,pulse)"
        );
    }
    if !effects.is_empty() {
        bail!("--effect is for campaigns; the two-control rig runs the base model (--mu)");
    }
    for (flag, given) in [
        ("--fault", !args.faults.is_empty()),
        ("--scatter", args.scatter.is_some()),
        ("--run-scatter", args.run_scatter.is_some()),
        ("--unmodelled", !args.unmodelled.is_empty()),
        ("--noise", args.noise != "quiet"),
        ("--runs", args.runs.is_some()),
    ] {
        if given {
            bail!("{flag} is for campaigns, not --two-control");
        }
    }
    let channels = two_channels(args)?;
    let diameter_mm = match args.diameters.as_deref() {
        None => 12.7,
        Some([d]) => *d,
        Some(_) => bail!("--two-control: one capstan, one --diameters value"),
    };
    let drive_v = match args.drive_v.as_slice() {
        [v] => *v,
        _ => bail!("--two-control: one drive motor, one --drive-v value"),
    };
    let cfg = TwoControlConfig {
        diameter_mm,
        drive_v,
        channels,
        model,
        protocol: protocol(args),
        plant: plant(args)?,
        seed: args.seed,
        sensor_noise: !args.no_noise,
        ..TwoControlConfig::default()
    };
    // The same ranges as a campaign's (diameter, wraps, drive voltage).
    cfg.validate().map_err(|e| anyhow::anyhow!("{e}"))?;
    Ok(cfg)
}

/// `--two-control --mode force`: one force-controlled channel per `--wraps` value (default
/// two 720° cords) on one drive, as `capstan_sim::force::channels` makes them (odd channels step
/// through 5, 10, 20 and 30 N, even ones hold 15 N from 5 s later; `--delays-ms` overrides),
/// the thesis fit's cords with `--noise` (default quiet; thesis for the rig's scatter).
fn force_config(args: &Args) -> anyhow::Result<TwoControlConfig> {
    for (flag, given) in [
        ("--order", args.order.is_some()),
        ("--orders", args.orders.is_some()),
        ("--effect", !args.effects.is_empty()),
        ("--fault", !args.faults.is_empty()),
        ("--scatter", args.scatter.is_some()),
        ("--run-scatter", args.run_scatter.is_some()),
        ("--unmodelled", !args.unmodelled.is_empty()),
        ("--runs", args.runs.is_some()),
        ("--profile", args.profile.is_some()),
        ("--levels-n", args.levels_n.is_some()),
        ("--sine-hz", args.sine_hz.is_some()),
        ("--model-from", args.model_from.is_some()),
        ("--compare", args.compare),
        ("--ee-mu", args.ee_mu.is_some()),
    ] {
        if given {
            bail!("{flag} is not for --two-control --mode force (its channels: odd ones step through 5, 10, 20 and 30 N, even ones hold 15 N)");
        }
    }
    if args.mu != 0.115 {
        bail!("--mu is not for --mode force: its cords are the thesis fit's (--cord-mu-factor scales their mu)");
    }
    let wraps = args.wraps.clone().unwrap_or_else(|| vec![720.0, 720.0]);
    let n = wraps.len();
    if !(1..=capstan_sim::plant::MAX_CORDS).contains(&n) {
        bail!(
            "--two-control: give 1 to {} wraps (one per channel), not {n}",
            capstan_sim::plant::MAX_CORDS
        );
    }
    let mut cfg = capstan_sim::force::channels(n);
    for (ch, w) in cfg.channels.iter_mut().zip(&wraps) {
        ch.wrap_deg = *w;
    }
    if let Some(d) = &args.delays_ms {
        if d.len() != n {
            bail!(
                "--two-control: {n} channels (--wraps) but {} --delays-ms",
                d.len()
            );
        }
        for (ch, d) in cfg.channels.iter_mut().zip(d) {
            ch.delay_ms = *d;
        }
    }
    let noise: capstan_sim::noise::NoiseProfile = args
        .noise
        .parse()
        .map_err(|e| anyhow::anyhow!("--noise {e}"))?;
    cfg.plant.disturbances = noise.disturbances();
    if let Some(r) = args.motor_ohm {
        cfg.plant.motor.resistance_ohm = r;
    }
    if let Some(f) = args.cord_mu_factor {
        if !(0.5..=2.0).contains(&f) {
            bail!("--cord-mu-factor {f}: must be 0.5 to 2 (a cord's mu over the model's)");
        }
        cfg.model.law.mu *= f;
    }
    if args.no_heating {
        cfg.model.law.heat_per_ns = 0.0;
    }
    for f in cfg.force.iter_mut() {
        if let Some(kp) = args.kp {
            f.kp = kp as f32;
        }
        if let Some(ki) = args.ki {
            f.ki = ki as f32;
        }
        *f = capstan_sim::force::feedback(*f, !args.open_loop);
    }
    match args.diameters.as_deref() {
        None => {}
        Some([d]) => cfg.diameter_mm = *d,
        Some(_) => bail!("--two-control: one capstan, one --diameters value"),
    }
    match args.drive_v.as_slice() {
        [v] => cfg.drive_v = *v,
        _ => bail!("--two-control: one drive motor, one --drive-v value"),
    }
    cfg.protocol = protocol(args);
    cfg.seed = args.seed;
    cfg.sensor_noise = !args.no_noise;
    cfg.validate().map_err(|e| anyhow::anyhow!("{e}"))?;
    Ok(cfg)
}

/// One channel per `--wraps` value, with its order and start delay (alternating monotone and
/// pulse, 0 and 5 s, unless given).
fn two_channels(args: &Args) -> anyhow::Result<Vec<ChannelSpec>> {
    let wraps = args.wraps.clone().unwrap_or_else(|| vec![720.0, 720.0]);
    let n = wraps.len();
    if !(1..=capstan_sim::plant::MAX_CORDS).contains(&n) {
        bail!(
            "--two-control: give 1 to {} wraps (one per channel), not {n}",
            capstan_sim::plant::MAX_CORDS
        );
    }
    let alternate = |i: usize| {
        if i.is_multiple_of(2) {
            Order::Monotone
        } else {
            Order::Pulse
        }
    };
    let orders = (args.orders.clone()).unwrap_or_else(|| (0..n).map(alternate).collect());
    let delays = (args.delays_ms.clone())
        .unwrap_or_else(|| (0..n as u32).map(|i| 5_000 * (i % 2)).collect());
    if orders.len() != n || delays.len() != n {
        bail!(
            "--two-control: {n} channels (--wraps) but {} --orders and {} --delays-ms",
            orders.len(),
            delays.len()
        );
    }
    Ok((wraps.iter().zip(&orders).zip(&delays))
        .map(|((&wrap_deg, &o), &delay_ms)| ChannelSpec {
            wrap_deg,
            order: o.into(),
            delay_ms,
        })
        .collect())
}

/// The run's figures for `--json`.
fn two_json(r: &TwoControlResult, n: usize) -> serde_json::Value {
    let pairs: usize = r.channels.iter().map(|c| c.log.pairs.len()).sum();
    let (t2_rel, rpm_rel) = r.worst_crosstalk();
    let faults: Vec<_> = (r.channels.iter().enumerate())
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
    let d = &r.drive;
    json!({
        "channels": n,
        "pairs": pairs,
        "simulated_s": r.simulated_s,
        "wall_s": r.wall_s,
        "realtime_factor": r.simulated_s / r.wall_s.max(1e-9),
        // The drive from the plant every 1 ms: the peak is a spin-up's inrush; the running
        // peak leaves out the first 0.3 s after the drive came on.
        "peak_current_a": d.peak_current_a,
        "peak_power_w": d.peak_power_w,
        "running_peak_current_a": d.running_current_a,
        "running_peak_power_w": d.running_power_w,
        "mean_power_w": d.mean_power_w,
        "crosstalk_events": r.crosstalk.len(),
        "worst_t2_crosstalk_rel": t2_rel,
        "worst_speed_crosstalk_rel": rpm_rel,
        "faults": faults,
    })
}

/// What made this run (as a campaign's `summary.json` says it): program, commit, command line,
/// seed, mu, effects (none: the two-control rig runs the base model), noise (sensor noise
/// only), and the rig: capstan, drive, motor and each channel's wrap, order and delay.
fn two_provenance(cfg: &TwoControlConfig) -> serde_json::Value {
    let mut p = provenance_of(
        cfg.seed,
        &cfg.model,
        &[],
        json!({
            "profile": "quiet",
            "sensor_noise": cfg.sensor_noise,
            "cord_scatter_pct": 0.0,
            "run_scatter_pct": 0.0,
        }),
    );
    p["rig"] = json!({
        "diameter_mm": cfg.diameter_mm,
        "drive_v": cfg.drive_v,
        "motor_ohm": cfg.plant.motor.resistance_ohm,
        "channels": cfg.channels.iter().map(|c| json!({
            "wrap_deg": c.wrap_deg,
            "order": c.order.name(),
            "delay_ms": c.delay_ms,
        })).collect::<Vec<_>>(),
    });
    p
}

/// The run in words.
fn say_two(args: &Args, cfg: &TwoControlConfig, r: &TwoControlResult) {
    let n = cfg.channels.len();
    let (t2_rel, rpm_rel) = r.worst_crosstalk();
    crate::outln!(
        "{n} channels on one {} mm capstan at {} V: {:.0} s simulated in {:.3} s",
        cfg.diameter_mm,
        cfg.drive_v,
        r.simulated_s,
        r.wall_s
    );
    let d = &r.drive;
    crate::outln!(
        "drive (1 ms): peak {:.2} A / {:.1} W (the spin-up's inrush), running at most {:.2} A / \
         {:.2} W, mean {:.2} W while on",
        d.peak_current_a,
        d.peak_power_w,
        d.running_current_a,
        d.running_power_w,
        d.mean_power_w
    );
    if cfg.force.is_empty() {
        crate::outln!(
            "cross-talk over {} steps: holding channel's T2 moved at most {:.3} %, capstan \
             speed at most {:.1} %",
            r.crosstalk.len(),
            t2_rel * 100.0,
            rpm_rel * 100.0
        );
    }
    crate::outln!(
        "-> {}, {}, pairs_ch1..{n}.csv",
        args.out.join("two_control.csv").display(),
        args.out.join("crosstalk.csv").display()
    );
}

fn write_two(set: &mut Staged, cfg: &TwoControlConfig, r: &TwoControlResult) -> anyhow::Result<()> {
    let n = cfg.channels.len();
    let mut w = set.create("two_control.csv")?;
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
    if !cfg.force.is_empty() {
        return super::two_force::write(set, cfg, r);
    }
    let mut w = set.create("crosstalk.csv")?;
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
        let cord = CordKey {
            diameter_mm: cfg.diameter_mm,
            wrap_deg: cfg.channels[k].wrap_deg,
            drive_v: cfg.drive_v,
        };
        let rows: Vec<PairRow> = ch
            .log
            .pairs
            .iter()
            .map(|p| PairRow::new(cord, 1, p))
            .collect();
        let mut w = set.create(&format!("pairs_ch{}.csv", k + 1))?;
        write_pairs_to(&mut w, &to_pairs(&rows))?;
        w.flush()?;
    }
    Ok(())
}
