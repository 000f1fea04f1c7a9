//! `capstan simulate --mode force`: the firmware in force mode (T2 held to a target) on the
//! simulated thesis rig, its servo's dead band on; the board's feedforward goes through the
//! fitted law (`--model-from metrics.json`, default the thesis fit), the cord is that law's
//! (`--cord-mu-factor` for a new cord). Writes `pairs.csv` and `raw/<cord>_run<k>.csv`, both
//! with `t2_target_n`, `faults.csv` and `summary.json`, and says how each run tracked its
//! target. `--compare`: open loop (Euler-Eytelwein with one mu; the fitted law) against the
//! fitted law with feedback, on the model's cord and on cords whose mu is off, into
//! `compare.csv`.

use super::{checks, provenance_of, Args, Mode};
use anyhow::{bail, Context};
use capstan_outdir::{OutputDir, Staged};
use capstan_rig::{BoardLaw, ForceConfig, ForceProfile};
use capstan_sim::force::{self as hf, ForceRig};
use capstan_sim::noise::NoiseProfile;
use capstan_sim::plant::{rng::derive_seed, Injection};
use capstan_tracking::{bandwidth, bode, steps, Bandwidth, SteadyWindow, StepResponse};
use serde_json::json;
use std::io::Write;

/// The one-mu Euler-Eytelwein fit of the bundled thesis data (`capstan analyze`'s baseline
/// model), for the open-loop row when no `--model-from` gives one.
const THESIS_EE_MU: f64 = hf::THESIS_EE_MU;

/// Force mode as the options describe it.
struct ForceRun {
    rig: ForceRig,
    /// The force settings of each profile given (run k uses the ((k − 1) mod n)-th).
    profiles: Vec<ForceConfig>,
    runs: u32,
    ee_mu: f64,
    model: String,
}

pub(super) fn run_force(args: &Args) -> anyhow::Result<()> {
    debug_assert_eq!(args.mode, Mode::Force);
    let f = force_run(args)?;
    if args.compare {
        return compare(args, &f);
    }
    let label = capstan_sim::campaign::CordKey {
        diameter_mm: f.rig.diameter_mm,
        wrap_deg: f.rig.wrap_deg,
        drive_v: f.rig.drive_v,
    }
    .label();
    let raw_name = |k: u32| format!("raw/{label}_run{k}.csv");
    let writes = |rel: &str| !args.no_raw && (1..=f.runs).any(|k| raw_name(k) == rel);
    let out = OutputDir::open_with(
        &args.out,
        "simulate",
        &["pairs.csv", "faults.csv", "summary.json"],
        &[("raw", &writes)],
    )?;
    crate::outputs::say_recovered(&out);
    let mut set = out.stage()?;
    let mut pairs = set.create("pairs.csv")?;
    writeln!(
        pairs,
        "capstan_diameter_mm,wrap_deg,drive_v,run,step,time_s,t1_n,t2_n,t2_target_n"
    )?;
    let mut faults = set.create("faults.csv")?;
    writeln!(faults, "run,fault,at_s,channel,value")?;
    let window = window(&f.rig);
    let mut runs_json = Vec::new();
    for k in 1..=f.runs {
        let rig = run_rig(args, &f, k)?;
        let out = hf::run_force(&rig).map_err(|e| anyhow::anyhow!("{e}"))?;
        set.keep_on_failure(crate::outputs::say_kept);
        for p in &out.log.pairs {
            writeln!(
                pairs,
                "{},{},{},{k},{},{},{},{},{}",
                f.rig.diameter_mm,
                f.rig.wrap_deg,
                f.rig.drive_v,
                p.step,
                p.t_mid_ms as f64 / 1000.0,
                p.t1.mean_n,
                p.t2.mean_n,
                p.t2_target_n
            )?;
        }
        for x in &out.log.faults {
            let ch = x.channel.map_or("", |c| c.name());
            let at = x.t_us as f64 * 1e-6;
            writeln!(faults, "{k},{},{at},{ch},{}", x.kind.name(), x.value)?;
        }
        if !args.no_raw {
            set.write(&raw_name(k), raw_csv(&out.log).as_bytes())?;
        }
        let trace = hf::trace_of(&out.log);
        let st = steps(&trace, window);
        let bd = bode(&trace);
        if !args.json {
            say_run(k, &st, &bd, out.log.faults.first().map(|x| x.kind.name()));
        }
        runs_json.push(json!({
            "run": k,
            "cord_mu": rig.cord.law.mu,
            "pairs": out.log.pairs.len(),
            "fault": out.log.faults.first().map(|x| x.kind.name()),
            "steps": st,
            "bode": bd,
            "bandwidth": bandwidth(&bd),
        }));
    }
    pairs.flush()?;
    faults.flush()?;
    drop((pairs, faults));
    let summary = json!({
        "mode": "force",
        "runs": runs_json,
        "rig": rig_json(&f),
        "provenance": provenance(args, &f),
    });
    write_summary(&mut set, &summary)?;
    set.commit()?;
    if args.json {
        crate::outln!("{summary}");
    } else {
        crate::outln!(
            "-> {} (with t2_target_n), {}{}; capstan analyze {} reports the tracking",
            args.out.join("pairs.csv").display(),
            args.out.join("summary.json").display(),
            if args.no_raw { "" } else { ", raw/" },
            args.out.join("pairs.csv").display()
        );
    }
    Ok(())
}

/// The steady window: the protocol's conditioning window.
fn window(rig: &ForceRig) -> SteadyWindow {
    SteadyWindow {
        after_s: rig.protocol.window_after_change_ms as f64 * 1e-3,
        before_s: rig.protocol.window_before_next_ms as f64 * 1e-3,
    }
}

fn write_summary(set: &mut Staged, summary: &serde_json::Value) -> anyhow::Result<()> {
    let text = serde_json::to_string_pretty(summary)? + "\n";
    Ok(set.write("summary.json", text.as_bytes())?)
}

/// Run `k`'s rig: its own seed, and the faults given for it.
fn run_rig(args: &Args, f: &ForceRun, k: u32) -> anyhow::Result<ForceRig> {
    let mut rig = f.rig.clone();
    rig.seed = derive_seed(args.seed, &[u64::from(k)]);
    // `--scatter PCT`: each run a new cord, its mu drawn with the given cord-to-cord SD (the
    // thesis data's is 4.3 %) around the model's.
    if let Some(pct) = args.scatter {
        let mut rng =
            capstan_sim::plant::rng::Rng::new(derive_seed(args.seed, &[u64::from(k), 0x5c]));
        rig.cord.law.mu *= (pct / 100.0 * rng.normal()).exp();
    }
    let p = &f.profiles[(k as usize - 1) % f.profiles.len()];
    rig.force = ForceConfig {
        profile: p.profile,
        levels_n: p.levels_n,
        sine_hz: p.sine_hz,
        sine_to_hz: p.sine_to_hz,
        sine_steps: p.sine_steps,
        ..rig.force
    };
    for s in &args.faults {
        let spec = checks::fault(s)?;
        if spec.run.is_none_or(|r| r == k) {
            rig.injections.push(Injection {
                kind: spec.kind,
                cord: 0,
                after_trigger_us: (spec.at_s * 1e6).round() as u64,
            });
        }
    }
    Ok(rig)
}

/// The force run the options describe, refusing what does not apply to it.
fn force_run(args: &Args) -> anyhow::Result<ForceRun> {
    for (flag, given) in [
        ("--order", args.order.is_some()),
        ("--effect", !args.effects.is_empty()),
        ("--run-scatter", args.run_scatter.is_some()),
        ("--unmodelled", !args.unmodelled.is_empty()),
        ("--two-control", args.two_control),
        ("--no-noise", args.no_noise),
    ] {
        if given {
            bail!(
                "{flag} is not for --mode force (its cord is the model's: --model-from, \
                 --cord-mu-factor, --no-heating; its noise --noise quiet|thesis)"
            );
        }
    }
    if args.mu != 0.115 {
        bail!("--mu is not for --mode force: its cord is the model's (--cord-mu-factor X scales its mu)");
    }
    let one = |flag: &str, list: &Option<Vec<f64>>, default: f64| match list.as_deref() {
        None => Ok(default),
        Some([v]) => Ok(*v),
        Some(_) => bail!("--mode force runs one rig: one {flag} value"),
    };
    let diameter_mm = one("--diameters", &args.diameters, 12.7)?;
    let wrap_deg = one("--wraps", &args.wraps, 720.0)?;
    let drive_v = one("--drive-v", &Some(args.drive_v.clone()), 10.0)?;
    let wanted = args
        .profile
        .clone()
        .unwrap_or_else(|| vec![super::Profile::Steps]);
    let profiles = wanted
        .iter()
        .map(|&p| profile(args, p))
        .collect::<anyhow::Result<Vec<ForceConfig>>>()?;
    let max_target = profiles
        .iter()
        .map(|f| match f.profile {
            ForceProfile::Sine => f.levels_n[0] + f.levels_n[1],
            _ => f.levels_n.iter().copied().fold(0.0, f32::max),
        })
        .fold(0.0, f32::max);
    let mut force = profiles[0];
    let (model, law, ee_mu, name) = match &args.model_from {
        Some(path) => {
            let point = crate::cli::rig::model::RigPoint {
                wrap_deg,
                diameter_mm,
                drive_v,
                max_target_n: f64::from(max_target),
            };
            let l = crate::cli::rig::model::load(path, &point)?;
            let ee = l.euler_eytelwein_mu.unwrap_or(THESIS_EE_MU);
            (l.model, l.law, ee, path.display().to_string())
        }
        None => {
            let model = hf::thesis_fit();
            let op = capstan_physics::Operating {
                diameter_mm,
                drive_v,
                ..capstan_physics::Operating::from_wrap_deg(wrap_deg)
            };
            let law = hf::board_law(&model, &op, 12.0)?;
            (model, law, THESIS_EE_MU, "the thesis fit (built in)".into())
        }
    };
    force.law = match args.ee_mu {
        Some(mu) if mu > 0.0 && mu <= 2.0 => BoardLaw::euler_eytelwein(mu as f32),
        Some(mu) => bail!("--ee-mu {mu}: must be above 0 and at most 2"),
        None => law,
    };
    if let Some(kp) = args.kp {
        force.kp = kp as f32;
    }
    if let Some(ki) = args.ki {
        force.ki = ki as f32;
    }
    force = hf::feedback(force, !args.open_loop);
    if let Some(pct) = args.scatter {
        // (A campaign's range for the same option.)
        if !(0.0..=50.0).contains(&pct) {
            bail!("--scatter {pct}: must be 0 to 50 (%)");
        }
    }
    let factor = args.cord_mu_factor.unwrap_or(1.0);
    if !(0.5..=2.0).contains(&factor) {
        bail!("--cord-mu-factor {factor}: must be 0.5 to 2 (a cord's mu over the model's)");
    }
    let mut cord = model;
    cord.law.mu *= factor;
    if args.no_heating {
        cord.law.heat_per_ns = 0.0;
    }
    let noise: NoiseProfile = args
        .noise
        .parse()
        .map_err(|e| anyhow::anyhow!("--noise {e}"))?;
    let mut rig = ForceRig {
        wrap_deg,
        diameter_mm,
        drive_v,
        cord,
        force,
        protocol: super::protocol(args),
        noise,
        ..ForceRig::default()
    };
    if let Some(r) = args.motor_ohm {
        rig.plant.motor.resistance_ohm = r;
    }
    for p in &profiles {
        let each = ForceRig {
            force: ForceConfig {
                profile: p.profile,
                levels_n: p.levels_n,
                sine_hz: p.sine_hz,
                sine_to_hz: p.sine_to_hz,
                sine_steps: p.sine_steps,
                ..rig.force
            },
            ..rig.clone()
        };
        each.board_protocol().validate().map_err(|e| {
            anyhow::anyhow!(
                "the firmware refuses force mode's settings ({}): {e}",
                p.profile.name()
            )
        })?;
    }
    Ok(ForceRun {
        rig,
        runs: args.runs.unwrap_or(profiles.len() as u32),
        profiles,
        ee_mu,
        model: name,
    })
}

/// The target profile `p` with `--levels-n` and `--sine-hz` (each profile's defaults where
/// not given).
fn profile(args: &Args, p: super::Profile) -> anyhow::Result<ForceConfig> {
    let mut f = ForceConfig {
        profile: p.into(),
        ..ForceConfig::default()
    };
    if let Some(levels) = &args.levels_n {
        if levels.is_empty() || levels.len() > 4 {
            bail!("--levels-n: 1 to 4 values");
        }
        f.levels_n = [0.0; 4];
        for (slot, v) in f.levels_n.iter_mut().zip(levels) {
            *slot = *v as f32;
        }
    } else if f.profile == ForceProfile::Sine {
        f.levels_n = [15.0, 5.0, 0.0, 0.0];
    } else if f.profile == ForceProfile::Ramp {
        f.levels_n = [5.0, 25.0, 0.0, 0.0];
    }
    if let Some(s) = &args.sine_hz {
        let parts: Vec<f64> = s
            .split(':')
            .map(|x| x.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| anyhow::anyhow!("--sine-hz {s}: give F, F0:F1 or F0:F1:STEPS"))?;
        let (a, b, n) = match parts.as_slice() {
            [a] => (*a, *a, 1.0),
            [a, b] => (*a, *b, 8.0),
            [a, b, n] => (*a, *b, *n),
            _ => bail!("--sine-hz {s}: give F, F0:F1 or F0:F1:STEPS"),
        };
        if n.fract() != 0.0 || !(1.0..=16.0).contains(&n) {
            bail!("--sine-hz {s}: 1 to 16 steps");
        }
        (f.sine_hz, f.sine_to_hz, f.sine_steps) = (a as f32, b as f32, n as u32);
    } else if f.profile == ForceProfile::Sine {
        (f.sine_hz, f.sine_to_hz, f.sine_steps) = (0.3, 20.0, 10);
    }
    Ok(f)
}

fn raw_csv(log: &capstan_sim::run::RunLog) -> String {
    use std::fmt::Write as _;
    let mut s = String::from("t_s,t1_counts,t2_counts,t1_n,t2_n,t2_target_n\n");
    for x in &log.raw {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{}",
            x.t_us as f64 / 1e6,
            x.counts[0],
            x.counts[1],
            x.force_n[0],
            x.force_n[1],
            x.t2_target_n
        );
    }
    s
}

fn rig_json(f: &ForceRun) -> serde_json::Value {
    let (r, c) = (&f.rig, &f.rig.force);
    json!({
        "diameter_mm": r.diameter_mm,
        "wrap_deg": r.wrap_deg,
        "drive_v": r.drive_v,
        "cord": {
            "mu": r.cord.law.mu,
            "heat_per_ns": r.cord.law.heat_per_ns,
            "heat_tau_s": r.cord.law.heat_tau_s,
            "t2_offset_n": r.cord.sensors.t2_offset_n,
        },
        "model": f.model,
        "board": {
            "profile": c.profile.name(),
            "levels_n": c.levels_n,
            "sine_hz": [c.sine_hz, c.sine_to_hz],
            "sine_steps": c.sine_steps,
            "kp": c.kp, "ki": c.ki, "t1_gain": c.t1_gain,
            "rate_deg_s": c.rate_deg_s, "shape_ms": c.shape_ms,
            "law": {
                "mu": c.law.mu, "heat_per_n": c.law.heat_per_n,
                "t2_offset_n": c.law.t2_offset_n, "exponent": c.law.exponent,
            },
        },
        "servo_s_per_60deg": 60.0 / r.plant.servo.no_load_deg_per_s,
        "servo_dead_band_motion": r.plant.servo.dynamics.dead_band_motion,
        "dwell_ms": r.protocol.dwell_ms,
    })
}

fn provenance(args: &Args, f: &ForceRun) -> serde_json::Value {
    provenance_of(
        args.seed,
        &f.rig.cord,
        &[],
        json!({ "profile": args.noise, "sensor_noise": true }),
    )
}

fn opt(v: Option<f64>) -> String {
    v.map_or("-".into(), |x| format!("{x:.2}"))
}

fn say_run(k: u32, st: &[StepResponse], bd: &[capstan_tracking::BodePoint], fault: Option<&str>) {
    crate::outln!(
        "run {k}{}",
        fault.map_or(String::new(), |f| format!(": ended by {f}"))
    );
    for s in st {
        crate::outln!(
            "  step {:5.1} -> {:5.1} N: steady {:6.2} N ({:+5.2} %), overshoot {:4.1} %, rise {} s, settling {} s",
            s.from_target_n,
            s.target_n,
            s.steady_n,
            s.ss_error_pct,
            s.overshoot_pct,
            opt(s.rise_s),
            opt(s.settling_s)
        );
    }
    for p in bd {
        crate::outln!(
            "  sine {:5.2} Hz: gain {:5.3} ({:+5.2} dB), phase {:6.1}°",
            p.freq_hz,
            p.gain,
            p.gain_db,
            p.phase_deg
        );
    }
    match bandwidth(bd) {
        Bandwidth::Within { freq_hz, phase_deg } => {
            crate::outln!("  closed loop: -3 dB at {freq_hz:.2} Hz, phase {phase_deg:.0}° there")
        }
        Bandwidth::Above { freq_hz } => {
            crate::outln!("  closed loop: above -3 dB up to {freq_hz:.2} Hz (the sweep's end)")
        }
        Bandwidth::Below { freq_hz } => {
            crate::outln!("  closed loop: below -3 dB already at {freq_hz:.2} Hz")
        }
        Bandwidth::None => {}
    }
}

/// `--compare`: every controller on the model's cord, cords whose mu is off by ±PCT, and the
/// model's cord without its heating.
fn compare(args: &Args, f: &ForceRun) -> anyhow::Result<()> {
    let pct = args.compare_mu_pct;
    if !(pct > 0.0 && pct <= 50.0) {
        bail!("--compare-mu-pct {pct}: must be above 0 and at most 50");
    }
    let factor = f.rig.cord.law.mu / hf::THESIS_FIT_MU;
    if args.model_from.is_some() || (factor - 1.0).abs() > 1e-12 {
        bail!(
            "--compare runs the thesis fit's cords (the model's, mu ±{pct} %, no heating): \
             leave out --model-from and --cord-mu-factor"
        );
    }
    let mut out =
        crate::outputs::open_out(&args.out, "simulate", &["compare.csv", "summary.json"])?
            .stage()?;
    let base = ForceRig {
        seed: derive_seed(args.seed, &[1]),
        force: hf::feedback(f.rig.force, true),
        ..f.rig.clone()
    };
    let c = hf::standard(&base, f.ee_mu as f32, pct).map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut w = out.create("compare.csv")?;
    writeln!(
        w,
        "controller,cord,cord_mu_factor,heating,from_n,target_n,steady_n,ss_error_pct,overshoot_pct,rise_s,settling_s"
    )?;
    let cell = |v: Option<f64>| v.map_or(String::new(), |x| x.to_string());
    for r in &c.rows {
        for s in &r.steps {
            writeln!(
                w,
                "{},{},{},{},{},{},{},{},{},{},{}",
                capstan_data::text_cell(r.controller.name()),
                capstan_data::text_cell(&r.cord.name()),
                r.cord.mu_factor,
                r.cord.heating,
                s.from_target_n,
                s.target_n,
                s.steady_n,
                s.ss_error_pct,
                s.overshoot_pct,
                cell(s.rise_s),
                cell(s.settling_s)
            )
            .context("compare.csv")?;
        }
    }
    w.flush()?;
    drop(w);
    let rows: Vec<_> = c
        .rows
        .iter()
        .map(|r| {
            json!({
                "controller": r.controller.name(),
                "cord": r.cord.name(),
                "clean": r.clean,
                "worst_ss_error_pct": r.worst_ss_error_pct(),
                "worst_overshoot_pct": r.worst_overshoot_pct(),
                "steps": r.steps,
            })
        })
        .collect();
    let summary = json!({
        "mode": "force",
        "compare": rows,
        "euler_eytelwein_mu": f.ee_mu,
        "rig": rig_json(f),
        "provenance": provenance(args, f),
    });
    write_summary(&mut out, &summary)?;
    out.commit()?;
    if args.json {
        crate::outln!("{summary}");
        return Ok(());
    }
    crate::outln!(
        "{:36} {:30} {:>9} {:>9} {:>16} {:>16}",
        "controller",
        "cord",
        "|ss| max",
        "over max",
        "rise s (min-max)",
        "settle s (max)"
    );
    for r in &c.rows {
        let rise: Vec<f64> = r.steps.iter().filter_map(|s| s.rise_s).collect();
        let settle = r
            .steps
            .iter()
            .filter_map(|s| s.settling_s)
            .fold(0.0, f64::max);
        let (lo, hi) = rise
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
        crate::outln!(
            "{:36} {:30} {:>8.2}% {:>8.1}% {:>16} {:>16.2}",
            r.controller.name(),
            r.cord.name(),
            r.worst_ss_error_pct(),
            r.worst_overshoot_pct(),
            format!("{lo:.2}-{hi:.2}"),
            settle
        );
    }
    crate::outln!("-> {}", args.out.join("compare.csv").display());
    Ok(())
}
