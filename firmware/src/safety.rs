//! The safety supervisor: decides, sample by sample, whether the run must stop.
//!
//! It only decides; the rig (`rig.rs`) puts the hardware in its safe state (servo to rest,
//! amplifier to 0 V, trigger low) in the same sample period the fault is raised. Every check
//! needs a few consecutive bad samples, so one noisy conversion never stops a run, and the
//! longest of them (5 samples at 1 kHz) keeps detection well inside 20 ms.

use crate::hal::{AdcError, Channel, ADC_MAX_COUNTS};
use crate::record::{Fault, FaultKind};

/// Thresholds of the supervisor.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub struct SafetyLimits {
    /// Highest force on either channel, N (default 45).
    pub over_force_n: f32,
    /// Consecutive samples above it before the fault (default 3).
    pub over_force_samples: u16,
    /// A channel at or below this many counts is at the low rail (unplugged).
    pub rail_low_counts: u16,
    /// A channel at or above this many counts is at the high rail (shorted / saturated).
    pub rail_high_counts: u16,
    /// Consecutive rail (or failed) conversions before the fault (default 5).
    pub rail_samples: u16,
    /// The cord is broken when T2 < ratio × T1 ...
    pub cord_break_ratio: f32,
    /// ... while T1 is at least this, N ...
    pub cord_break_min_t1_n: f32,
    /// ... for this many consecutive samples. A cord that parted also shows as both channels
    /// below `cord_slack_n` (a free end carries nothing, and the turning capstan feeds the loose
    /// cord towards the servo, so T1 collapses with T2) for as many samples.
    pub cord_break_samples: u16,
    /// Both channels below this while a tension level is held: the cord parted, N (default
    /// 0.05; the lowest level holds T1 ≥ ~0.3 N and T2 above it).
    pub cord_slack_n: f32,
    /// Largest gap between two samples before the watchdog fault, µs (default 10 ms).
    pub max_sample_gap_us: u32,
}

impl Default for SafetyLimits {
    fn default() -> Self {
        SafetyLimits {
            over_force_n: 45.0,
            over_force_samples: 3,
            rail_low_counts: 4,
            rail_high_counts: ADC_MAX_COUNTS - 4,
            rail_samples: 5,
            cord_break_ratio: 0.3,
            cord_break_min_t1_n: 0.5,
            cord_break_samples: 5,
            cord_slack_n: 0.05,
            max_sample_gap_us: 10_000,
        }
    }
}

/// One sample as the supervisor sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SafetyInput {
    /// µs since the trigger.
    pub t_us: i64,
    /// Raw conversions, T1 then T2.
    pub counts: [Result<u16, AdcError>; 2],
    /// Calibrated forces, N (meaningless where the conversion failed).
    pub force_n: [f32; 2],
    /// The capstan is driven and a tension level is held: the cord-break checks are armed.
    pub cord_check_armed: bool,
}

/// Consecutive-sample counters of each check.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Supervisor {
    limits: SafetyLimits,
    over: [u16; 2],
    rail: [u16; 2],
    cord: u16,
    last_t_us: Option<i64>,
}

impl Supervisor {
    /// A supervisor with all counters clear.
    pub const fn new(limits: SafetyLimits) -> Self {
        Supervisor {
            limits,
            over: [0; 2],
            rail: [0; 2],
            cord: 0,
            last_t_us: None,
        }
    }

    /// Check one sample; a fault is returned the sample its condition is confirmed.
    pub fn check(&mut self, input: &SafetyInput) -> Option<Fault> {
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

#[cfg(test)]
mod tests {
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
}
