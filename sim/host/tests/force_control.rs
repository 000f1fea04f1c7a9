//! Force control on the simulated thesis rig (issue 43): the firmware in force mode holds T2 at
//! its target through the same run, supervisor and safe state as a protocol run.

use capstan_plant::{Injection, InjectionKind};
use capstan_rig::hal::Channel;
use capstan_rig::{FaultKind, ForceProfile};
use capstan_sim::force::{compare, run_force, trace_of, Controller, CordCase, ForceRig};
use capstan_tracking::{bandwidth, bode, steps, Bandwidth, SteadyWindow};

const MS: u64 = 1_000;

fn cords() -> [CordCase; 3] {
    [1.0, 1.2, 0.8].map(|mu_factor| CordCase {
        mu_factor,
        heating: true,
    })
}

/// The test: steps of 5, 10, 20 and 30 N at 720° on the 12.7 mm capstan, with the
/// thesis rig's noise and the contact heating fitted to its data. With feedback every step ends
/// within 3 % of its target and overshoots by at most 15 %, on the model's own cord and on
/// cords whose mu is 20 % off it; open loop the fitted law misses on those cords.
#[test]
fn feedback_holds_every_step_on_the_models_cord_and_on_cords_20_percent_off() {
    for seed in [1, 2] {
        let base = ForceRig {
            seed,
            ..ForceRig::default()
        };
        let c = compare(
            &base,
            &[Controller::OpenLoopFitted, Controller::Feedback],
            &cords(),
        )
        .unwrap();
        for row in &c.rows {
            assert!(row.clean, "{} / {}", row.controller.name(), row.cord.name());
            let targets: Vec<f64> = row.steps.iter().map(|s| s.target_n).collect();
            assert_eq!(targets, [5.0, 10.0, 20.0, 30.0]);
            let (ss, os) = (row.worst_ss_error_pct(), row.worst_overshoot_pct());
            eprintln!(
                "seed {seed}: {:32} {:18} worst |ss| {ss:5.2} %, overshoot {os:5.2} %",
                row.controller.name(),
                row.cord.name()
            );
            match (row.controller, row.cord.mu_factor == 1.0) {
                (Controller::Feedback, _) => {
                    assert!(ss <= 3.0, "{seed} {}: {ss}", row.cord.name());
                    assert!(os <= 15.0, "{seed} {}: {os}", row.cord.name());
                    for s in &row.steps {
                        assert!(s.rise_s.is_some_and(|r| r < 1.5), "{s:?}");
                        assert!(s.settling_s.is_some_and(|r| r < 3.0), "{s:?}");
                    }
                }
                // Open loop on a cord 20 % off: T2 off by exp(±0.2 mu β) less the heating's
                // relief: far beyond 3 %.
                (_, false) => assert!(ss > 10.0, "{seed} {}: {ss}", row.cord.name()),
                (_, true) => {}
            }
        }
    }
}

#[test]
fn every_run_record_carries_the_target() {
    let out = run_force(&ForceRig::default()).unwrap();
    let log = &out.log;
    assert_eq!(log.pairs.len(), 4);
    let targets: Vec<f32> = log.pairs.iter().map(|p| p.t2_target_n).collect();
    assert_eq!(targets, [5.0, 10.0, 20.0, 30.0]);
    // The pair's mean T2 is its target (feedback), its angle the servo's command then.
    for p in &log.pairs {
        assert!((p.t2.mean_n / p.t2_target_n - 1.0).abs() < 0.03, "{p:?}");
        assert!(p.angle_deg < 120.0 && p.angle_deg >= 65.0, "{p:?}");
    }
    // Raw records: no target before the first segment, the level's after it.
    let start = log.start.unwrap();
    let first_us = (start.protocol.step_start_ms(1) - start.protocol.trigger_at_ms()) as i64 * 1000;
    for r in &log.raw {
        let want = if r.t_us < first_us { 0.0 } else { 5.0 };
        if r.t_us < first_us + 10_000_000 {
            assert_eq!(r.t2_target_n, want, "{r:?}");
        }
    }
    assert_eq!(start.protocol.force.mode, capstan_rig::ControlMode::Force);
}

/// A fault during force control stops the drive as in a protocol run: the same fault, the same
/// safe state (servo commanded to rest, amplifier 0 V) within 20 ms, the pairs before it kept.
/// On the quiet plant, as the protocol's fault tests (`sim_firmware.rs`) run: with the thesis
/// rig's zero errors (SD 0.1 N after the tare) a parted cord can read above the supervisor's
/// 0.05 N slack threshold, in protocol runs as in force runs (issue 38's slack detection).
#[test]
fn a_fault_during_force_control_stops_the_drive_as_in_a_protocol_run() {
    // 35.2 s after the trigger: in the third segment (20 N, from 30.5 s), two pairs made.
    let cases = [
        (InjectionKind::OverForce, FaultKind::OverForce),
        (InjectionKind::CordBreak, FaultKind::CordBreak),
        (
            InjectionKind::SensorUnplugged(Channel::T2),
            FaultKind::SensorRail,
        ),
        (
            InjectionKind::SensorUnplugged(Channel::T1),
            FaultKind::SensorRail,
        ),
        (InjectionKind::Abort, FaultKind::Abort),
    ];
    let quiet = ForceRig {
        noise: capstan_sim::noise::NoiseProfile::Quiet,
        ..ForceRig::default()
    };
    let clean = run_force(&quiet).unwrap();
    for (kind, want) in cases {
        let rig = ForceRig {
            injections: vec![Injection {
                kind,
                cord: 0,
                after_trigger_us: 35_200 * MS,
            }],
            ..quiet.clone()
        };
        let out = run_force(&rig).unwrap();
        let end = out.end.unwrap();
        assert_eq!(end.fault, Some(want), "{kind:?}");
        assert_eq!(out.log.faults.len(), 1);
        let safe_ms = out.injections[0].safe_after_us().expect("made safe") as f64 / 1000.0;
        assert!(safe_ms <= 20.0, "{kind:?}: safe after {safe_ms} ms");
        assert_eq!(out.safe_since_us, out.injections[0].safe_at_us);
        assert_eq!(end.pairs, 2);
        assert_eq!(out.log.pairs[..], clean.log.pairs[..2]);
        eprintln!("force mode, {}: safe after {safe_ms} ms", kind.name());
    }
}

/// A snag that pulls T2 over the limit is not fought by the controller: the supervisor stops
/// the run on its third sample over 45 N, as in a protocol run.
#[test]
fn an_over_force_is_caught_in_three_samples_whatever_the_controller_does() {
    let rig = ForceRig {
        injections: vec![Injection {
            kind: InjectionKind::OverForce,
            cord: 0,
            after_trigger_us: 35_000 * MS,
        }],
        ..ForceRig::default()
    };
    let out = run_force(&rig).unwrap();
    let f = out.log.faults[0];
    assert_eq!(f.kind, FaultKind::OverForce);
    // The snag's 50 N as the T2 sensor reads it (the run's zero error and noise).
    assert!((f.value - 50.0).abs() < 1.5, "{f:?}");
    let detected_after_us = f.t_us - 35_000_000;
    assert!(
        (2_000..=4_000).contains(&detected_after_us),
        "{detected_after_us}"
    );
}

/// A stepped sine sweep about 15 N: the closed loop follows slow sines at unit gain and its
/// −3 dB bandwidth lies inside the sweep.
#[test]
fn a_sine_sweep_gives_the_closed_loops_bandwidth() {
    let mut rig = ForceRig::default();
    rig.force.profile = ForceProfile::Sine;
    rig.force.levels_n = [15.0, 5.0, 0.0, 0.0];
    rig.force.sine_hz = 0.3;
    rig.force.sine_to_hz = 20.0;
    rig.force.sine_steps = 10;
    let out = run_force(&rig).unwrap();
    assert!(out.log.end.is_some_and(|e| e.fault.is_none()));
    let points = bode(&trace_of(&out.log));
    assert_eq!(points.len(), 10, "{points:?}");
    for p in &points {
        eprintln!(
            "{:5.2} Hz: gain {:6.3} ({:+6.2} dB), phase {:7.1}°, residual {:4.1} %",
            p.freq_hz, p.gain, p.gain_db, p.phase_deg, p.residual_pct
        );
    }
    assert!((points[0].gain - 1.0).abs() < 0.05, "{:?}", points[0]);
    match bandwidth(&points) {
        Bandwidth::Within { freq_hz, phase_deg } => {
            eprintln!("-3 dB at {freq_hz:.2} Hz, phase {phase_deg:.0}°");
            assert!(freq_hz > 3.0 && freq_hz < 20.0);
            assert!(phase_deg < -45.0 && phase_deg > -180.0);
        }
        b => panic!("{b:?}"),
    }
}

/// A ramp from 5 to 25 N over a dwell: followed with a lag, and held at both ends.
#[test]
fn a_ramp_is_followed_and_its_ends_held() {
    let mut rig = ForceRig::default();
    rig.force.profile = ForceProfile::Ramp;
    rig.force.levels_n = [5.0, 25.0, 0.0, 0.0];
    let out = run_force(&rig).unwrap();
    let p = &out.log.pairs;
    assert_eq!(p.len(), 3);
    assert!((p[0].t2.mean_n / 5.0 - 1.0).abs() < 0.03);
    assert!((p[2].t2.mean_n / 25.0 - 1.0).abs() < 0.03);
    // Mid-ramp (2 N/s) the window's mean is its target, give or take the lag.
    assert!(
        (p[1].t2.mean_n - p[1].t2_target_n).abs() < 1.0,
        "{:?}",
        p[1]
    );
    let s = steps(&trace_of(&out.log), SteadyWindow::default());
    assert_eq!(
        s.len(),
        1,
        "the ramp is no step: only the first level is: {s:?}"
    );
}
