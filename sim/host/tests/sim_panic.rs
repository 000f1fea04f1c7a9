//! A firmware panic mid-run: the board's panic path (`capstan_rig::force_safe` with the duties
//! computed at boot) must leave the plant's pins safe — amplifier duty 0, servo pulse at rest —
//! within 1 ms of plant time, with nothing else running (the runner's own safe-state code is
//! skipped by a panic). See `capstan_sim::panic`.

use capstan_physics::Model;
use capstan_plant::{CordSetup, THESIS_REST_PULSE_US};
use capstan_rig::ServoMap;
use capstan_sim::panic::{run_with_panic, PanicOutcome, PanicRunError, AFTER_PANIC_US};
use capstan_sim::run::RunSpec;

const MS: u64 = 1_000;

fn spec(wrap_deg: f64) -> RunSpec {
    RunSpec {
        cord: CordSetup::new(wrap_deg, Model::euler_eytelwein(0.115)),
        keep_raw: false,
        ..RunSpec::default()
    }
}

fn check_safe_within_1_ms(out: &PanicOutcome) -> u64 {
    let at = out.panic_at_us;
    // The panic struck a running rig: capstan driven, servo away from rest.
    assert!(out.before.amp_control_v > 2.0, "{:?}", out.before);
    assert!(
        (out.before.commanded_pulse_us - THESIS_REST_PULSE_US).abs() > 50.0,
        "{:?}",
        out.before
    );
    // The handler, at the same instant: amplifier duty 0, servo pulse at rest (1833 µs).
    assert_eq!(out.after.amp_control_v, 0.0, "{:?}", out.after);
    assert!(
        (out.after.commanded_pulse_us - 1_833.0).abs() <= 1.0,
        "{:?}",
        out.after
    );
    let safe_at = out
        .safe_since_us
        .expect("the pins stayed safe after the panic");
    let took_us = safe_at - at;
    assert!(took_us <= MS, "safe {took_us} µs after the panic");
    // Nothing undid it, and the plant followed: the horn back at rest within a frame plus its
    // slew, the drive below 1 % once the RC filter has settled (4.6 τ = 22 ms).
    assert_eq!(out.end.amp_control_v, 0.0);
    assert_eq!(out.end.amp_filtered_v, 0.0);
    let at_rest = out.servo_at_rest_us.expect("servo at rest") - at;
    assert!(
        at_rest <= 250 * MS,
        "servo at rest {at_rest} µs after the panic"
    );
    let below = out.drive_below_1pct_us.expect("drive off") - at;
    assert!(
        (15 * MS..=30 * MS).contains(&below),
        "drive < 1 % after {below} µs"
    );
    eprintln!(
        "panic at {:.3} s: pins safe after {took_us} µs (amplifier duty 0, servo pulse {:.1} µs); \
         drive {:.2} V -> below 1 % after {:.0} ms; horn at rest after {:.0} ms",
        at as f64 * 1e-6,
        out.after.commanded_pulse_us,
        out.drive_v_at_panic,
        below as f64 / 1e3,
        at_rest as f64 / 1e3,
    );
    took_us
}

#[test]
fn a_panic_mid_run_leaves_the_pins_safe_within_1_ms() {
    // Mid step 4 (as the fault tests), and at the last level, where T1 is highest.
    for (wrap, after_trigger_ms) in [(360.0, 45_200), (720.0, 126_300)] {
        let out = run_with_panic(&spec(wrap), after_trigger_ms * MS).unwrap();
        assert!(out.records > 100, "the run was under way");
        check_safe_within_1_ms(&out);
        assert!(out.end.t1_n < out.before.t1_n, "tension released");
    }
}

#[test]
fn before_the_rig_exists_a_panic_stops_the_servo_pulses() {
    // `SafeDuties::NO_SERVO_PULSES` is what the board's handler has until boot has made the
    // rig: the servo then gets no pulse at all rather than a guess.
    assert_eq!(capstan_rig::SafeDuties::NO_SERVO_PULSES.servo_rest, 0);
    // And with the rig made, the duty is the Arduino convention's 125° (1833 µs).
    let rest = ServoMap::default().pulse_us(125.0);
    assert!((rest - 1_833.0).abs() <= 1.0);
}

#[test]
fn a_panic_that_never_comes_is_reported() {
    // Due after the run has ended.
    let err = run_with_panic(&spec(360.0), 200_000 * MS).unwrap_err();
    assert_eq!(err, PanicRunError::NoPanic);
    // The plant is watched long enough to see the drive off and the horn at rest.
    const { assert!(AFTER_PANIC_US >= 250 * MS) };
}
