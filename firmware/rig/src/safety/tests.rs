//! The supervisor's checks, one by one, on scripted samples, and the visibility of both force
//! limits under a calibration.

use super::*;

fn input(t_us: i64, counts: [Result<u16, AdcError>; 2], force_n: [f32; 2]) -> SafetyInput {
    SafetyInput {
        t_us,
        counts,
        force_n,
        driven: None,
    }
}

fn feed(
    sup: &mut Supervisor,
    n: usize,
    c: [Result<u16, AdcError>; 2],
    f: [f32; 2],
) -> Option<(usize, Fault)> {
    (0..n).find_map(|i| sup.check(&input(i as i64 * 1000, c, f)).map(|x| (i, x)))
}

/// The context of a run at 0.015 N/count, tare reference 0.1 N, 12.7 mm capstan, 10 V,
/// `wrap_deg` of wrap (0: not given).
fn context(wrap_deg: f32) -> DriveContext {
    DriveContext {
        tare_reference_n: 0.1,
        n_per_count: [0.015; 2],
        zero_counts: [400.0; 2],
        capstan_radius_m: 6.35e-3,
        max_amplification: if wrap_deg > 0.0 {
            libm::expf(0.5 * wrap_deg.to_radians())
        } else {
            f32::INFINITY
        },
        drive_v: 10.0,
    }
}

/// A driven rig's supervisor.
fn driving(limits: SafetyLimits, wrap_deg: f32) -> Supervisor {
    let mut s = Supervisor::new(limits);
    s.drive(context(wrap_deg));
    s
}

/// A small deterministic noise: the sensors' ~1.3 counts sd, as integers.
struct Noise(u64);

impl Noise {
    fn counts(&mut self) -> i32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        // Sum of four uniform draws in -1..=1: sd ~1.15 counts.
        (0..4).map(|k| ((self.0 >> (8 * k)) % 3) as i32 - 1).sum()
    }
}

/// One driven sample at `t_ms` of true forces `f` (N) on a zero of 400 counts at
/// 0.015 N/count, with noise unless `frozen[k]` holds channel k at that count.
fn driven_sample(
    t_ms: i64,
    f: [f32; 2],
    noise: &mut Noise,
    frozen: [Option<u16>; 2],
    d: Driven,
) -> SafetyInput {
    let mut counts = [0u16; 2];
    for k in 0..2 {
        let c = 400.0 + f[k] / 0.015;
        counts[k] = frozen[k].unwrap_or((c.round() as i32 + noise.counts()) as u16);
    }
    SafetyInput {
        t_us: t_ms * 1000,
        counts: [Ok(counts[0]), Ok(counts[1])],
        force_n: counts.map(|c| (c as f32 - 400.0) * 0.015),
        driven: Some(d),
    }
}

fn at(servo_deg: f32, level_held: bool) -> Driven {
    Driven {
        servo_deg,
        at_rest: servo_deg == 125.0,
        level_held,
    }
}

#[test]
fn healthy_samples_raise_nothing() {
    let mut s = Supervisor::new(SafetyLimits::default());
    assert_eq!(
        feed(&mut s, 10_000, [Ok(1000), Ok(2000)], [9.0, 24.0]),
        None
    );
}

#[test]
fn over_force_needs_three_samples() {
    let mut s = Supervisor::new(SafetyLimits::default());
    let got = feed(&mut s, 10, [Ok(1000), Ok(3500)], [9.0, 46.5]).unwrap();
    assert_eq!(got.0, 2);
    assert_eq!(got.1.kind, FaultKind::OverForce);
    assert_eq!(got.1.channel, Some(Channel::T2));
    assert_eq!(got.1.value, 46.5);
}

#[test]
fn an_unplugged_sensor_at_the_real_adcs_floor_or_a_failing_one_is_a_rail_fault() {
    // An RP2040 reads 10-20 counts with its input grounded: that is an unplugged sensor.
    for floor in [0, 10, 20, 40] {
        let mut s = Supervisor::new(SafetyLimits::default());
        let got = feed(&mut s, 10, [Ok(floor), Ok(2000)], [-6.0, 24.0]).unwrap();
        assert_eq!(
            (got.0, got.1.kind, got.1.channel),
            (4, FaultKind::SensorRail, Some(Channel::T1)),
            "{floor}"
        );
    }
    let mut s = Supervisor::new(SafetyLimits::default());
    assert_eq!(feed(&mut s, 100, [Ok(41), Ok(2000)], [-2.9, 24.0]), None);
    let mut s = Supervisor::new(SafetyLimits::default());
    let got = feed(&mut s, 10, [Ok(1000), Err(AdcError)], [9.0, 0.0]).unwrap();
    assert_eq!(
        (got.1.kind, got.1.channel),
        (FaultKind::SensorRail, Some(Channel::T2))
    );
}

#[test]
fn cord_break_when_t2_collapses_under_held_t1() {
    let mut s = driving(SafetyLimits::default(), 0.0);
    let held = Some(at(100.0, true));
    let got = (0..10)
        .find_map(|t| {
            let mut i = input(t * 1000, [Ok(1000), Ok(410)], [9.0, 0.15]);
            i.driven = held;
            s.check(&i).map(|f| (t, f))
        })
        .unwrap();
    assert_eq!((got.0, got.1.kind), (4, FaultKind::CordBreak));
    // Not while no level is held, nor undriven (a tare, idle).
    for driven in [Some(at(100.0, false)), None] {
        let mut s = driving(SafetyLimits::default(), 0.0);
        for t in 0..10 {
            let mut i = input(t * 1000, [Ok(1000), Ok(410)], [9.0, 0.15]);
            i.driven = driven;
            assert_eq!(s.check(&i), None);
        }
    }
}

#[test]
fn a_parted_cord_reads_at_or_below_the_tare_whatever_its_preload() {
    // The tare read the preload P as the reference R = 0.1 N: a parted cord reads R − P, for
    // P = 0.1, 0.02 and 0 N; the lowest level reads R − P + ≥ 0.25 N on T1 and more on T2.
    let l = SafetyLimits::default();
    for p in [0.1, 0.02, 0.0] {
        let mut s = driving(l, 0.0);
        let mut noise = Noise(7);
        let got = (0..20).find_map(|t| {
            let i = driven_sample(
                t,
                [0.1 - p, 0.1 - p],
                &mut noise,
                [None; 2],
                at(120.0, true),
            );
            s.check(&i).map(|f| (t, f))
        });
        assert_eq!(
            got.map(|g| (g.0, g.1.kind)),
            Some((4, FaultKind::CordBreak)),
            "{p}"
        );
        let mut s = driving(l, 0.0);
        let healthy = (0..2_000).find_map(|t| {
            let f = [0.1 - p + 0.26, 0.1 - p + 0.26 * 4.24];
            s.check(&driven_sample(t, f, &mut noise, [None; 2], at(120.0, true)))
        });
        assert_eq!(healthy, None, "{p}");
    }
}

#[test]
fn a_late_sample_trips_the_watchdog() {
    let mut s = Supervisor::new(SafetyLimits::default());
    let ok = [Ok(1000), Ok(2000)];
    assert_eq!(s.check(&input(0, ok, [9.0, 24.0])), None);
    assert_eq!(s.check(&input(1_000, ok, [9.0, 24.0])), None);
    let f = s.check(&input(16_000, ok, [9.0, 24.0])).unwrap();
    assert_eq!(f.kind, FaultKind::Watchdog);
    assert_eq!(f.value, 15.0);
}

#[test]
fn a_reading_far_below_zero_is_a_fault() {
    // A reversed sensor reads a rising tension as a falling one: over-force blind.
    let mut s = Supervisor::new(SafetyLimits::default());
    let got = feed(&mut s, 10, [Ok(150), Ok(2000)], [-3.75, 24.0]).unwrap();
    assert_eq!(
        (got.0, got.1.kind, got.1.channel),
        (2, FaultKind::NegativeForce, Some(Channel::T1))
    );
    // Offsets and noise around zero are not.
    let mut s = Supervisor::new(SafetyLimits::default());
    assert_eq!(feed(&mut s, 100, [Ok(330), Ok(530)], [-1.2, 2.0]), None);
}

#[test]
fn a_channel_that_holds_one_count_while_driven_is_frozen() {
    let l = SafetyLimits::default();
    let mut s = driving(l, 0.0);
    let mut noise = Noise(3);
    let got = (0..2_000)
        .find_map(|t| {
            let frozen = [None, (t >= 100).then_some(1_100)];
            let i = driven_sample(t, [2.0, 4.0], &mut noise, frozen, at(120.0, false));
            s.check(&i).map(|f| (t, f))
        })
        .unwrap();
    assert_eq!(
        (got.1.kind, got.1.channel, got.1.value),
        (FaultKind::SensorFrozen, Some(Channel::T2), 1_100.0)
    );
    // 500 samples of the same count, the first at 100 ms.
    assert_eq!(got.0, 100 + 499);
    // Not idle (the capstan stopped, a tare), nor with the check off.
    let mut s = Supervisor::new(l);
    assert_eq!(feed(&mut s, 2_000, [Ok(1000), Ok(1100)], [9.0, 10.5]), None);
    let mut s = driving(
        SafetyLimits {
            stuck_samples: 0,
            ..l
        },
        0.0,
    );
    let frozen = [Some(533), Some(666)];
    assert!((0..2_000).all(|t| {
        s.check(&driven_sample(
            t,
            [2.0, 4.0],
            &mut noise,
            frozen,
            at(120.0, false),
        ))
        .is_none()
    }));
}

/// A run's step from 125° (rest) to 120° at 1000 ms, T1 1 → `t1_after` N, T2 2 → `t2_after`
/// N, each channel frozen at its count before the step if asked; the first fault.
fn a_step(t1_after: f32, t2_after: f32, frozen: [bool; 2]) -> Option<(i64, Fault)> {
    let mut s = driving(SafetyLimits::default(), 0.0);
    let mut noise = Noise(11);
    (0..3_000).find_map(|t| {
        let (deg, f) = if t < 1_000 {
            (125.0, [1.0, 2.0])
        } else {
            (120.0, [t1_after, t2_after])
        };
        let hold = |k: usize, n: f32| {
            (frozen[k] && t >= 1_000).then_some((400.0 + n / 0.015).round() as u16)
        };
        let fr = [hold(0, 1.0), hold(1, 2.0)];
        // (No level held: the slack check would take a servo that did not pull first.)
        let i = driven_sample(t, f, &mut noise, fr, at(deg, false));
        s.check(&i).map(|x| (t, x))
    })
}

#[test]
fn each_channel_must_answer_a_servo_step() {
    // Both answer: nothing.
    assert_eq!(a_step(1.35, 2.74, [false; 2]), None);
    // With no noise of its own the frozen channel's answer is decided at the block
    // 300-400 ms after the step; the stuck check would take 500 ms.
    let t2 = a_step(1.35, 2.74, [false, true]).unwrap();
    assert_eq!(
        (t2.0, t2.1.kind, t2.1.channel),
        (1_399, FaultKind::SensorFrozen, Some(Channel::T2))
    );
    let t1 = a_step(1.35, 2.74, [true, false]).unwrap();
    assert_eq!(
        (t1.1.kind, t1.1.channel),
        (FaultKind::SensorFrozen, Some(Channel::T1))
    );
    // The servo did not follow: neither moved.
    let stall = a_step(1.0, 2.0, [false; 2]).unwrap();
    assert_eq!((stall.0, stall.1.kind), (1_399, FaultKind::ServoStall));
    // T1 fell where the servo pulled, T2 rose: T1 reads reversed.
    let against = a_step(0.7, 2.2, [false; 2]).unwrap();
    assert_eq!(against.1.kind, FaultKind::Implausible);
    assert_eq!(against.1.channel, Some(Channel::T1));
    // T1 fell and T2 did not move: the servo did not follow.
    let against = a_step(0.7, 2.0, [false; 2]).unwrap();
    assert_eq!(against.1.kind, FaultKind::ServoStall);
}

#[test]
fn a_cord_parting_at_rest_is_caught_from_the_drop_of_both_channels() {
    // Step 0: the servo at rest, the drive on; the preload 0.1 N reads as the reference on
    // both, the drive lowers T1 and raises T2 (0.057 and 0.118 N at 360°). It parts at 3 s.
    let l = SafetyLimits::default();
    let mut s = driving(l, 0.0);
    let mut noise = Noise(5);
    let got = (0..10_000)
        .find_map(|t| {
            let f = if t < 3_000 {
                [0.057, 0.118]
            } else {
                [0.0, 0.0]
            };
            let i = driven_sample(t, f, &mut noise, [None; 2], at(125.0, false));
            s.check(&i).map(|x| (t, x))
        })
        .unwrap();
    assert_eq!(got.1.kind, FaultKind::CordBreak);
    assert!(got.0 >= 3_000 && got.0 <= 3_300, "{got:?}");
    // A slow drift of the same size over 10 s is not a break.
    let mut s = driving(l, 0.0);
    let none = (0..12_000).find_map(|t| {
        let d = 0.2 * (t as f32 / 12_000.0);
        let f = [0.057 - d / 2.0, 0.118 - d / 2.0];
        s.check(&driven_sample(
            t,
            f,
            &mut noise,
            [None; 2],
            at(125.0, false),
        ))
    });
    assert_eq!(none, None);
}

#[test]
fn a_load_at_the_motors_stall_torque_is_a_stalled_motor() {
    // The thesis-as-written motor (46.5 Ω): 0.18 N m of stall torque at 10 V; on the 12.7 mm
    // capstan, T2 − T1 of 28.3 N.
    let l = SafetyLimits {
        motor_nm_per_v: 19.7 * 0.0612 / 46.5,
        ..SafetyLimits::default()
    };
    let mut s = driving(l, 0.0);
    let mut noise = Noise(9);
    let got = (0..1_000)
        .find_map(|t| {
            let i = driven_sample(t, [10.0, 38.0], &mut noise, [None; 2], at(80.0, true));
            s.check(&i).map(|x| (t, x))
        })
        .unwrap();
    assert_eq!((got.0, got.1.kind), (99, FaultKind::MotorStall));
    assert!((got.1.value - 28.0 * 6.35e-3).abs() < 0.002, "{got:?}");
    // The board's motor (4.65 Ω) turns that load without stalling.
    let mut s = driving(SafetyLimits::default(), 0.0);
    assert!((0..1_000).all(|t| s
        .check(&driven_sample(
            t,
            [10.0, 38.0],
            &mut noise,
            [None; 2],
            at(80.0, true)
        ))
        .is_none()));
}

#[test]
fn t2_beyond_what_the_capstan_can_make_of_t1_is_implausible() {
    // 90° at μ up to 0.5: T2 ≤ 2.19 × (T1 + 3 N) + 3 N, each reading 3 N off at most.
    let mut s = driving(SafetyLimits::default(), 90.0);
    let mut noise = Noise(13);
    let got = (0..100).find_map(|t| {
        let i = driven_sample(t, [2.0, 14.5], &mut noise, [None; 2], at(120.0, true));
        s.check(&i).map(|x| (t, x))
    });
    assert_eq!(got.map(|g| g.1.kind), Some(FaultKind::Implausible));
    let mut s = driving(SafetyLimits::default(), 90.0);
    assert!((0..100).all(|t| s
        .check(&driven_sample(
            t,
            [2.0, 13.4],
            &mut noise,
            [None; 2],
            at(120.0, true)
        ))
        .is_none()));
    // A T1 that reads 3 N low at the first level (the catalogue's `t1_offset` at its limit:
    // T1 1.5 N reads -1.5 N, T2 2.6 N at 270°) is not.
    let mut s = driving(SafetyLimits::default(), 270.0);
    assert!((0..100).all(|t| s
        .check(&driven_sample(
            t,
            [-1.5, 2.6],
            &mut noise,
            [None; 2],
            at(120.0, true)
        ))
        .is_none()));
    // Without the wrap there is no bound.
    let mut s = driving(SafetyLimits::default(), 0.0);
    assert!((0..100).all(|t| s
        .check(&driven_sample(
            t,
            [2.0, 9.0],
            &mut noise,
            [None; 2],
            at(120.0, true)
        ))
        .is_none()));
}

#[test]
fn a_calibration_is_visible_only_if_both_limits_read_inside_the_rail_checks() {
    use crate::calib::{Calibration, ChannelCal};
    let l = SafetyLimits::default();
    // The default: 45 N at 3400 counts, rail check at 3900; -3 N at 200 counts, above 40.
    assert_eq!(l.visible(&Calibration::default()), Ok(()));
    let with = |t1: ChannelCal| Calibration {
        t1,
        ..Calibration::default()
    };
    // The hardware chapter's 0.01253 N/count with a 0.5 V zero (400 counts): 45 N at 3991 counts,
    // above where the divider saturates: blind.
    let b = l
        .visible(&with(ChannelCal::placeholder(400.0, 0.01253)))
        .unwrap_err();
    assert_eq!(b.channel, Channel::T1);
    assert!((b.readable_n - 43.34).abs() < 0.01, "{b:?}");
    // A sensitivity typed ten times low.
    assert!(l
        .visible(&with(ChannelCal::placeholder(400.0, 0.0015)))
        .is_err());
    // A zero moved up by a preload of 6 N at 0.015 N/count.
    assert!(l
        .visible(&with(ChannelCal::placeholder(800.0, 0.015)))
        .is_ok());
    assert!(l
        .visible(&with(ChannelCal::placeholder(900.0, 0.015)))
        .is_err());
    // A 0-5 V sensor at 0 V: its zero at the ADC's floor, where an unplugged one reads. The
    // lowest zero at 0.015 N/count is 281 counts.
    let low = l
        .visible(&with(ChannelCal::placeholder(15.0, 0.015)))
        .unwrap_err();
    assert!(low.readable_n > -3.0, "{low:?}");
    assert_eq!(l.min_zero_counts(0.015), 281.0);
    assert!(l
        .visible(&with(ChannelCal::placeholder(281.5, 0.015)))
        .is_ok());
    assert!(l
        .visible(&with(ChannelCal::placeholder(280.5, 0.015)))
        .is_err());
    // NaN never passes.
    assert!(l
        .visible(&with(ChannelCal::placeholder(f32::NAN, 0.015)))
        .is_err());
}
