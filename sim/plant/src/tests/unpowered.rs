//! What the plant does when the firmware is not there: a servo without pulses (a reset, a
//! power cycle of the Pico), whose horn the cord back-drives toward release; and a sensor
//! pinned at the saturation of its output.

use super::*;

/// The horn at the last level (65°, T1 ≈ 15 N at 360°), the capstan stopped, then no pulses.
fn unpowered_at(angle: f64) -> (Plant, f64) {
    let mut p = plant(360.0, Model::euler_eytelwein(0.115), 6);
    hold(&mut p, angle, 0.0);
    let held = p.truth(0).angle_deg;
    p.set_servo_duty(0, 0, SERVO_MAX_DUTY);
    (p, held)
}

#[test]
fn the_cord_back_drives_an_unpowered_horn_toward_release_only() {
    let (mut p, held) = unpowered_at(65.0);
    let t0 = p.now_us();
    let t1_before = p.truth(0).t1_n;
    assert!(t1_before > 10.0, "{t1_before}");
    // Within a frame the servo has no pulse, and the horn starts to turn back.
    let mut last = held;
    let mut t1_last = t1_before;
    for k in 1..=3_000 {
        p.advance_to(t0 + k * MS);
        let t = p.truth(0);
        assert!(t.angle_deg >= last, "back-drive only toward release");
        assert!(t.t1_n <= t1_last + 1e-12, "the tension only falls");
        last = t.angle_deg;
        t1_last = t.t1_n;
    }
    let t = p.truth(0);
    assert_eq!(t.commanded_pulse_us, 0.0);
    // It stops where the cord's torque on the lever meets the gear train's hold (0.003 N m:
    // T1 = 0.47 N), on the tension side of rest (0.1 N at 123.3° of horn).
    let hold_n = p.config().servo.unpowered_hold_nm / p.config().servo.lever_m;
    assert!((t.t1_n - hold_n).abs() < 0.05, "{t:?}");
    assert!(
        t.angle_deg > held + 40.0 && t.angle_deg < horn_deg(125.0),
        "{t:?}"
    );
    // At the preload nothing moves: the gear train holds it.
    let (mut p, held) = unpowered_at(125.0);
    p.advance_to(p.now_us() + 500 * MS);
    assert_eq!(p.truth(0).angle_deg, held);
}

#[test]
fn a_pulse_re_sent_after_a_back_drive_re_pulls_the_cord_at_full_speed() {
    // The hazard of issue 24: a reset leaves the servo without pulses; the cord pulls the horn
    // back; a boot that re-sends the last command pulls it all the way again at the servo's
    // own speed, on a stopped capstan.
    let (mut p, _) = unpowered_at(65.0);
    p.advance_to(p.now_us() + 300 * MS);
    let slack = p.truth(0);
    p.set_servo_duty(0, duty_for(65.0), SERVO_MAX_DUTY);
    let t0 = p.now_us();
    let mut rise_ms = None;
    for k in 1..=300 {
        p.advance_to(t0 + k * MS);
        if rise_ms.is_none() && p.truth(0).t1_n > 10.0 {
            rise_ms = Some(k);
        }
    }
    let rise_ms = rise_ms.expect("re-pulled");
    assert!(rise_ms < 300, "{rise_ms} ms from {slack:?}");
    // The rest pulse instead (the fix: the first pulse after the person's acknowledgement)
    // only releases.
    let (mut p, _) = unpowered_at(65.0);
    p.advance_to(p.now_us() + 300 * MS);
    let t1 = p.truth(0).t1_n;
    p.set_servo_duty(0, duty_for(125.0), SERVO_MAX_DUTY);
    let t0 = p.now_us();
    for k in 1..=300 {
        p.advance_to(t0 + k * MS);
        assert!(p.truth(0).t1_n <= t1 + 1e-9);
    }
    assert!((p.truth(0).t1_n - 0.1).abs() < 0.01, "{:?}", p.truth(0));
}

#[test]
fn a_sensor_beyond_its_range_reads_pinned_at_the_dividers_saturation() {
    let mut p = plant(360.0, Model::euler_eytelwein(0.115), 7);
    p.advance_to(10 * MS);
    // 70 N hung on T2: far beyond the sensor's 5 V output.
    p.hang(0, Channel::T2, 70.0);
    let sat = DIVIDER_SATURATION_COUNTS;
    assert!((sat - 3989.6).abs() < 0.1);
    for _ in 0..100 {
        let [_, c2] = p.read_both(0);
        assert_eq!(c2, Ok(3990));
        assert_eq!(p.read_analog(0, Channel::T2), sat);
    }
}
