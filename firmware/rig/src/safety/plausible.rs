//! Is each force channel a sensor on a driven cord? The checks that need more than one sample
//! and know the capstan is driven (any mode that drives it feeds them [`Driven`]):
//!
//! * **no noise at all**: a channel giving the same count [`SafetyLimits::stuck_samples`]
//!   times in a row (`sensor_frozen`);
//! * **the answer to a servo step**: the mean of each channel over a block of samples just
//!   before the servo command changes, against a block [`SafetyLimits::answer_settle_ms`]
//!   after it. T1 must move the way the servo was told (tension up for a step toward tension)
//!   and T2 must move, each by [`SafetyLimits::answer_z`] standard errors of the difference
//!   (the blocks' own scatter) and at least [`SafetyLimits::answer_min_counts`]: neither
//!   moving is a servo that does not follow (`servo_stall`), one of them a channel frozen at a
//!   plausible value (`sensor_frozen`, that channel), T1 moving against the servo while T2
//!   follows it a reversed sensor (`implausible`, T1);
//! * **a cord parting at rest**: with the servo at rest (step 0) T1 + T2 falling by
//!   [`SafetyLimits::rest_drop_n`] from 0.1-0.2 s before, two blocks in a row (`cord_break`);
//! * **the motor's load**: (T2 − T1) × the capstan's radius, the torque the drive turns against
//!   (its current), reaching [`SafetyLimits::motor_stall_fraction`] of its stall torque at the
//!   commanded drive for [`SafetyLimits::motor_stall_samples`] (`motor_stall`).
//!
//! The answer and rest checks work on block means of the raw counts (integers: the scatter is
//! exact), so they need no calibration; a step's answer is known
//! `answer_settle_ms` + one block (0.4 s) after it. A command that changes again before that
//! (a dwell under 0.4 s) is not checked.

use super::SafetyLimits;
use crate::hal::Channel;
use crate::record::{Fault, FaultKind};

/// What the supervisor needs to know of a driven capstan, every sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Driven {
    /// The servo angle commanded now, deg (a larger angle releases the cord).
    pub servo_deg: f32,
    /// The command is the rest angle: the cord at its preload.
    pub at_rest: bool,
    /// A tension level has been held long enough for the cord checks (slack, ratio, bound).
    pub level_held: bool,
}

/// What stays fixed while the capstan is driven (a run): set when the drive comes on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DriveContext {
    /// The tare's reference force, N: what both channels read at the preload.
    pub tare_reference_n: f32,
    /// Sensitivities of T1 and T2, N per count.
    pub n_per_count: [f32; 2],
    /// Zeros of T1 and T2 (the run's, after its tare), counts.
    pub zero_counts: [f32; 2],
    /// The capstan's radius, m.
    pub capstan_radius_m: f32,
    /// The most T2/T1 the capstan can make: e^(μ_max · wrap) (infinite: the wrap is not given).
    pub max_amplification: f32,
    /// The drive motor's voltage, V.
    pub drive_v: f32,
}

/// One block of samples: sums of counts and of their squares.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Block {
    n: u16,
    sum: [u32; 2],
    sq: [u64; 2],
}

/// A complete block's means and variances of the mean's terms, counts and counts².
#[derive(Clone, Copy, Debug, PartialEq)]
struct Stats {
    mean: [f32; 2],
    var: [f32; 2],
    n: f32,
}

impl Block {
    fn add(&mut self, c: [u16; 2]) {
        self.n += 1;
        for (k, &x) in c.iter().enumerate() {
            self.sum[k] += x as u32;
            self.sq[k] += x as u64 * x as u64;
        }
    }

    fn stats(&self) -> Stats {
        let n = self.n as u64;
        let one = |k: usize| {
            // n·Σx² − (Σx)², exact in integers.
            let spread = (n * self.sq[k]).saturating_sub(self.sum[k] as u64 * self.sum[k] as u64);
            (
                self.sum[k] as f32 / n as f32,
                spread as f32 / (n * n) as f32,
            )
        };
        let [(m1, v1), (m2, v2)] = [one(0), one(1)];
        Stats {
            mean: [m1, m2],
            var: [v1, v2],
            n: n as f32,
        }
    }
}

/// The state of the checks over many samples (see the module).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plausibility {
    /// Each channel's last count and how many samples in a row it gave it.
    last: [u16; 2],
    same: [u16; 2],
    /// The servo command of the present stretch (NaN: none yet) and when it began, µs.
    command_deg: f32,
    since_us: i64,
    block: Block,
    /// The last complete block at this command.
    steady: Option<Stats>,
    /// A step awaiting its answer: the block before it, and whether it was toward tension.
    pending: Option<(Stats, bool)>,
    /// At rest: the sum of both channels two blocks back and one back (N), and how many
    /// blocks in a row fell short of the first.
    rest: Option<(f32, f32)>,
    low_blocks: u16,
    /// What both channels read at rest with the drive on (the first block there), N: the
    /// level a parted cord falls to, whatever the preload and the sensors' offsets.
    rest_level_n: Option<[f32; 2]>,
    stalled: u16,
}

impl Default for Plausibility {
    fn default() -> Self {
        Plausibility::new()
    }
}

impl Plausibility {
    /// Nothing seen yet.
    pub const fn new() -> Self {
        Plausibility {
            last: [0; 2],
            same: [0; 2],
            command_deg: f32::NAN,
            since_us: 0,
            block: Block {
                n: 0,
                sum: [0; 2],
                sq: [0; 2],
            },
            steady: None,
            pending: None,
            rest: None,
            low_blocks: 0,
            rest_level_n: None,
            stalled: 0,
        }
    }

    /// One driven sample with both conversions done: a fault when one is confirmed.
    pub fn check(
        &mut self,
        l: &SafetyLimits,
        ctx: &DriveContext,
        d: &Driven,
        t_us: i64,
        counts: [u16; 2],
        force_n: [f32; 2],
    ) -> Option<Fault> {
        let fault = |kind, channel, value| {
            Some(Fault {
                kind,
                channel,
                value,
                t_us,
            })
        };
        for ch in Channel::BOTH {
            let k = ch as usize;
            if counts[k] == self.last[k] {
                self.same[k] = self.same[k].saturating_add(1);
            } else {
                (self.last[k], self.same[k]) = (counts[k], 1);
            }
            if l.stuck_samples > 0 && self.same[k] >= l.stuck_samples {
                return fault(FaultKind::SensorFrozen, Some(ch), counts[k] as f32);
            }
        }
        if let Some(f) = self.motor(l, ctx, force_n) {
            return fault(FaultKind::MotorStall, None, f);
        }
        if d.servo_deg != self.command_deg {
            self.new_command(d.servo_deg, t_us);
        }
        if t_us - self.since_us < l.answer_settle_ms as i64 * 1000 {
            return None;
        }
        self.block.add(counts);
        if self.block.n < l.answer_block_samples.max(1) {
            return None;
        }
        let stats = self.block.stats();
        self.block = Block::default();
        self.steady = Some(stats);
        if let Some((before, toward_tension)) = self.pending.take() {
            if let Some((kind, ch, value)) = answer(l, ctx, &before, &stats, toward_tension) {
                return fault(kind, ch, value);
            }
        }
        if d.at_rest && self.rest_level_n.is_none() {
            self.rest_level_n =
                Some([0, 1].map(|k| (stats.mean[k] - ctx.zero_counts[k]) * ctx.n_per_count[k]));
        }
        if d.at_rest && self.rest_dropped(l, ctx, &stats) {
            return fault(FaultKind::CordBreak, None, force_n[0] + force_n[1]);
        }
        None
    }

    /// What both channels read at rest with the drive on, N (`None` before a block there).
    pub fn rest_level_n(&self) -> Option<[f32; 2]> {
        self.rest_level_n
    }

    /// The servo was commanded elsewhere: a step to check if the last command had a complete
    /// block, and a new stretch.
    fn new_command(&mut self, deg: f32, t_us: i64) {
        self.pending = self.steady.map(|b| (b, deg < self.command_deg));
        self.command_deg = deg;
        self.since_us = t_us;
        self.block = Block::default();
        self.steady = None;
        self.rest = None;
        self.low_blocks = 0;
    }

    /// The friction load on the capstan at its stall for long enough: the load, N m.
    fn motor(&mut self, l: &SafetyLimits, ctx: &DriveContext, f: [f32; 2]) -> Option<f32> {
        let load_nm = (f[1] - f[0]) * ctx.capstan_radius_m;
        let stall_nm = l.motor_nm_per_v * ctx.drive_v - l.motor_friction_nm;
        let at_stall = stall_nm > 0.0 && load_nm >= l.motor_stall_fraction * stall_nm;
        self.stalled = if at_stall { self.stalled + 1 } else { 0 };
        (l.motor_stall_samples > 0 && self.stalled >= l.motor_stall_samples).then_some(load_nm)
    }

    /// At rest: both channels' sum (N) fell by `rest_drop_n` from two blocks back, twice in a
    /// row. The reference follows the blocks one behind while they do not fall.
    fn rest_dropped(&mut self, l: &SafetyLimits, ctx: &DriveContext, b: &Stats) -> bool {
        let sum_n = b.mean[0] * ctx.n_per_count[0] + b.mean[1] * ctx.n_per_count[1];
        let Some((reference, back)) = self.rest else {
            self.rest = Some((sum_n, sum_n));
            return false;
        };
        if sum_n < reference - l.rest_drop_n {
            self.low_blocks += 1;
            return self.low_blocks >= 2;
        }
        self.low_blocks = 0;
        self.rest = Some((back, sum_n));
        false
    }
}

/// A step's answer: `None` if both channels answered; else the fault, the silent channel and
/// the change it showed, N.
fn answer(
    l: &SafetyLimits,
    ctx: &DriveContext,
    before: &Stats,
    after: &Stats,
    toward_tension: bool,
) -> Option<(FaultKind, Option<Channel>, f32)> {
    let moved = |k: usize| {
        let delta = after.mean[k] - before.mean[k];
        let se = libm::sqrtf(before.var[k] / before.n + after.var[k] / after.n);
        let threshold = if l.answer_z * se > l.answer_min_counts {
            l.answer_z * se
        } else {
            l.answer_min_counts
        };
        (delta, threshold)
    };
    let (d1, th1) = moved(0);
    let (d2, th2) = moved(1);
    // T1 the way the servo was told (`along`), or against it; T2 either way (its law is T1's
    // business).
    let along = if toward_tension { d1 } else { -d1 };
    let t2 = d2 >= th2 || -d2 >= th2;
    let n = |k: usize, d: f32| d * ctx.n_per_count[k];
    if along >= th1 {
        return (!t2).then_some((FaultKind::SensorFrozen, Some(Channel::T2), n(1, d2)));
    }
    Some(match (-along >= th1, t2) {
        // T2 followed the servo and T1 went the other way: a reversed sensor (or wiring).
        (true, true) => (FaultKind::Implausible, Some(Channel::T1), n(0, d1)),
        (false, true) => (FaultKind::SensorFrozen, Some(Channel::T1), n(0, d1)),
        (_, false) => (FaultKind::ServoStall, Some(Channel::T1), n(0, d1)),
    })
}
