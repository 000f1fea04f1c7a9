//! The safety supervisor: decides, sample by sample, whether the rig must go safe.
//!
//! It only decides; the rig (`rig.rs`) puts the hardware in its safe state (servo to rest,
//! amplifier to 0 V, trigger low) in the same sample period the fault is raised. It runs in
//! every state: runs, idle (homing and a latched fault included) and setup mode. Every check
//! needs a few consecutive bad samples, so one noisy conversion never stops a run, and the
//! longest of them (5 samples at 1 kHz) keeps detection well inside 20 ms.
//!
//! Also here: [`SafetyLimits::visible`], the condition a calibration must meet for the
//! over-force check to hold by construction (the limit reads below the rail check), checked
//! wherever a calibration comes in (`set`, `weigh`, `zero`, the flash) and after every tare.

use crate::hal::{AdcError, Channel};
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
    /// A channel at or above this many counts is at the high rail (shorted or saturated).
    /// Must be below the highest reading a sensor can produce: a 0-5 V sensor behind the
    /// board's 10k/18k divider saturates at ~3990 counts (3.21 V; 3910 with a 2 % high
    /// ADC_VREF), so the default 3900 makes a sensor pinned at its output's rail a rail
    /// fault, never a blind spot between saturation and the check (default 3900).
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
    /// A channel reading below −this, N, for `over_force_samples` samples is a fault
    /// (`negative_force`): a cord cannot push, so the sensor is reversed or its zero is wrong,
    /// and a reversed sensor would hide any over-force (default 3).
    pub negative_force_n: f32,
}

/// The over-force limit must read at least this many counts below the rail check
/// ([`SafetyLimits::visible`]): 1 % of the ADC's range.
pub const VISIBLE_MARGIN_COUNTS: f32 = 41.0;

/// A calibration under which the over-force check could not trip: on `channel`, the highest
/// force the rig can read before the rail check is `readable_n`, below the limit (with
/// [`VISIBLE_MARGIN_COUNTS`]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub struct Blind {
    /// The channel that cannot show the limit.
    pub channel: Channel,
    /// The force it reads at the rail check less the margin, N.
    pub readable_n: f32,
}

impl Default for SafetyLimits {
    fn default() -> Self {
        SafetyLimits {
            over_force_n: 45.0,
            over_force_samples: 3,
            rail_low_counts: 4,
            rail_high_counts: 3_900,
            rail_samples: 5,
            cord_break_ratio: 0.3,
            cord_break_min_t1_n: 0.5,
            cord_break_samples: 5,
            cord_slack_n: 0.05,
            max_sample_gap_us: 10_000,
            negative_force_n: 3.0,
        }
    }
}

impl SafetyLimits {
    /// The over-force check holds by construction under `cal`: on each channel the limit
    /// reads at least [`VISIBLE_MARGIN_COUNTS`] below the rail check, so a force at the limit
    /// is either read as one (over-force) or pins the sensor (rail). `Err` names the first
    /// channel where it does not (a sensitivity typed too low, a zero too high, a sensor whose
    /// range ends below the limit). Only a true calibration makes the reading true: `weigh`
    /// measures the sensitivity, the tare checks the zero ([`crate::rig::TARE_MAX_N`]).
    pub fn visible(&self, cal: &crate::calib::Calibration) -> Result<(), Blind> {
        let top = self.rail_high_counts as f32 - VISIBLE_MARGIN_COUNTS;
        for (channel, ch) in [(Channel::T1, &cal.t1), (Channel::T2, &cal.t2)] {
            let readable_n = (top - ch.zero_counts) * ch.n_per_count;
            if readable_n.is_nan() || readable_n < self.over_force_n {
                return Err(Blind {
                    channel,
                    readable_n,
                });
            }
        }
        Ok(())
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
    neg: [u16; 2],
    rail: [u16; 2],
    cord: u16,
    last_t_us: Option<i64>,
    /// The last sample went through every check without a fault and left every counter clear
    /// (so every check needs at least one bad sample): a sample on which no check's condition
    /// holds then leaves everything as it is and raises nothing (the common case, which
    /// [`Supervisor::check`] decides without the counters on the host).
    #[cfg(not(target_os = "none"))]
    quiet: bool,
    /// The counts off the rails, `rail_low_counts < c < rail_high_counts`, as one unsigned
    /// comparison: `c - off_rail_from < off_rail_span` (wrapping; see [`Supervisor::new`]).
    #[cfg(not(target_os = "none"))]
    off_rail_from: u16,
    #[cfg(not(target_os = "none"))]
    off_rail_span: u16,
}

impl Supervisor {
    /// A supervisor with all counters clear.
    pub const fn new(limits: SafetyLimits) -> Self {
        Supervisor {
            limits,
            over: [0; 2],
            neg: [0; 2],
            rail: [0; 2],
            cord: 0,
            last_t_us: None,
            #[cfg(not(target_os = "none"))]
            quiet: false,
            // The range low + 1 .. high: `c - (low + 1)`, wrapping, is below its length
            // exactly for the counts in it (below low + 1 it wraps to at least
            // 65 536 − (low + 1), which is at least the length). Empty (length 0, nothing off
            // the rails) when high ≤ low + 1, low = 65 535 (where low + 1 wraps to 0) included.
            #[cfg(not(target_os = "none"))]
            off_rail_from: limits.rail_low_counts.wrapping_add(1),
            #[cfg(not(target_os = "none"))]
            off_rail_span: limits
                .rail_high_counts
                .saturating_sub(limits.rail_low_counts)
                .saturating_sub(1),
        }
    }

    /// Check one sample; a fault is returned the sample its condition is confirmed.
    // The host simulator runs this for every simulated sample: there the common case is decided
    // first, inlined into the sample path, and the counters are out of line. On the board it
    // stays the one function of every check it always was: the common case would cost it ~250
    // bytes of flash (soft-float comparisons), and save it no time (the same comparisons).
    #[cfg_attr(not(target_os = "none"), inline)]
    pub fn check(&mut self, input: &SafetyInput) -> Option<Fault> {
        if let Some(last) = self.last_t_us.replace(input.t_us) {
            let gap_us = input.t_us - last;
            if gap_us > self.limits.max_sample_gap_us as i64 {
                return Some(Fault {
                    kind: FaultKind::Watchdog,
                    channel: None,
                    value: gap_us as f32 / 1000.0,
                    t_us: input.t_us,
                });
            }
        }
        #[cfg(not(target_os = "none"))]
        {
            if self.quiet && self.healthy(input) {
                return None;
            }
            // The out-of-line counters get a copy of their own: the sample's fields then never
            // have to be in memory on the common path above (inlined into the sample loop,
            // the caller's `SafetyInput` is only read, and stays in registers).
            let input = *input;
            self.count(&input)
        }
        #[cfg(target_os = "none")]
        self.count(input)
    }

    /// No check's condition holds on this sample: both conversions done and off the rails, no
    /// force over the limit, the cord not collapsed (the conditions of [`Supervisor::count`]).
    /// With every counter clear, `count` would then keep them clear and raise nothing.
    #[cfg(not(target_os = "none"))]
    #[inline(always)]
    fn healthy(&self, input: &SafetyInput) -> bool {
        let [Ok(c1), Ok(c2)] = input.counts else {
            return false;
        };
        let l = &self.limits;
        let [t1, t2] = input.force_n;
        // (`c > l.rail_low_counts && c < l.rail_high_counts`, in one comparison: see `new`.)
        let off_rail = |c: u16| c.wrapping_sub(self.off_rail_from) < self.off_rail_span;
        let over = |f: f32| f > l.over_force_n || f < -l.negative_force_n;
        off_rail(c1)
            && off_rail(c2)
            && !over(t1)
            && !over(t2)
            && !(input.cord_check_armed
                && ((t1 >= l.cord_break_min_t1_n && t2 < l.cord_break_ratio * t1)
                    || (t1 < l.cord_slack_n && t2 < l.cord_slack_n)))
    }

    /// Every check with its counter, after the watchdog check.
    #[cfg_attr(not(target_os = "none"), inline(never))]
    #[cfg_attr(target_os = "none", inline)]
    fn count(&mut self, input: &SafetyInput) -> Option<Fault> {
        // Not until this sample has gone through without a fault and left every counter clear.
        #[cfg(not(target_os = "none"))]
        {
            self.quiet = false;
        }
        let l = &self.limits;
        let fault = |kind, channel, value| {
            Some(Fault {
                kind,
                channel,
                value,
                t_us: input.t_us,
            })
        };
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
        // No fault: every sample limit is above its counter, so at least one.
        #[cfg(not(target_os = "none"))]
        {
            self.quiet =
                self.rail == [0; 2] && self.over == [0; 2] && self.neg == [0; 2] && self.cord == 0;
        }
        None
    }
}

#[cfg(test)]
mod tests;
