//! The safety supervisor: decides, sample by sample, whether the rig must go safe.
//!
//! It only decides; the rig (`rig.rs`) puts the hardware in its safe state (servo to rest,
//! amplifier to 0 V, trigger low) in the same sample period the fault is raised. It runs in
//! every state: runs, idle (homing and a latched fault included) and setup mode. Every
//! sample's check needs a few consecutive bad samples, so one noisy conversion never stops a
//! run, and the longest of them (5 samples at 1 kHz) keeps detection well inside 20 ms.
//!
//! While the capstan is driven ([`SafetyInput::driven`]), it also asks whether each channel is
//! a sensor on a driven cord and the cord is whole (`safety/plausible.rs`): noise, the answer
//! to every servo step, a cord parting at rest, the motor's load. Any mode that drives the
//! capstan feeds it the same way: this is the one implementation of every check, on the board
//! and in the simulator alike.
//!
//! Also here: [`SafetyLimits::visible`], the condition a calibration must meet for the force
//! checks to hold by construction (both limits read inside the rail checks), checked wherever
//! a calibration comes in (`set`, `weigh`, `zero`, the flash) and after every tare.

use crate::hal::{AdcError, Channel};
use crate::record::{Fault, FaultKind};

mod limits;
mod plausible;

pub use limits::{Blind, SafetyLimits, VISIBLE_MARGIN_COUNTS};
pub use plausible::{DriveContext, Driven, Plausibility};

/// One sample as the supervisor sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SafetyInput {
    /// µs since the trigger.
    pub t_us: i64,
    /// Raw conversions, T1 then T2.
    pub counts: [Result<u16, AdcError>; 2],
    /// Calibrated forces, N (meaningless where the conversion failed).
    pub force_n: [f32; 2],
    /// The capstan is driven (`None`: idle, setup mode, a tare): the cord and plausibility
    /// checks run, with the context [`Supervisor::drive`] was given.
    pub driven: Option<Driven>,
}

/// Consecutive-sample counters of each check, and the state of the driven checks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Supervisor {
    limits: SafetyLimits,
    over: [u16; 2],
    neg: [u16; 2],
    rail: [u16; 2],
    cord: u16,
    bound: u16,
    last_t_us: Option<i64>,
    context: Option<DriveContext>,
    plausible: Plausibility,
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
            bound: 0,
            last_t_us: None,
            context: None,
            plausible: Plausibility::new(),
        }
    }

    /// The drive comes on with `context` (the run's calibration and capstan): the driven
    /// checks start afresh.
    pub fn drive(&mut self, context: DriveContext) {
        self.context = Some(context);
        self.plausible = Plausibility::new();
        (self.cord, self.bound) = (0, 0);
    }

    /// Check one sample; a fault is returned the sample its condition is confirmed.
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
        if let Some(f) = self.each_channel(input) {
            return Some(f);
        }
        match (input.driven, self.context, input.counts) {
            (Some(d), Some(ctx), [Ok(c1), Ok(c2)]) => self.driven(input, &d, &ctx, [c1, c2]),
            _ => None,
        }
    }

    /// The rails, the over-force and the negative-force checks of both channels.
    fn each_channel(&mut self, input: &SafetyInput) -> Option<Fault> {
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
        None
    }

    /// The checks of a driven capstan: the cord (collapsed, slack, T2 beyond what the
    /// capstan can make) while a level is held, and the plausibility of both channels.
    fn driven(
        &mut self,
        input: &SafetyInput,
        d: &Driven,
        ctx: &DriveContext,
        counts: [u16; 2],
    ) -> Option<Fault> {
        let l = &self.limits;
        let [t1, t2] = input.force_n;
        let fault = |kind, value| {
            Some(Fault {
                kind,
                channel: Some(Channel::T2),
                value,
                t_us: input.t_us,
            })
        };
        // A parted cord reads what it did at rest with the drive on, less what the cord carried
        // there (≥ 0): whatever the preload and the offsets the drive brings. (Before a block
        // at rest, what the tare made the preload read.)
        let [r1, r2] = self
            .plausible
            .rest_level_n()
            .unwrap_or([ctx.tare_reference_n; 2]);
        let m = l.cord_slack_margin_n;
        let collapsed = d.level_held
            && ((t1 >= l.cord_break_min_t1_n && t2 < l.cord_break_ratio * t1)
                || (t1 < r1 + m && t2 < r2 + m));
        self.cord = if collapsed { self.cord + 1 } else { 0 };
        if self.cord >= l.cord_break_samples {
            return fault(FaultKind::CordBreak, t2);
        }
        // Each reading may be off by the sensors' offsets (what the drive adds after the tare)
        // before the capstan's amplification bounds T2 by T1.
        let m = l.implausible_margin_n;
        let beyond = d.level_held && t2 > (t1 + m).max(0.0) * ctx.max_amplification + m;
        self.bound = if beyond { self.bound + 1 } else { 0 };
        if self.bound >= l.cord_break_samples {
            return fault(FaultKind::Implausible, t2);
        }
        self.plausible
            .check(l, ctx, d, input.t_us, counts, input.force_n)
    }
}

#[cfg(test)]
mod tests;
