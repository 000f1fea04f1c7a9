//! Tuning aid (not a test): steps on the thesis rig, open loop and feedback, on three cords.
use capstan_sim::force::{compare, Controller, CordCase, ForceRig};

fn main() {
    let mut base = ForceRig::default();
    if let Ok(seed) = std::env::var("SEED") {
        base.seed = seed.parse().unwrap();
    }
    if let Ok(s) = std::env::var("SERVO_S") {
        base.plant.servo.no_load_deg_per_s = 60.0 / s.parse::<f64>().unwrap();
    }
    if std::env::var("QUIET").is_ok() {
        base.noise = capstan_sim::noise::NoiseProfile::Quiet;
    }
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .map(|a| a.parse().unwrap())
        .collect();
    if let [kp, ki, g, shape, rate] = args[..] {
        base.force.kp = kp as f32;
        base.force.ki = ki as f32;
        base.force.t1_gain = g as f32;
        base.force.shape_ms = shape as u32;
        base.force.rate_deg_s = rate as f32;
    }
    let cords = [
        CordCase {
            mu_factor: 1.0,
            heating: true,
        },
        CordCase {
            mu_factor: 1.2,
            heating: true,
        },
        CordCase {
            mu_factor: 0.8,
            heating: true,
        },
    ];
    let c = compare(
        &base,
        &[Controller::OpenLoopFitted, Controller::Feedback],
        &cords,
    )
    .unwrap();
    let verbose = std::env::var("V").is_ok();
    for r in &c.rows {
        let rise: Vec<String> = r
            .steps
            .iter()
            .map(|s| format!("{:.2}", s.rise_s.unwrap_or(f64::NAN)))
            .collect();
        let os: Vec<String> = r
            .steps
            .iter()
            .map(|s| format!("{:.1}", s.overshoot_pct))
            .collect();
        let settle: Vec<String> = r
            .steps
            .iter()
            .map(|s| format!("{:.2}", s.settling_s.unwrap_or(f64::NAN)))
            .collect();
        println!(
            "{:38} {:20} ss {:5.2}% os [{}] rise [{}] settle [{}] clean {}",
            r.controller.name(),
            r.cord.name(),
            r.worst_ss_error_pct(),
            os.join(" "),
            rise.join(" "),
            settle.join(" "),
            r.clean
        );
        if !verbose {
            continue;
        }
        for s in &r.steps {
            println!(
                "  {:5.1}->{:5.1} ss {:+6.2} % os {:6.2} % rise {:?} settle {:?} sd {:.3}",
                s.from_target_n,
                s.target_n,
                s.ss_error_pct,
                s.overshoot_pct,
                s.rise_s.map(|x| (x * 1000.0).round() / 1000.0),
                s.settling_s.map(|x| (x * 1000.0).round() / 1000.0),
                s.steady_sd_n
            );
        }
    }
}
