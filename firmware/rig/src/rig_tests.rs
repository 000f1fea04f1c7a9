//! The rig state machine driven sample by sample against a scripted fake plant: protocol
//! timing, trigger, conditioning, tare, sequence numbers and every safety fault.

use crate::calib::Calibration;
use crate::hal::AdcError;
use crate::protocol::{Protocol, StepOrder};
use crate::record::{FaultKind, LogSink, Record, RunEnd, StepPair};
use crate::rig::{Inputs, Outputs, Rig};
use crate::safety::SafetyLimits;
use std::vec::Vec;

/// What must never blind a check or move the rig without a person: a loaded tare, a mistyped
/// sensitivity, a held button, a fault while idle, a reset, a store away from rest.
mod guard;
/// Between runs: fault latching and acknowledgement, slow homing.
mod idle;

#[derive(Default)]
struct VecSink(Vec<(u32, Record)>);

impl LogSink for VecSink {
    fn emit(&mut self, seq: u32, record: &Record) {
        self.0.push((seq, *record));
    }
}

impl VecSink {
    fn pairs(&self) -> Vec<StepPair> {
        self.0
            .iter()
            .filter_map(|(_, r)| match r {
                Record::Pair(p) => Some(*p),
                _ => None,
            })
            .collect()
    }
}

/// What the scripted plant does at a given time (µs from the start of the simulation).
type Script<'a> = dyn Fn(u64, &Outputs) -> ([Result<u16, AdcError>; 2], bool) + 'a;

struct Trace {
    outputs: Vec<(u64, Outputs)>,
    sink: VecSink,
    end: Option<(u64, RunEnd)>,
}

/// Press the button at 100 ms for 50 ms; sample at 1 kHz; stop at the run's end.
fn drive(rig: &mut Rig, script: &Script<'_>, skip: Option<(u64, u64)>) -> Trace {
    let mut sink = VecSink::default();
    let mut outputs = Vec::new();
    let mut last = rig.safe_outputs();
    let mut t = 0u64;
    while t < 200_000_000 {
        if let Some((from, to)) = skip {
            if t == from {
                t = to;
            }
        }
        let (counts, extra_press) = script(t, &last);
        let button_pressed = (100_000..150_000).contains(&t) || extra_press;
        let out = rig.step(
            &Inputs {
                now_us: t,
                counts,
                button_pressed,
                command: None,
            },
            &mut sink,
        );
        outputs.push((t, out));
        last = out;
        if let Some(end) = out.finished {
            return Trace {
                outputs,
                sink,
                end: Some((t, end)),
            };
        }
        t += 1_000;
    }
    Trace {
        outputs,
        sink,
        end: None,
    }
}

/// A linear spring on the servo: T1 = 0.1 N at rest plus 0.3 N per degree; T2 = 2 T1 with the
/// capstan driven.
fn plant_counts(out: &Outputs, cal: &Calibration, zero_shift: f32) -> [Result<u16, AdcError>; 2] {
    let t1 = 0.1 + 0.3 * (125.0 - out.servo_deg).max(0.0);
    let t2 = if out.amp_control_v > 0.0 {
        2.0 * t1
    } else {
        t1
    };
    [
        Ok((cal.t1.counts(t1) + zero_shift).round() as u16),
        Ok((cal.t2.counts(t2) + zero_shift).round() as u16),
    ]
}

/// The default limits but the stuck check: the scripted plant has no noise, which no real
/// channel lacks.
fn limits() -> SafetyLimits {
    SafetyLimits {
        stuck_samples: 0,
        ..SafetyLimits::default()
    }
}

/// The thesis's protocol on sensitivities a person typed.
fn thesis_rig() -> Rig {
    Rig::new(
        Protocol::default(),
        Calibration::default().typed(),
        limits(),
    )
    .unwrap()
}

/// The debounced press lands 10 samples after the raw press at 100 ms.
const PRESS_US: u64 = 100_000 + 9_000;

#[test]
fn every_servo_step_and_the_trigger_are_on_time() {
    let mut rig = thesis_rig();
    let cal = Calibration::default();
    let tr = drive(
        &mut rig,
        &move |_, o| (plant_counts(o, &cal, 0.0), false),
        None,
    );
    let p = Protocol::default();
    // Angle changes, as (time from press, new angle).
    let mut changes = Vec::new();
    for w in tr.outputs.windows(2) {
        if w[1].1.servo_deg != w[0].1.servo_deg {
            changes.push((w[1].0 - PRESS_US, w[1].1.servo_deg));
        }
    }
    let want: Vec<(u64, f32)> = (1..=p.levels() + 1)
        .map(|k| (p.step_start_ms(k) as u64 * 1000, p.angle_deg(k)))
        .collect();
    assert_eq!(changes.len(), want.len(), "{changes:?}");
    for ((t, a), (wt, wa)) in changes.iter().zip(&want) {
        assert!(t.abs_diff(*wt) <= 1_000, "step to {a} at {t} µs, want {wt}");
        assert_eq!(a, wa);
    }
    // Trigger: one pulse of exactly 500 ms, rising 1 s after the press.
    let high: Vec<u64> = tr
        .outputs
        .iter()
        .filter(|(_, o)| o.trigger)
        .map(|(t, _)| t - PRESS_US)
        .collect();
    assert_eq!(high.len(), 500);
    assert_eq!(high[0], 1_000_000);
    assert_eq!(*high.last().unwrap(), 1_499_000);
    // The run ends back at rest with the amplifier off, at 131.5 s.
    let (t_end, end) = tr.end.unwrap();
    assert_eq!(t_end - PRESS_US, 131_500_000);
    assert_eq!((end.pairs, end.fault), (12, None));
    let last = tr.outputs.last().unwrap().1;
    assert_eq!(
        (last.servo_deg, last.amp_control_v, last.trigger),
        (125.0, 0.0, false)
    );
}

#[test]
fn pairs_carry_the_window_means_and_times() {
    let mut rig = thesis_rig();
    let cal = Calibration::default();
    let tr = drive(
        &mut rig,
        &move |_, o| (plant_counts(o, &cal, 0.0), false),
        None,
    );
    let pairs = tr.sink.pairs();
    assert_eq!(pairs.len(), 12);
    for (i, p) in pairs.iter().enumerate() {
        let k = i as u32 + 1;
        let t1 = 0.1 + 0.3 * 5.0 * k as f32;
        assert_eq!(
            (p.step, p.level, p.angle_deg),
            (k, k, 125.0 - 5.0 * k as f32)
        );
        assert_eq!(p.t_mid_ms, 10_000 * k + 6_000);
        assert_eq!((p.t1.count, p.t2.count), (7_000, 7_000));
        assert!((p.t1.mean_n - t1).abs() < 0.0151, "{p:?}");
        assert!((p.t2.mean_n - 2.0 * t1).abs() < 0.0151, "{p:?}");
    }
}

#[test]
fn tare_removes_a_zero_drift_of_both_channels() {
    let mut rig = thesis_rig();
    let cal = Calibration::default();
    // Both sensors drifted by +37 counts (0.55 N) since they were calibrated.
    let tr = drive(
        &mut rig,
        &move |_, o| (plant_counts(o, &cal, 37.0), false),
        None,
    );
    let start = tr.sink.0.iter().find_map(|(_, r)| match r {
        Record::RunStart(s) => Some(*s),
        _ => None,
    });
    let start = start.expect("run start record");
    assert!(
        (start.calibration.t1.zero_counts - 437.0).abs() < 0.6,
        "{start:?}"
    );
    for (i, p) in tr.sink.pairs().iter().enumerate() {
        let t1 = 0.1 + 0.3 * 5.0 * (i + 1) as f32;
        assert!((p.t1.mean_n - t1).abs() < 0.0151, "{p:?}");
    }
    // Without the tare the same drift would have biased every pair by 0.55 N.
    let mut no_tare = Rig::new(
        Protocol {
            tare_ms: 0,
            ..Protocol::default()
        },
        cal.typed(),
        limits(),
    )
    .unwrap();
    let tr = drive(
        &mut no_tare,
        &move |_, o| (plant_counts(o, &cal, 37.0), false),
        None,
    );
    assert!(
        matches!(tr.sink.0[0].1, Record::RunStart(_)),
        "a run start even without a tare"
    );
    let bias = tr.sink.pairs()[0].t1.mean_n - (0.1 + 0.3 * 5.0);
    assert!((bias - 0.555).abs() < 0.01, "{bias}");
}

#[test]
fn updown_order_holds_each_level_once() {
    let p = Protocol {
        order: StepOrder::UpDown,
        ..Protocol::default()
    };
    let mut rig = Rig::new(p, Calibration::default().typed(), limits()).unwrap();
    let cal = Calibration::default();
    let tr = drive(
        &mut rig,
        &move |_, o| (plant_counts(o, &cal, 0.0), false),
        None,
    );
    let levels: Vec<u32> = tr.sink.pairs().iter().map(|p| p.level).collect();
    assert_eq!(levels, [1, 3, 5, 7, 9, 11, 12, 10, 8, 6, 4, 2]);
    for p in tr.sink.pairs() {
        let t1 = 0.1 + 0.3 * 5.0 * p.level as f32;
        assert!((p.t1.mean_n - t1).abs() < 0.0151, "{p:?}");
    }
}

#[test]
fn sequence_numbers_are_consecutive_and_records_are_ordered() {
    let mut rig = thesis_rig();
    let cal = Calibration::default();
    let tr = drive(
        &mut rig,
        &move |_, o| (plant_counts(o, &cal, 0.0), false),
        None,
    );
    for (i, (seq, _)) in tr.sink.0.iter().enumerate() {
        assert_eq!(*seq, i as u32);
    }
    assert!(matches!(tr.sink.0.first().unwrap().1, Record::RunStart(_)));
    assert!(matches!(tr.sink.0.last().unwrap().1, Record::RunEnd(_)));
    // 100 Hz raw log from the end of the tare (0.5 s) to the end of the run (131.5 s).
    let raws = tr
        .sink
        .0
        .iter()
        .filter(|(_, r)| matches!(r, Record::Raw(_)))
        .count();
    assert_eq!(raws, 13_101); // both ends included
}

/// Inject a fault at 45.2 s after the press (mid step 4) and check the rig's reaction.
fn fault_case(kind: FaultKind) {
    let cal = Calibration::default();
    let at = PRESS_US + 45_200_000;
    let script = move |t: u64, o: &Outputs| {
        let mut c = plant_counts(o, &cal, 0.0);
        let mut press = false;
        if t >= at {
            match kind {
                FaultKind::OverForce => c[1] = Ok(cal.t2.counts(48.0) as u16),
                FaultKind::CordBreak => c[1] = Ok(cal.t2.counts(0.0) as u16),
                FaultKind::SensorRail => c[0] = Ok(0),
                FaultKind::Abort => press = t < at + 40_000,
                FaultKind::NegativeForce => c[0] = Ok(cal.t1.counts(-4.0) as u16),
                _ => {}
            }
        }
        (c, press)
    };
    let mut rig = thesis_rig();
    let skip = (kind == FaultKind::Watchdog).then_some((at, at + 25_000));
    let tr = drive(&mut rig, &script, skip);
    let (t_end, end) = tr.end.expect("the run must end");
    assert_eq!(end.fault, Some(kind));
    // Safe within 20 ms of the fault: servo at rest, amplifier off, trigger low.
    let fault_at = if kind == FaultKind::Watchdog {
        at + 25_000
    } else {
        at
    };
    assert!(
        t_end - fault_at <= 20_000,
        "{kind:?}: safe after {} µs",
        t_end - fault_at
    );
    let last = tr.outputs.last().unwrap().1;
    assert_eq!(
        (last.servo_deg, last.amp_control_v, last.trigger),
        (125.0, 0.0, false)
    );
    // The fault record precedes the run end; the three pairs made before it are kept.
    let n = tr.sink.0.len();
    match (&tr.sink.0[n - 2].1, &tr.sink.0[n - 1].1) {
        (Record::Fault(f), Record::RunEnd(_)) => assert_eq!(f.kind, kind),
        other => panic!("{kind:?}: last records {other:?}"),
    }
    assert_eq!(tr.sink.pairs().len(), 3);
    assert_eq!(end.pairs, 3);
    // After the fault the rig idles safely until the next press.
    let mut sink = VecSink::default();
    let counts = [Ok(500), Ok(500)];
    let out = rig.step(
        &Inputs {
            now_us: t_end + 1000,
            counts,
            button_pressed: false,
            command: None,
        },
        &mut sink,
    );
    assert!(!rig.is_running());
    assert_eq!((out.servo_deg, out.amp_control_v), (125.0, 0.0));
}

#[test]
fn over_force_makes_the_rig_safe() {
    fault_case(FaultKind::OverForce);
}

#[test]
fn cord_break_makes_the_rig_safe() {
    fault_case(FaultKind::CordBreak);
}

#[test]
fn unplugged_sensor_makes_the_rig_safe() {
    fault_case(FaultKind::SensorRail);
}

#[test]
fn abort_button_makes_the_rig_safe() {
    fault_case(FaultKind::Abort);
}

#[test]
fn a_reversed_reading_makes_the_rig_safe() {
    fault_case(FaultKind::NegativeForce);
}

#[test]
fn missed_samples_trip_the_watchdog() {
    fault_case(FaultKind::Watchdog);
}

#[test]
fn invalid_protocol_is_never_run() {
    let bad = Protocol {
        step_deg: 7.0,
        ..Protocol::default()
    };
    assert!(Rig::new(bad, Calibration::default(), SafetyLimits::default()).is_err());
}
