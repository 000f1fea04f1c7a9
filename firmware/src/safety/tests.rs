//! The supervisor's checks, one by one, against a one-pass reference, and the visibility of
//! the over-force limit under a calibration.

use super::*;

fn input(t_us: i64, counts: [Result<u16, AdcError>; 2], force_n: [f32; 2]) -> SafetyInput {
    SafetyInput {
        t_us,
        counts,
        force_n,
        cord_check_armed: true,
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

#[test]
fn off_the_rails_in_one_comparison_is_the_two() {
    for (low, high) in [
        (4, 4091),
        (0, u16::MAX),
        (0, 0),
        (5, 6),
        (5, 7),
        (3000, 2000),
    ]
    .into_iter()
    .chain([
        (u16::MAX, 0),
        (u16::MAX, u16::MAX),
        (u16::MAX - 1, u16::MAX),
    ]) {
        let s = Supervisor::new(SafetyLimits {
            rail_low_counts: low,
            rail_high_counts: high,
            ..SafetyLimits::default()
        });
        for c in 0..=u16::MAX {
            let one = c.wrapping_sub(s.off_rail_from) < s.off_rail_span;
            assert_eq!(one, c > low && c < high, "{c} in {low}..{high}");
        }
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
fn unplugged_or_failing_sensor_is_a_rail_fault() {
    let mut s = Supervisor::new(SafetyLimits::default());
    let got = feed(&mut s, 10, [Ok(0), Ok(2000)], [-6.0, 24.0]).unwrap();
    assert_eq!(
        (got.0, got.1.kind, got.1.channel),
        (4, FaultKind::SensorRail, Some(Channel::T1))
    );
    let mut s = Supervisor::new(SafetyLimits::default());
    let got = feed(&mut s, 10, [Ok(1000), Err(AdcError)], [9.0, 0.0]).unwrap();
    assert_eq!(
        (got.1.kind, got.1.channel),
        (FaultKind::SensorRail, Some(Channel::T2))
    );
}

#[test]
fn cord_break_when_t2_collapses_under_held_t1() {
    let mut s = Supervisor::new(SafetyLimits::default());
    let got = feed(&mut s, 10, [Ok(1000), Ok(410)], [9.0, 0.15]).unwrap();
    assert_eq!((got.0, got.1.kind), (4, FaultKind::CordBreak));
    // Not armed (capstan stopped, tare): no fault.
    let mut s = Supervisor::new(SafetyLimits::default());
    let mut i = input(0, [Ok(1000), Ok(410)], [9.0, 0.15]);
    i.cord_check_armed = false;
    for t in 0..10 {
        i.t_us = t * 1000;
        assert_eq!(s.check(&i), None);
    }
    // Low tension with amplification near one is not a break.
    let mut s = Supervisor::new(SafetyLimits::default());
    assert_eq!(feed(&mut s, 100, [Ok(430), Ok(428)], [0.45, 0.42]), None);
}

#[test]
fn cord_break_when_both_sides_go_slack_under_a_held_level() {
    // The cord parted: neither side carries anything (± noise).
    let mut s = Supervisor::new(SafetyLimits::default());
    let got = feed(&mut s, 10, [Ok(401), Ok(399)], [0.01, -0.02]).unwrap();
    assert_eq!((got.0, got.1.kind), (4, FaultKind::CordBreak));
    // Not while no level is held (rest, tare, between runs).
    let mut s = Supervisor::new(SafetyLimits::default());
    let mut i = input(0, [Ok(401), Ok(399)], [0.01, -0.02]);
    i.cord_check_armed = false;
    for t in 0..10 {
        i.t_us = t * 1000;
        assert_eq!(s.check(&i), None);
    }
    // The lowest level at the smallest wrap is well clear of it.
    let mut s = Supervisor::new(SafetyLimits::default());
    assert_eq!(feed(&mut s, 100, [Ok(420), Ok(435)], [0.3, 0.52]), None);
}

/// The supervisor as it was written before its fast path: one pass over every check and
/// counter on every sample. `Supervisor::check` must decide exactly as this does.
struct Reference {
    limits: SafetyLimits,
    over: [u16; 2],
    neg: [u16; 2],
    rail: [u16; 2],
    cord: u16,
    last_t_us: Option<i64>,
}

impl Reference {
    fn check(&mut self, input: &SafetyInput) -> Option<Fault> {
        let l = &self.limits;
        let fault = |kind, channel, value| {
            Some(Fault {
                kind,
                channel,
                value,
                t_us: input.t_us,
            })
        };
        if let Some(last) = self.last_t_us.replace(input.t_us) {
            let gap_us = input.t_us - last;
            if gap_us > l.max_sample_gap_us as i64 {
                return fault(FaultKind::Watchdog, None, gap_us as f32 / 1000.0);
            }
        }
        for ch in Channel::BOTH {
            let i = ch as usize;
            let at_rail = match input.counts[i] {
                Ok(c) => c <= l.rail_low_counts || c >= l.rail_high_counts,
                Err(AdcError) => true,
            };
            self.rail[i] = if at_rail { self.rail[i] + 1 } else { 0 };
            if self.rail[i] >= l.rail_samples {
                let value = input.counts[i].map(f32::from).unwrap_or(f32::NAN);
                return fault(FaultKind::SensorRail, Some(ch), value);
            }
            let f = input.force_n[i];
            let over = !at_rail && f > l.over_force_n;
            self.over[i] = if over { self.over[i] + 1 } else { 0 };
            if self.over[i] >= l.over_force_samples {
                return fault(FaultKind::OverForce, Some(ch), f);
            }
            let negative = !at_rail && f < -l.negative_force_n;
            self.neg[i] = if negative { self.neg[i] + 1 } else { 0 };
            if self.neg[i] >= l.over_force_samples {
                return fault(FaultKind::NegativeForce, Some(ch), f);
            }
        }
        let [t1, t2] = input.force_n;
        let collapsed = input.cord_check_armed
            && input.counts.iter().all(|c| c.is_ok())
            && ((t1 >= l.cord_break_min_t1_n && t2 < l.cord_break_ratio * t1)
                || (t1 < l.cord_slack_n && t2 < l.cord_slack_n));
        self.cord = if collapsed { self.cord + 1 } else { 0 };
        if self.cord >= l.cord_break_samples {
            return fault(FaultKind::CordBreak, Some(Channel::T2), t2);
        }
        None
    }
}

/// Random streams of samples — healthy ones, and runs of rail, failed, over-force,
/// collapsed, slack, NaN and late samples — under the default limits and under odd ones
/// (zero sample counts, empty rail windows): the same fault on the same sample, with the
/// same counters, as the reference.
#[test]
fn decides_exactly_as_the_one_pass_reference() {
    let mut x: u64 = 0x2545_f491_4f6c_dd1d;
    let mut next = move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x
    };
    let mut faults = 0;
    for limits in limit_sets() {
        for _stream in 0..300 {
            let mut sup = Supervisor::new(limits);
            let mut reference = Reference {
                limits,
                over: [0; 2],
                neg: [0; 2],
                rail: [0; 2],
                cord: 0,
                last_t_us: None,
            };
            let mut t_us = 0i64;
            // Each stream holds one kind of sample for a while, then switches.
            let mut kind = 0;
            for _ in 0..400 {
                let r = next();
                if r % 16 == 0 {
                    kind = (r >> 8) % 11;
                }
                t_us += if (r >> 20) % 997 == 0 { 12_000 } else { 1_000 };
                let input = random_sample(kind, r, t_us, &mut next);
                let got = sup.check(&input);
                let want = reference.check(&input);
                // NaN values compare by their bits.
                let bits =
                    |f: Option<Fault>| f.map(|f| (f.kind, f.channel, f.value.to_bits(), f.t_us));
                assert_eq!(bits(got), bits(want), "{limits:?} {input:?}");
                assert_eq!(
                    (sup.rail, sup.over, sup.neg, sup.cord, sup.last_t_us),
                    (
                        reference.rail,
                        reference.over,
                        reference.neg,
                        reference.cord,
                        reference.last_t_us
                    ),
                    "{limits:?} {input:?}"
                );
                if got.is_some() {
                    faults += 1;
                    break;
                }
            }
        }
    }
    // The streams reach the faults, not only the healthy path.
    assert!(faults > 1000, "{faults}");
}

/// The limits the supervisor is compared with the reference under: the defaults and their
/// edges (checks that trip at once, empty and inverted rail ranges, long counts).
fn limit_sets() -> [SafetyLimits; 9] {
    let default = SafetyLimits::default();
    [
        default,
        SafetyLimits {
            rail_samples: 0,
            ..default
        },
        SafetyLimits {
            over_force_samples: 0,
            ..default
        },
        SafetyLimits {
            cord_break_samples: 0,
            ..default
        },
        SafetyLimits {
            rail_samples: 1,
            over_force_samples: 1,
            cord_break_samples: 1,
            ..default
        },
        SafetyLimits {
            rail_low_counts: 3000,
            rail_high_counts: 2000,
            ..default
        },
        SafetyLimits {
            rail_low_counts: 1999,
            rail_high_counts: 2000,
            ..default
        },
        SafetyLimits {
            rail_low_counts: u16::MAX,
            rail_high_counts: 0,
            ..default
        },
        SafetyLimits {
            rail_samples: 40,
            over_force_samples: 40,
            cord_break_samples: 40,
            ..default
        },
    ]
}

/// A random sample of one kind (0: healthy; 1, 2: at a rail; 3: failed conversions; 4: over
/// force; 5, 6, 8: a cord collapsing; 7: NaN; 9: negative force), at `t_us`.
fn random_sample(kind: u64, r: u64, t_us: i64, next: &mut impl FnMut() -> u64) -> SafetyInput {
    let count = |r: u64| -> Result<u16, AdcError> {
        match (kind, r % 8) {
            (1, 0..=5) => Ok((r >> 3) as u16 % 6),
            (2, 0..=5) => Ok(4095 - (r >> 3) as u16 % 6),
            (3, 0..=2) => Err(AdcError),
            _ => Ok(400 + (r >> 3) as u16 % 3000),
        }
    };
    let counts = [count(next()), count(next())];
    let f = |r: u64| (r % 5000) as f32 / 100.0 - 1.0;
    let mut force_n = [f(next()), f(next())];
    match kind {
        4 => force_n[(r >> 30) as usize % 2] = 45.0 + (r >> 40) as f32 % 3.0,
        9 => force_n[(r >> 30) as usize % 2] = -2.0 - (r >> 40) as f32 % 3.0,
        5 => force_n = [9.0, 0.15 + (r >> 40) as f32 % 4.0],
        6 => force_n = [0.01, -0.02 + ((r >> 40) % 2) as f32 * 0.07],
        7 => force_n[(r >> 30) as usize % 2] = f32::NAN,
        8 => force_n = [0.5, 0.15],
        _ => {}
    }
    SafetyInput {
        t_us,
        counts,
        force_n,
        cord_check_armed: !(r >> 50).is_multiple_of(4),
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
fn a_calibration_is_visible_only_if_the_limit_reads_below_the_rail_check() {
    use crate::calib::{Calibration, ChannelCal};
    let l = SafetyLimits::default();
    // The default: 45 N at 3400 counts, rail check at 3900.
    assert_eq!(l.visible(&Calibration::default()), Ok(()));
    let with = |t1: ChannelCal| Calibration {
        t1,
        ..Calibration::default()
    };
    // The README's 0.01253 N/count with a 0.5 V zero (400 counts): 45 N at 3991 counts,
    // above where the divider saturates: blind.
    let readme = ChannelCal {
        zero_counts: 400.0,
        n_per_count: 0.01253,
    };
    let b = l.visible(&with(readme)).unwrap_err();
    assert_eq!(b.channel, Channel::T1);
    assert!((b.readable_n - 43.34).abs() < 0.01, "{b:?}");
    // A sensitivity typed ten times low.
    let typo = ChannelCal {
        zero_counts: 400.0,
        n_per_count: 0.0015,
    };
    assert!(l.visible(&with(typo)).is_err());
    // A zero moved up by a preload of 6 N at 0.015 N/count.
    let preloaded = ChannelCal {
        zero_counts: 800.0,
        n_per_count: 0.015,
    };
    assert!(l.visible(&with(preloaded)).is_ok());
    let preloaded = ChannelCal {
        zero_counts: 900.0,
        n_per_count: 0.015,
    };
    assert!(l.visible(&with(preloaded)).is_err());
    // NaN never passes.
    let nan = ChannelCal {
        zero_counts: f32::NAN,
        n_per_count: 0.015,
    };
    assert!(l.visible(&with(nan)).is_err());
}
