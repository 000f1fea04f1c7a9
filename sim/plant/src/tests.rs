//! The plant alone, driven by direct calls (no firmware, no time driver).
extern crate std;

use super::*;
use capstan_physics::{Effect, EffectKind, Model};
use capstan_rig::hal::Channel;

const MS: u64 = 1_000;

/// Parts that fail as real parts do (issue 38).
mod failures;
/// A servo without pulses, the cord back-driving it; a sensor pinned at its saturation.
mod unpowered;

/// The duty the firmware writes for a protocol angle (its default map: the Arduino Servo's).
fn duty_for(angle_deg: f64) -> u16 {
    capstan_rig::ServoMap::default().duty(angle_deg as f32, SERVO_MAX_DUTY)
}

/// Where the HS-322HD's horn goes for that duty, deg.
fn horn_deg(angle_deg: f64) -> f64 {
    let pulse_us = duty_for(angle_deg) as f64 / SERVO_MAX_DUTY as f64 * 20_000.0;
    ServoCharacteristic::HS_322HD.angle_deg(pulse_us)
}

fn plant(wrap_deg: f64, model: Model, seed: u64) -> Plant {
    let mut cord = CordSetup::new(wrap_deg, model);
    cord.press_at_us = None;
    Plant::new_at(PlantConfig::default(), &[cord], seed, 0).unwrap()
}

/// Drive at `drive_v`, servo to `angle`, settle for 2 s.
fn hold(p: &mut Plant, angle: f64, drive_v: f64) {
    let t = p.now_us();
    p.set_amp_duty(0, (drive_v / 4.0 * 1000.0).round() as u16, AMP_MAX_DUTY);
    p.set_servo_duty(0, duty_for(angle), SERVO_MAX_DUTY);
    p.advance_to(t + 2_000 * MS);
}

#[test]
fn at_rest_with_the_capstan_stopped_both_sides_carry_the_preload() {
    let mut p = plant(450.0, Model::euler_eytelwein(0.115), 1);
    p.advance_to(500 * MS);
    let t = p.truth(0);
    assert!((t.t1_n - 0.1).abs() < 1e-9 && t.t2_n == t.t1_n, "{t:?}");
    assert_eq!(p.drive().capstan_rpm, 0.0);
}

#[test]
fn euler_eytelwein_is_exact_and_the_protocol_spans_the_thesis_tensions() {
    let mu = 0.115;
    for (wrap, t1_step1, t1_step12) in [
        (270.0, (0.6, 0.9), (19.0, 23.0)),
        (720.0, (0.25, 0.5), (7.5, 10.5)),
    ] {
        let mut p = plant(wrap, Model::euler_eytelwein(mu), 2);
        let mut t1s = [0.0; 13];
        for (k, t1) in t1s.iter_mut().enumerate() {
            hold(&mut p, 125.0 - 5.0 * k as f64, 10.0);
            let t = p.truth(0);
            let want = libm::exp(mu * wrap.to_radians());
            assert!(
                (t.t2_n / t.t1_n / want - 1.0).abs() < 1e-12,
                "{wrap} step {k}: {t:?}"
            );
            assert!(
                (t.angle_deg - horn_deg(125.0 - 5.0 * k as f64)).abs() < 0.1,
                "{t:?}"
            );
            *t1 = t.t1_n;
        }
        assert!(
            (t1_step1.0..t1_step1.1).contains(&t1s[1]),
            "{wrap}: {t1s:?}"
        );
        assert!(
            (t1_step12.0..t1_step12.1).contains(&t1s[12]),
            "{wrap}: {t1s:?}"
        );
        // Hardening: increments grow over the first steps.
        assert!(t1s[2] - t1s[1] > t1s[1] - t1s[0]);
        assert!(t1s[3] - t1s[2] > t1s[2] - t1s[1]);
        // The 45 N over-force limit is not reached.
        assert!(t1s[12] * libm::exp(mu * wrap.to_radians()) < 43.0);
    }
}

#[test]
fn the_drive_matches_the_data_sheet_no_load_figures() {
    let mut p = plant(360.0, Model::euler_eytelwein(0.115), 3);
    // Slack the cord so nothing loads the capstan: servo above rest.
    p.set_servo_duty(0, duty_for(160.0), SERVO_MAX_DUTY);
    p.set_amp_duty(0, 3_000, AMP_MAX_DUTY); // 3.0 V control -> 12 V
    p.advance_to(1_000 * MS);
    let d = p.drive();
    assert!((d.drive_v - 12.0).abs() < 1e-9);
    assert_eq!(p.truth(0).t1_n, 0.0);
    // Scaled to 24 V: 179 rpm and 0.26 A at no load (data sheet).
    let mut big = PlantConfig::default();
    big.motor.amp_gain = 8.0;
    let mut cord = CordSetup::new(360.0, Model::euler_eytelwein(0.115));
    cord.press_at_us = None;
    let mut q = Plant::new_at(big, &[cord], 3, 0).unwrap();
    q.set_servo_duty(0, duty_for(160.0), SERVO_MAX_DUTY);
    q.set_amp_duty(0, 3_000, AMP_MAX_DUTY);
    q.advance_to(2_000 * MS);
    let d = q.drive();
    assert!((d.capstan_rpm - 180.0).abs() < 3.0, "{d:?}");
    assert!((d.current_a - 0.26).abs() < 0.01, "{d:?}");
    // Spin-up time constant ~31 ms: at 10 V it is at speed well within 0.3 s.
    let mut r = plant(360.0, Model::euler_eytelwein(0.115), 3);
    r.set_servo_duty(0, duty_for(160.0), SERVO_MAX_DUTY);
    r.set_amp_duty(0, 2_500, AMP_MAX_DUTY);
    r.advance_to(300 * MS);
    let rpm = r.drive().capstan_rpm;
    assert!((70.0..76.0).contains(&rpm), "{rpm}");
}

#[test]
fn friction_loads_the_drive_and_a_weak_drive_stalls() {
    let mut p = plant(720.0, Model::euler_eytelwein(0.115), 4);
    hold(&mut p, 125.0, 10.0);
    let idle = p.drive();
    hold(&mut p, 65.0, 10.0);
    let loaded = p.drive();
    let t = p.truth(0);
    let torque = (t.t2_n - t.t1_n) * 12.7e-3 / 2.0;
    assert!((loaded.load_nm - torque).abs() < 1e-9, "{loaded:?}");
    assert!(
        loaded.current_a > idle.current_a + 0.1,
        "{idle:?} {loaded:?}"
    );
    assert!(loaded.capstan_rpm < idle.capstan_rpm && loaded.transmission == 1.0);
    // The thesis-as-written 46.5 Ω on the 1.0 in capstan cannot hold 720° at step 12.
    let mut cfg = PlantConfig::default();
    cfg.motor.resistance_ohm = 46.5;
    cfg.capstan_diameter_mm = 25.4;
    let mut cord = CordSetup::new(720.0, Model::euler_eytelwein(0.115));
    cord.press_at_us = None;
    let mut q = Plant::new_at(cfg, &[cord], 4, 0).unwrap();
    hold(&mut q, 65.0, 10.0);
    let d = q.drive();
    let t = q.truth(0);
    assert_eq!(d.capstan_rpm, 0.0, "{d:?}");
    assert!(d.transmission < 1.0, "{d:?}");
    let stall_out = 0.0612 * 10.0 / 46.5 * 19.7 - 0.004 * 19.7;
    assert!(
        ((t.t2_n - t.t1_n) * 12.7e-3 - stall_out).abs() < 1e-6,
        "{t:?}"
    );
}

#[test]
fn the_servo_takes_pulses_at_frames_and_slews_at_its_rated_speed() {
    let mut p = plant(360.0, Model::euler_eytelwein(0.115), 5);
    p.advance_to(25 * MS);
    p.set_servo_duty(0, duty_for(65.0), SERVO_MAX_DUTY);
    p.advance_to(39 * MS);
    let rest = horn_deg(125.0);
    assert!((p.truth(0).angle_deg - rest).abs() < 0.032); // one duty count; next frame: 40 ms
    p.advance_to(40 * MS);
    let last = horn_deg(65.0);
    assert!((p.truth(0).target_deg - last).abs() < 1e-9); // one duty count is 0.032°
                                                          // Release towards rest runs at the no-load rate: 60° in 0.19 s.
    p.advance_to(1_000 * MS);
    p.set_servo_duty(0, duty_for(125.0), SERVO_MAX_DUTY);
    p.advance_to(1_020 * MS);
    let start = p.now_us();
    assert!((p.truth(0).target_deg - rest).abs() < 1e-9);
    while p.truth(0).angle_deg < rest {
        p.advance_to(p.now_us() + MS);
    }
    let took = p.now_us() - start;
    // The thesis's 60° of command are 61.9° of this servo's horn: 196 ms.
    let want = (rest - last) / (60.0 / 0.19) * 1e6;
    assert!(
        (took as f64 - want).abs() <= 1_000.0,
        "{took} µs, want {want}"
    );
    let (events, dropped) = p.servo_events(0);
    assert_eq!(dropped, 0);
    assert_eq!(events.len(), 2);
    assert_eq!(events[0].t_us, 25 * MS);
    assert!((events[0].angle_deg as f64 - last).abs() < 1e-4);
    assert!(
        (events[0].pulse_us - 1214.0).abs() <= 1.0,
        "{:?}",
        events[0]
    );
    assert!(
        (events[1].pulse_us - 1833.0).abs() <= 1.0,
        "{:?}",
        events[1]
    );
}

#[test]
fn read_both_converts_as_two_read_counts() {
    // `read_both` works out the shared parts once and draws on a copy of the generator's
    // state: the same counts, and the generator left the same, as two `read_counts` (drive off,
    // then on; ~1 % of the draws take the ziggurat's rare path).
    let run = |both: bool| {
        let mut p = plant(450.0, Model::euler_eytelwein(0.115), 9);
        let mut v = std::vec::Vec::new();
        for k in 0..5_000u64 {
            p.advance_to(k * MS);
            if k == 100 {
                p.set_amp_duty(0, 2_500, AMP_MAX_DUTY);
                p.set_servo_duty(0, duty_for(95.0), SERVO_MAX_DUTY);
            }
            if both {
                v.extend(p.read_both(0).map(Result::unwrap));
            } else {
                v.push(p.read_counts(0, Channel::T1).unwrap());
                v.push(p.read_counts(0, Channel::T2).unwrap());
            }
        }
        v
    };
    assert_eq!(run(true), run(false));
}

#[test]
fn same_seed_same_counts_and_noise_has_the_configured_spread() {
    let run = |seed| {
        let mut p = plant(450.0, Model::euler_eytelwein(0.115), seed);
        let mut v = std::vec::Vec::new();
        for k in 0..20_000u64 {
            p.advance_to(k * MS);
            if k == 100 {
                p.set_amp_duty(0, 2_500, AMP_MAX_DUTY);
                p.set_servo_duty(0, duty_for(95.0), SERVO_MAX_DUTY);
            }
            v.push(p.read_counts(0, Channel::T1).unwrap());
            v.push(p.read_counts(0, Channel::T2).unwrap());
        }
        (v, p.sensor_zero_counts(0), p.truth(0))
    };
    let (a, zero, truth) = run(9);
    let (b, _, _) = run(9);
    let (c, _, _) = run(10);
    assert_eq!(a, b);
    assert_ne!(a, c);
    // Last 10 s: mean counts = zero + T/0.015; sd = 0.02 N / 0.015 = 1.33 counts (+ rounding).
    let tail: std::vec::Vec<f64> = a[20_000..].iter().step_by(2).map(|&x| x as f64).collect();
    let n = tail.len() as f64;
    let mean = tail.iter().sum::<f64>() / n;
    let sd = (tail.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n).sqrt();
    assert!(
        (mean - (zero[0] + truth.t1_n / 0.015)).abs() < 0.05,
        "{mean}"
    );
    assert!(
        (sd - (1.333f64.powi(2) + 1.0 / 12.0).sqrt()).abs() < 0.05,
        "{sd}"
    );
}

#[test]
fn catalogue_artefacts_ride_on_the_drive() {
    let noiseless = |model: Model| {
        let mut cfg = PlantConfig::default();
        cfg.sensor.noise_sd_n = 0.0;
        cfg.sensor.zero_spread_counts = 0.0;
        let mut cord = CordSetup::new(360.0, model);
        cord.press_at_us = None;
        Plant::new_at(cfg, &[cord], 0, 0).unwrap()
    };
    let base = Model::euler_eytelwein(0.115);
    let m = base
        .with_effect(Effect {
            kind: EffectKind::T1Offset,
            value: 0.3,
        })
        .with_effect(Effect {
            kind: EffectKind::SensorGain,
            value: 1.1,
        });
    let mut p = noiseless(m);
    p.advance_to(100 * MS);
    // Stopped (the tare's conditions): no offset, no gain; both read the 0.1 N preload.
    let c1 = p.read_counts(0, Channel::T1).unwrap();
    let c2 = p.read_counts(0, Channel::T2).unwrap();
    assert_eq!((c1, c2), (407, 407)); // 400 + 0.1/0.015 = 406.7
    let m = base.with_effect(Effect {
        kind: EffectKind::SensorGain,
        value: 1.5,
    });
    let mut p2 = noiseless(m);
    p2.advance_to(100 * MS);
    // Were the gain applied here, T2 would read 400 + 0.15/0.015 = 410.
    assert_eq!(p2.read_counts(0, Channel::T2).unwrap(), 407);
    hold(&mut p, 85.0, 10.0);
    let t = p.truth(0);
    let c1 = p.read_counts(0, Channel::T1).unwrap() as f64;
    let c2 = p.read_counts(0, Channel::T2).unwrap() as f64;
    assert!((c1 - (400.0 + (t.t1_n + 0.3) / 0.015)).abs() <= 0.5);
    assert!((c2 - (400.0 + 1.1 * t.t2_n / 0.015)).abs() <= 0.5);
}

#[test]
fn injected_faults_act_on_the_plant() {
    let mut p = plant(360.0, Model::euler_eytelwein(0.115), 6);
    let kinds = [
        InjectionKind::SensorUnplugged(Channel::T1),
        InjectionKind::OverForce,
        InjectionKind::Abort,
        InjectionKind::CordBreak,
    ];
    for (k, kind) in kinds.into_iter().enumerate() {
        let after_trigger_us = (k as u64 + 1) * 1_000 * MS;
        p.inject(Injection {
            kind,
            cord: 0,
            after_trigger_us,
        })
        .unwrap();
    }
    let bad = Injection {
        kind: InjectionKind::Abort,
        cord: 1,
        after_trigger_us: 0,
    };
    assert_eq!(p.inject(bad), Err(PlantError::BadInjection));
    hold(&mut p, 95.0, 10.0);
    p.set_trigger(0, true);
    let rise = p.now_us();
    p.advance_to(rise + 999 * MS);
    assert!(p.truth(0).t2_n > 5.0);
    assert!(p.read_counts(0, Channel::T1).unwrap() > 400);
    assert!(p.injections()[0].at_us.is_none());
    p.advance_to(rise + 1_000 * MS);
    assert_eq!(p.injections()[0].at_us, Some(rise + 1_000 * MS));
    assert_eq!(p.read_counts(0, Channel::T1), Ok(0));
    p.advance_to(rise + 2_000 * MS);
    assert_eq!(p.truth(0).t2_n, 50.0);
    assert!(!p.button_pressed(0));
    p.advance_to(rise + 3_000 * MS);
    assert!(p.button_pressed(0));
    p.advance_to(rise + 3_200 * MS);
    assert!(!p.button_pressed(0));
    p.advance_to(rise + 4_000 * MS);
    assert_eq!((p.truth(0).t1_n, p.truth(0).t2_n), (0.0, 0.0));
    // The safe state: servo commanded to rest and amplifier at 0 V.
    assert!(p.injections().iter().all(|r| r.safe_at_us.is_none()));
    p.set_servo_duty(0, duty_for(125.0), SERVO_MAX_DUTY);
    assert!(p.injections().iter().all(|r| r.safe_at_us.is_none()));
    p.advance_to(rise + 4_005 * MS);
    p.set_amp_duty(0, 0, AMP_MAX_DUTY);
    for r in p.injections() {
        assert_eq!(r.safe_at_us, Some(rise + 4_005 * MS), "{r:?}");
    }
    assert_eq!(p.injections()[3].safe_after_us(), Some(5 * MS));
    for name in InjectionKind::NAMES {
        assert_eq!(InjectionKind::from_name(name).unwrap().name(), name);
    }
}

#[test]
fn time_dependent_laws_are_refreshed_and_heating_lowers_mu() {
    let mut model = Model::euler_eytelwein(0.115);
    model.law.heat_per_ns = 0.002;
    model.law.heat_tau_s = 7.0;
    let mut p = plant(720.0, model, 7);
    hold(&mut p, 75.0, 10.0);
    let early = p.truth(0);
    p.advance_to(p.now_us() + 30_000 * MS);
    let late = p.truth(0);
    assert!(late.mu < early.mu * 0.9, "{early:?} {late:?}");
    let a = late.t2_n / late.t1_n;
    assert!(
        (a - libm::exp(late.mu * (720.0f64).to_radians())).abs() < 2e-3,
        "{a} {late:?}"
    );
}

#[test]
fn bad_constants_are_refused_by_name() {
    let mut cfg = PlantConfig::default();
    cfg.cord.stiffness = 0.0;
    let cord = CordSetup::default();
    assert_eq!(
        Plant::new_at(cfg, &[cord], 0, 0).unwrap_err(),
        PlantError::BadConstant("cord.stiffness")
    );
    assert_eq!(
        Plant::new_at(PlantConfig::default(), &[], 0, 0).unwrap_err(),
        PlantError::CordCount
    );
    assert_eq!(
        Plant::new_at(PlantConfig::default(), &[cord; 5], 0, 0).unwrap_err(),
        PlantError::CordCount
    );
}

#[test]
fn the_plant_fits_a_small_microcontroller() {
    // The QEMU build keeps one in RAM (lm3s6965: 64 KiB). (6.0 KiB before issue 24's servo
    // back-drive and sensor saturation constants and the servos' power state.)
    let size = core::mem::size_of::<Plant>();
    assert!(size < 6 * 1024 + 512, "{size} bytes");
}

#[test]
fn the_servo_is_an_hs322hd_whatever_the_firmware_means() {
    let hs = ServoCharacteristic::HS_322HD;
    // Data sheet: 1500 µs neutral, 40° per 400 µs, clockwise as the pulse grows.
    assert_eq!(hs.angle_deg(1_500.0), 90.0);
    assert!((hs.angle_deg(1_900.0) - 130.0).abs() < 1e-9);
    assert!((hs.angle_deg(1_100.0) - 50.0).abs() < 1e-9);
    assert_eq!(hs.angle_deg(3_000.0), 180.0); // end of travel
    assert!((hs.pulse_us(hs.angle_deg(1_833.0)) - 1_833.0).abs() < 1e-9);
    // The thesis's write(125) and write(65): the protocol's 60° are 61.9° of horn.
    assert!((THESIS_REST_PULSE_US - 1_832.89).abs() < 0.01);
    assert!((horn_deg(125.0) - 123.3).abs() < 0.05);
    assert!((horn_deg(65.0) - 61.4).abs() < 0.05);
    // A firmware still on a 1000-2000 µs map over 0-180° rests this servo 13.9° of horn past
    // the preload point (1694 µs: T1 2.6 N where the tare assumes 0.1 N) and moves it by about
    // half the thesis's travel: the last level is nowhere near the thesis's ~21 N.
    let old = capstan_rig::ServoMap {
        pulse_at_min_us: 1_000.0,
        pulse_at_max_us: 2_000.0,
        max_deg: 180.0,
    };
    let mut p = plant(270.0, Model::euler_eytelwein(0.115), 8);
    let mut t1 = [0.0; 13];
    for (k, t) in t1.iter_mut().enumerate() {
        let t0 = p.now_us();
        p.set_amp_duty(0, 2_500, AMP_MAX_DUTY);
        let duty = old.duty(125.0 - 5.0 * k as f32, SERVO_MAX_DUTY);
        p.set_servo_duty(0, duty, SERVO_MAX_DUTY);
        p.advance_to(t0 + 2_000 * MS);
        *t = p.truth(0).t1_n;
    }
    assert!((2.0..3.0).contains(&t1[0]), "{t1:?}");
    assert!(t1[12] < 16.0 && t1[12] - t1[0] < 12.0, "{t1:?}");
    // With the Arduino convention the same servo spans the thesis's tensions (0.75 → 21 N).
    let mut p = plant(270.0, Model::euler_eytelwein(0.115), 8);
    hold(&mut p, 120.0, 10.0);
    let first = p.truth(0).t1_n;
    hold(&mut p, 65.0, 10.0);
    let last = p.truth(0).t1_n;
    assert!((0.6..0.9).contains(&first) && (19.0..23.0).contains(&last));
}

#[test]
fn the_amplifiers_rc_filter_takes_22_ms_to_settle_within_1_percent() {
    let mut p = plant(360.0, Model::euler_eytelwein(0.115), 7);
    p.set_servo_duty(0, duty_for(160.0), SERVO_MAX_DUTY); // slack: no friction load
    p.set_amp_duty(0, 2_500, AMP_MAX_DUTY); // 2.5 V control, 10 V drive
    assert!(!p.is_safe(0));
    // One time constant (4.7 kΩ · 1 µF = 4,700 µs): 63 %.
    p.advance_to(4_700);
    let d = p.drive().drive_v;
    assert!((d - 10.0 * (1.0 - (-1.0f64).exp())).abs() < 0.01, "{d}");
    p.advance_to(1_000 * MS);
    assert_eq!(p.drive().drive_v, 10.0);
    assert_eq!(p.truth(0).amp_filtered_v, 2.5);
    // The safe state is commanded at once (duty 0), the drive follows the filter.
    p.set_amp_duty(0, 0, AMP_MAX_DUTY);
    p.set_servo_duty(0, duty_for(125.0), SERVO_MAX_DUTY);
    assert!(p.is_safe(0));
    // 1 % of 10 V after 4.6 τ = 21.6 ms.
    p.advance_to(1_020 * MS);
    assert!(p.drive().drive_v > 0.1, "{:?}", p.drive());
    p.advance_to(1_022 * MS);
    assert!(p.drive().drive_v < 0.1, "{:?}", p.drive());
    p.advance_to(1_200 * MS);
    assert_eq!(p.drive().drive_v, 0.0);
    // Without the filter the drive follows the duty at once.
    let mut cfg = PlantConfig::default();
    cfg.motor.amp_filter_tau_s = 0.0;
    let mut cord = CordSetup::new(360.0, Model::euler_eytelwein(0.115));
    cord.press_at_us = None;
    let mut q = Plant::new_at(cfg, &[cord], 7, 0).unwrap();
    q.set_amp_duty(0, 2_500, AMP_MAX_DUTY);
    assert_eq!(q.drive().drive_v, 10.0);
}
