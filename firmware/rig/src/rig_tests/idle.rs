//! The idle rig between runs: a fault stays latched until a press acknowledges it, and a
//! servo command away from rest (setup mode left, a new rest angle) is brought there slowly.

use super::*;

/// Step an idle rig from `t0` for `ms` samples with the button held during `press` (µs,
/// absolute); returns the outputs.
fn idle_steps(rig: &mut Rig, t0: u64, ms: u64, press: (u64, u64)) -> Vec<(u64, Outputs)> {
    let mut sink = VecSink::default();
    (0..ms)
        .map(|k| {
            let t = t0 + k * 1_000;
            let out = rig.step(
                &Inputs {
                    now_us: t,
                    counts: [Ok(407), Ok(407)],
                    button_pressed: (press.0..press.1).contains(&t),
                    command: None,
                },
                &mut sink,
            );
            (t, out)
        })
        .collect()
}

#[test]
fn a_fault_is_latched_until_a_press_acknowledges_it() {
    let cal = Calibration::default();
    let at = PRESS_US + 45_200_000;
    let mut rig = thesis_rig();
    let tr = drive(
        &mut rig,
        &move |t, o| {
            let mut c = plant_counts(o, &cal, 0.0);
            if t >= at {
                c[1] = Ok(cal.t2.counts(48.0) as u16);
            }
            (c, false)
        },
        None,
    );
    let (t_end, end) = tr.end.unwrap();
    assert_eq!(end.fault, Some(FaultKind::OverForce));
    assert_eq!(rig.latched_fault(), Some(FaultKind::OverForce));
    // Fast blink (100 ms) while latched.
    let t0 = t_end + 1_000;
    let out = idle_steps(&mut rig, t0, 400, (u64::MAX, u64::MAX));
    let toggles = out.windows(2).filter(|w| w[0].1.led != w[1].1.led).count();
    assert!((3..=4).contains(&toggles), "{toggles}");
    // First press: acknowledged, no run; the servo stays at rest, the amplifier off.
    let t1 = t0 + 400_000;
    let out = idle_steps(&mut rig, t1, 300, (t1 + 50_000, t1 + 150_000));
    assert!(!rig.is_running());
    assert_eq!(rig.latched_fault(), None);
    assert!(out
        .iter()
        .all(|(_, o)| o.servo_deg == 125.0 && o.amp_control_v == 0.0 && !o.trigger));
    // Slow blink (500 ms) once acknowledged.
    let t2 = t1 + 300_000;
    let out = idle_steps(&mut rig, t2, 1_200, (u64::MAX, u64::MAX));
    let toggles = out.windows(2).filter(|w| w[0].1.led != w[1].1.led).count();
    assert!((2..=3).contains(&toggles), "{toggles}");
    // Second press: the next run starts.
    let t3 = t2 + 1_200_000;
    idle_steps(&mut rig, t3, 100, (t3 + 10_000, t3 + 60_000));
    assert!(rig.is_running());
}

#[test]
fn after_a_clean_run_one_press_starts_the_next() {
    let mut rig = thesis_rig();
    let cal = Calibration::default();
    let tr = drive(
        &mut rig,
        &move |_, o| (plant_counts(o, &cal, 0.0), false),
        None,
    );
    let (t_end, _) = tr.end.unwrap();
    assert_eq!(rig.latched_fault(), None);
    let t0 = t_end + 1_000;
    idle_steps(&mut rig, t0, 100, (t0 + 10_000, t0 + 60_000));
    assert!(rig.is_running());
}

#[test]
fn homing_brings_the_servo_to_rest_slowly() {
    let mut rig = thesis_rig();
    // Setup mode left the servo at the last level (65°).
    rig.home_from(65.0);
    assert!(rig.is_homing());
    assert_eq!(rig.idle_outputs().servo_deg, 65.0);
    assert_eq!(rig.idle_outputs().amp_control_v, 0.0);
    // A press during homing is not a run.
    let out = idle_steps(&mut rig, 0, 7_000, (1_000_000, 1_100_000));
    assert!(!rig.is_running());
    let max_step = out
        .windows(2)
        .map(|w| (w[1].1.servo_deg - w[0].1.servo_deg).abs())
        .fold(0.0f32, f32::max);
    assert!(max_step <= 10.0 / 1000.0 + 1e-4, "{max_step}");
    // 60° at 10°/s: at rest after 6 s, and not before 5.9 s.
    let at_rest = out.iter().find(|(_, o)| o.servo_deg == 125.0).unwrap().0;
    assert!((5_900_000..=6_001_000).contains(&at_rest), "{at_rest}");
    assert!(out
        .iter()
        .all(|(_, o)| o.amp_control_v == 0.0 && !o.trigger));
    assert!(!rig.is_homing());
    // Now a press starts a run.
    idle_steps(&mut rig, 7_000_000, 100, (7_010_000, 7_060_000));
    assert!(rig.is_running());
    // Without `home_from` the rig assumes rest: nothing to do; nor when the servo was at
    // rest, read back from its duty.
    assert!(!thesis_rig().is_homing());
    let mut rig = thesis_rig();
    let map = rig.calibration().servo;
    rig.home_from(map.angle_for_duty(map.duty(125.0, 62_499), 62_499));
    assert!(!rig.is_homing());
}
