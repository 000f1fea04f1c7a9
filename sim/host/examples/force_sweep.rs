//! Tuning aid (not a test): a stepped sine sweep on the thesis rig.
use capstan_sim::force::{run_force, trace_of, ForceRig};
use capstan_tracking::{bandwidth, bode};

fn main() {
    let a: Vec<f64> = std::env::args()
        .skip(1)
        .map(|a| a.parse().unwrap())
        .collect();
    let mut rig = ForceRig::default();
    rig.force.profile = capstan_rig::ForceProfile::Sine;
    rig.force.levels_n = [a[0] as f32, a[1] as f32, 0.0, 0.0];
    rig.force.sine_hz = a[2] as f32;
    rig.force.sine_to_hz = a[3] as f32;
    rig.force.sine_steps = a[4] as u32;
    if a.len() > 5 {
        rig.cord.law.heat_per_ns *= a[5];
        rig.force.law.heat_per_n *= a[5] as f32;
    }
    let out = run_force(&rig).unwrap();
    println!("end {:?}", out.log.end);
    let p = bode(&trace_of(&out.log));
    for p in &p {
        println!(
            "{:5.2} Hz: gain {:6.3} ({:+6.2} dB), phase {:7.1}, residual {:4.1} %",
            p.freq_hz, p.gain, p.gain_db, p.phase_deg, p.residual_pct
        );
    }
    println!("{:?}", bandwidth(&p));
}
