//! Firmware in the loop: the firmware's own runner and rig against the plant, checked from the
//! plant's side — what it was commanded, when, and what it really carried.

use capstan_physics::Model;
use capstan_plant::{CordSetup, Injection, InjectionKind, ServoCharacteristic, SERVO_MAX_DUTY};
use capstan_rig::hal::Channel;
use capstan_rig::{FaultKind, Protocol, ServoMap, StepOrder};
use capstan_sim::run::{run, RunOutput, RunSpec, TraceSample};

const MS: u64 = 1_000;
/// The plant presses the button at 10 ms; the debouncer accepts it 10 samples later.
const PRESS_US: u64 = 10 * MS + 9 * MS;

fn spec(wrap_deg: f64) -> RunSpec {
    RunSpec {
        cord: CordSetup::new(wrap_deg, Model::euler_eytelwein(0.115)),
        ..RunSpec::default()
    }
}

/// One duty count of the servo PWM, as horn angle on the HS-322HD (0.1°/µs): 0.032°.
const ANGLE_TOL: f64 = 0.1 * 20_000.0 / SERVO_MAX_DUTY as f64;
/// One duty count, as pulse width: 0.32 µs.
const PULSE_TOL: f64 = 20_000.0 / SERVO_MAX_DUTY as f64;

/// The pulse the protocol's angle means: the Arduino Servo convention (544-2400 µs, 0-180°).
fn arduino_pulse_us(angle_deg: f32) -> f64 {
    ServoMap::ARDUINO_SERVO.pulse_us(angle_deg) as f64
}

/// Where the simulated HS-322HD's horn goes for that pulse, deg.
fn horn_deg(angle_deg: f32) -> f64 {
    ServoCharacteristic::HS_322HD.angle_deg(arduino_pulse_us(angle_deg))
}

#[test]
fn servo_steps_and_trigger_reach_the_plant_on_time() {
    let out = run(&RunSpec {
        trace_every_ms: 1,
        ..spec(360.0)
    })
    .unwrap();
    let p = Protocol::default();
    assert_eq!(out.end.unwrap().fault, None);
    // The trigger: one pulse of 500 ms, rising 1 s after the (debounced) press.
    assert_eq!(
        out.trigger_edges,
        vec![
            (PRESS_US + 1_000 * MS, true),
            (PRESS_US + 1_500 * MS, false)
        ]
    );
    // Servo commands: rest at the first sample, then steps 1..=12 every 10 s, rest at the end.
    let ev = &out.servo_events;
    assert_eq!(ev.len(), 1 + 13, "{ev:?}");
    // The rest at 1833 µs and the last level at 1214 µs: the thesis's write(125), write(65).
    assert!(
        (ev[0].pulse_us - 1_833.0).abs() <= 1.0 && ev[0].t_us == MS,
        "{ev:?}"
    );
    assert!((ev[12].pulse_us - 1_214.0).abs() <= 1.0, "{ev:?}");
    for k in 1..=13u32 {
        let e = ev[k as usize];
        let want_t = PRESS_US + p.step_start_ms(k) as u64 * MS;
        assert_eq!(e.t_us, want_t, "step {k}");
        assert!(
            (e.pulse_us as f64 - arduino_pulse_us(p.angle_deg(k))).abs() <= PULSE_TOL,
            "step {k}: {e:?}"
        );
        assert!(
            (e.angle_deg as f64 - horn_deg(p.angle_deg(k))).abs() <= ANGLE_TOL,
            "step {k}: {e:?}"
        );
    }
    // The servo itself is there within a PWM frame plus its slew (5.2° of horn at ≥ 158°/s):
    // 60 ms.
    for k in 1..=12u32 {
        let t = PRESS_US + p.step_start_ms(k) as u64 * MS;
        let at = |dt_ms: u64| -> &TraceSample {
            out.trace.iter().find(|s| s.t_us >= t + dt_ms * MS).unwrap()
        };
        let target = horn_deg(p.angle_deg(k));
        assert!(
            (at(0).angle_deg - target).abs() > 4.0,
            "step {k} moved early"
        );
        assert!(
            (at(60).angle_deg - target).abs() <= ANGLE_TOL,
            "step {k}: {:?}",
            at(60)
        );
    }
    // The capstan turns from the end of the tare (500 ms) to the run's end.
    let rpm_at = |t_us: u64| {
        out.trace
            .iter()
            .find(|s| s.t_us >= t_us)
            .unwrap()
            .capstan_rpm
    };
    assert_eq!(rpm_at(PRESS_US + 400 * MS), 0.0);
    assert!(rpm_at(PRESS_US + 1_000 * MS) > 60.0);
    assert!(out.max_feed_gap_us <= MS, "watchdog fed every sample");
    assert!(out.log.sequence_ok);
}

#[test]
fn conditioned_pairs_are_the_plants_true_tensions_over_each_window() {
    for wrap in [270.0, 720.0] {
        let out = run(&RunSpec {
            trace_every_ms: 1,
            ..spec(wrap)
        })
        .unwrap();
        assert_eq!(out.log.pairs.len(), 12);
        for pair in &out.log.pairs {
            // Window [change + 2 s, next change − 1 s) on the plant's clock.
            let mid = out.plant_us(pair.t_mid_ms as i64 * 1000).unwrap();
            let (a, b) = (mid - 3_500 * MS, mid + 3_500 * MS);
            let win: Vec<&TraceSample> = out
                .trace
                .iter()
                .filter(|s| s.t_us >= a && s.t_us < b)
                .collect();
            assert_eq!(win.len(), 7_000);
            let t1 = win.iter().map(|s| s.t1_n).sum::<f64>() / 7_000.0;
            let t2 = win.iter().map(|s| s.t2_n).sum::<f64>() / 7_000.0;
            assert_eq!((pair.t1.count, pair.t2.count), (7_000, 7_000));
            // Noise 0.02 N/√7000, a tare on 500 samples, 0.015 N counts: a few mN at most.
            let tol = |t: f64| 0.004 + 2e-4 * t;
            assert!(
                (pair.t1.mean_n as f64 - t1).abs() < tol(t1),
                "{wrap}° step {}: T1 {} vs true {t1}",
                pair.step,
                pair.t1.mean_n
            );
            assert!(
                (pair.t2.mean_n as f64 - t2).abs() < tol(t2),
                "{wrap}° step {}: T2 {} vs true {t2}",
                pair.step,
                pair.t2.mean_n
            );
            // The window's spread is the sensor noise (0.02 N), not a transient.
            assert!(pair.t1.std_n < 0.03 && pair.t2.std_n < 0.03, "{pair:?}");
        }
    }
}

#[test]
fn the_tare_removes_each_sensors_own_zero() {
    let out = run(&spec(450.0)).unwrap();
    let start = out.log.start.expect("run start");
    let zero = out.sensor_zero_counts;
    // The plant drew zeros around 400 counts; the tare (preload 0.1 N, capstan stopped)
    // finds them to within the noise of 500 samples.
    assert!((zero[0] - 400.0).abs() > 0.5 || (zero[1] - 400.0).abs() > 0.5);
    assert!(
        (start.calibration.t1.zero_counts as f64 - zero[0]).abs() < 0.3,
        "{start:?}"
    );
    assert!(
        (start.calibration.t2.zero_counts as f64 - zero[1]).abs() < 0.3,
        "{start:?}"
    );
}

#[test]
fn updown_order_visits_every_level_once_and_the_plant_follows() {
    let mut s = spec(450.0);
    s.protocol.order = StepOrder::UpDown;
    let out = run(&s).unwrap();
    let levels: Vec<u32> = out.log.pairs.iter().map(|p| p.level).collect();
    assert_eq!(levels, vec![1, 3, 5, 7, 9, 11, 12, 10, 8, 6, 4, 2]);
    let p = Protocol {
        order: StepOrder::UpDown,
        ..Protocol::default()
    };
    for (k, ev) in out.servo_events[1..13].iter().enumerate() {
        let want = arduino_pulse_us(125.0 - 5.0 * p.level(k as u32 + 1) as f32);
        assert!((ev.pulse_us as f64 - want).abs() <= PULSE_TOL, "{ev:?}");
    }
    // Tension follows the level, not the time: T1 orders as the levels do.
    let mut by_level: Vec<(u32, f32)> = out
        .log
        .pairs
        .iter()
        .map(|p| (p.level, p.t1.mean_n))
        .collect();
    by_level.sort_by_key(|x| x.0);
    for w in by_level.windows(2) {
        assert!(w[1].1 > w[0].1, "{by_level:?}");
    }
    // Same level, same tension as the monotone order (same plant, same seed).
    let mono = run(&spec(450.0)).unwrap();
    for pair in &out.log.pairs {
        let m = mono.log.pairs[pair.level as usize - 1];
        assert!(
            (pair.t1.mean_n - m.t1.mean_n).abs() < 0.005,
            "{pair:?} {m:?}"
        );
        assert!(
            (pair.t2.mean_n - m.t2.mean_n).abs() < 0.01,
            "{pair:?} {m:?}"
        );
    }
}

/// Inject mid step 4 (45.2 s after the trigger) and check the firmware's reaction from the
/// plant's side.
fn fault_case(kind: InjectionKind, want: FaultKind) -> RunOutput {
    let mut s = spec(360.0);
    let clean = run(&s).unwrap();
    s.injections = vec![Injection {
        kind,
        cord: 0,
        after_trigger_us: 45_200 * MS,
    }];
    let out = run(&s).unwrap();
    let end = out.end.unwrap();
    assert_eq!(end.fault, Some(want), "{kind:?}: {:?}", out.log.faults);
    assert_eq!(out.log.faults.len(), 1);
    assert_eq!(out.log.faults[0].kind.name(), kind.name());
    // Safe (servo commanded to rest, amplifier 0 V) within 20 ms of the injection.
    let rep = out.injections[0];
    let safe_ms = rep.safe_after_us().expect("made safe") as f64 / 1000.0;
    assert!(safe_ms <= 20.0, "{kind:?}: safe after {safe_ms} ms");
    let last = out.servo_events.last().unwrap();
    assert!((last.pulse_us as f64 - arduino_pulse_us(125.0)).abs() <= PULSE_TOL);
    assert_eq!(out.safe_since_us, rep.safe_at_us);
    // The three pairs made before it are kept, identical to the clean run's.
    assert_eq!(end.pairs, 3);
    assert_eq!(out.log.pairs[..], clean.log.pairs[..3]);
    assert!(matches!(out.log.end, Some(e) if e.fault == Some(want)));
    eprintln!("{}: safe after {safe_ms} ms", kind.name());
    out
}

#[test]
fn cord_break_is_caught_and_made_safe() {
    fault_case(InjectionKind::CordBreak, FaultKind::CordBreak);
}

#[test]
fn unplugged_sensor_is_caught_and_made_safe() {
    fault_case(
        InjectionKind::SensorUnplugged(Channel::T2),
        FaultKind::SensorRail,
    );
    fault_case(
        InjectionKind::SensorUnplugged(Channel::T1),
        FaultKind::SensorRail,
    );
}

#[test]
fn over_force_is_caught_and_made_safe() {
    let out = fault_case(InjectionKind::OverForce, FaultKind::OverForce);
    assert!((out.log.faults[0].value - 50.0).abs() < 0.1);
}

#[test]
fn abort_press_is_caught_and_made_safe() {
    fault_case(InjectionKind::Abort, FaultKind::Abort);
}

#[test]
fn a_break_at_rest_is_caught_from_the_drop_of_both_channels() {
    // During step 0 no tension level is held; the cord at its preload (0.1 N) carries ~0.18 N
    // on both sensors with the drive on, and both fall at once when it parts: caught within
    // three of the supervisor's 0.1 s blocks. (Before issue 38: only at the first level, 10 s
    // later.)
    let mut s = spec(360.0);
    s.injections = vec![Injection {
        kind: InjectionKind::CordBreak,
        cord: 0,
        after_trigger_us: 700 * MS,
    }];
    let out = run(&s).unwrap();
    let f = out.log.faults[0];
    assert_eq!(f.kind, FaultKind::CordBreak);
    assert!((700_000..=1_000_000).contains(&f.t_us), "{f:?}");
    assert_eq!(out.end.unwrap().pairs, 0);
}
