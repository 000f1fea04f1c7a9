//! The supervisor's thresholds ([`SafetyLimits`]), each with the physics or the noise it comes
//! from, and [`SafetyLimits::visible`]: the condition a calibration must meet for the force
//! checks to hold by construction (both force limits read inside the rail checks).

use crate::hal::Channel;

/// Thresholds of the supervisor.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub struct SafetyLimits {
    /// Highest force on either channel, N (default 45).
    pub over_force_n: f32,
    /// Consecutive samples above it before the fault (default 3).
    pub over_force_samples: u16,
    /// A channel at or below this many counts is at the low rail (unplugged). Above the real
    /// ADC's floor: an RP2040 reads 10-20 counts with its input grounded (its offset), with
    /// ~1-2 counts of noise; 40 is 20 counts above the highest floor (default 40).
    pub rail_low_counts: u16,
    /// A channel at or above this many counts is at the high rail (shorted or saturated).
    /// Must be below the highest reading a sensor can produce: a 0-5 V sensor behind the
    /// board's 10k/18k divider saturates at ~3990 counts (3.21 V; 3910 with a 2 % high
    /// ADC_VREF), so the default 3900 makes a sensor pinned at its output's rail a rail
    /// fault, never a blind spot between saturation and the check (default 3900).
    pub rail_high_counts: u16,
    /// Consecutive rail (or failed) conversions before the fault (default 5).
    pub rail_samples: u16,
    /// While a level is held, the cord is broken when T2 < ratio × T1 ... (the capstan only
    /// adds tension on T2's side: T2 that far below T1 contradicts it; default 0.3)
    pub cord_break_ratio: f32,
    /// ... while T1 is at least this, N ...
    pub cord_break_min_t1_n: f32,
    /// ... for this many consecutive samples. A cord that parted also shows as both channels
    /// at or below the tare's reading ([`SafetyLimits::cord_slack_margin_n`]) for as many
    /// samples.
    pub cord_break_samples: u16,
    /// Both channels below the tare reference plus this while a level is held: the cord
    /// parted or hangs slack, N (default 0.1). Every reading is referred to the tare, which
    /// reads the preload P as the reference R: a parted cord carries nothing and reads
    /// R − P ≤ R whatever the preload was, while the lowest level (5° of servo) adds at least
    /// ~0.25 N to T1 and more to T2 at any wrap up to 720° (the plant: 0.26-0.35 N at 720°
    /// from a preload of 0-0.1 N). 0.1 N is 5 sd of a sample's noise above R.
    pub cord_slack_margin_n: f32,
    /// Largest gap between two samples before the watchdog fault, µs (default 10 ms).
    pub max_sample_gap_us: u32,
    /// A channel reading below −this, N, for `over_force_samples` samples is a fault
    /// (`negative_force`): a cord cannot push, so the sensor is reversed or its zero is wrong,
    /// and a reversed sensor would hide any over-force (default 3).
    pub negative_force_n: f32,
    /// While the capstan is driven, a channel whose conversion gives the same count this many
    /// times in a row shows no noise at all: no sensor does (the sensors' 0.02 N is ~1.3
    /// counts sd, the RP2040's ADC adds ~1 count): a lead off the pin, its 100 nF holding the
    /// last voltage, or a frozen amplifier, behind an ADC with no noise of its own. 500
    /// samples (0.5 s): with noise of even 0.5 count sd two conversions agree at most ~60 % of
    /// the time, 500 in a row less often than 1 in 10¹⁰⁰. 0: off (a noiseless simulated
    /// plant, which no real channel is; default 500).
    pub stuck_samples: u16,
    /// The answer to a servo step is read this long after it, ms: the servo takes its pulse
    /// at the next 20 ms frame and moves 5° in ~50 ms; the cord and the drive settle within
    /// ~0.2 s (default 300).
    pub answer_settle_ms: u16,
    /// Samples in each block of the answer and rest checks (default 100: 0.1 s).
    pub answer_block_samples: u16,
    /// A channel answers a servo step when its block mean after the step differs from the one
    /// before by this many standard errors of the difference (from the two blocks' own
    /// scatter), and by at least [`SafetyLimits::answer_min_counts`] (default 6).
    pub answer_z: f32,
    /// ... and at least this many counts (a noiseless reading moves by whole counts; the
    /// lowest level moves T1 by ≥ 17 counts at 0.015 N/count; default 1).
    pub answer_min_counts: f32,
    /// With the servo at rest and the capstan driven (step 0), the cord at its preload: T1 + T2
    /// falling by this much from where it was 0.1-0.2 s before, in two blocks in a row, is the
    /// cord parting, N (default 0.05: a preload of ≥ ~0.03 N drops the sum by that much; a
    /// block's sum has 0.006 N sd of noise; nothing else moves it that fast at rest).
    pub rest_drop_n: f32,
    /// The capstan cannot amplify more than e^(μ·wrap) with μ up to this (the thesis's cords
    /// 0.115; cord on metal rarely above 0.3): T2 above (T1 + m) × e^(μ_max · wrap) + m (m:
    /// [`SafetyLimits::implausible_margin_n`], each reading's offset allowance) while a level
    /// is held is a channel that reads wrong. Only with the wrap given (`wrap_deg` > 0); 0: off
    /// (default 0.5).
    pub max_mu: f32,
    /// Allowance for each sensor's offset in that bound, N: what the drive may add to a
    /// reading after the tare (the amplifier's current shifts the sensors' ground), as much as
    /// the negative-force check allows (the catalogue's `t1_offset`/`t2_offset` reach ±3 N;
    /// default 3).
    pub implausible_margin_n: f32,
    /// The drive motor's stall torque per volt at the capstan, N m/V: gear ratio × kt / R
    /// (the Pittman GM14904S016: 19.7 × 0.0612 N m/A / 4.65 Ω; default 0.2593).
    pub motor_nm_per_v: f32,
    /// The motor's own friction at the capstan, N m (19.7 × 4 mN m; default 0.0788).
    pub motor_friction_nm: f32,
    /// The motor stalls when the friction load on the capstan, (T2 − T1) × its radius (its
    /// current, in torque), reaches this fraction of its stall torque at the commanded drive
    /// (default 0.9) ...
    pub motor_stall_fraction: f32,
    /// ... for this many samples (default 100).
    pub motor_stall_samples: u16,
    /// The capstan diameter the motor check assumes when the protocol does not give one
    /// (`diameter_mm` 0), mm: the largest the rig takes, which reads the largest load
    /// (default 25.4).
    pub default_capstan_diameter_mm: f32,
}

/// The force limits must read at least this many counts inside the rail checks
/// ([`SafetyLimits::visible`]): 1 % of the ADC's range.
pub const VISIBLE_MARGIN_COUNTS: f32 = 41.0;

/// A calibration under which a force check could not trip: on `channel`, the force the rig
/// reads at the rail check less the margin is `readable_n`, short of the over-force limit (or,
/// negative, short of the negative-force limit at the low rail: a zero too near the ADC's
/// floor).
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
            rail_low_counts: 40,
            rail_high_counts: 3_900,
            rail_samples: 5,
            cord_break_ratio: 0.3,
            cord_break_min_t1_n: 0.5,
            cord_break_samples: 5,
            cord_slack_margin_n: 0.1,
            max_sample_gap_us: 10_000,
            negative_force_n: 3.0,
            stuck_samples: 500,
            answer_settle_ms: 300,
            answer_block_samples: 100,
            answer_z: 6.0,
            answer_min_counts: 1.0,
            rest_drop_n: 0.05,
            max_mu: 0.5,
            implausible_margin_n: 3.0,
            motor_nm_per_v: 19.7 * 0.0612 / 4.65,
            motor_friction_nm: 19.7 * 0.004,
            motor_stall_fraction: 0.9,
            motor_stall_samples: 100,
            default_capstan_diameter_mm: 25.4,
        }
    }
}

impl SafetyLimits {
    /// The force checks hold by construction under `cal`: on each channel the over-force limit
    /// reads at least [`VISIBLE_MARGIN_COUNTS`] below the high rail check, and the
    /// negative-force limit as far above the low one. A force at either limit is then read as
    /// one, or pins the sensor at a rail; and a zero far enough above the low rail tells a
    /// sensor at no load from an unplugged one, which reads the ADC's floor. `Err` names the
    /// first channel where it does not (a sensitivity typed too low, a zero too high, a
    /// sensor whose range ends below the limit, a zero at the ADC's floor). Only a true
    /// calibration makes the reading true: `weigh` measures the sensitivity, the tare checks
    /// the zero ([`crate::calib::TARE_MAX_N`]).
    pub fn visible(&self, cal: &crate::calib::Calibration) -> Result<(), Blind> {
        let top = self.rail_high_counts as f32 - VISIBLE_MARGIN_COUNTS;
        let bottom = self.rail_low_counts as f32 + VISIBLE_MARGIN_COUNTS;
        for (channel, ch) in [(Channel::T1, &cal.t1), (Channel::T2, &cal.t2)] {
            let readable_n = (top - ch.zero_counts) * ch.n_per_count;
            if readable_n.is_nan() || readable_n < self.over_force_n {
                return Err(Blind {
                    channel,
                    readable_n,
                });
            }
            let lowest_n = (bottom - ch.zero_counts) * ch.n_per_count;
            if lowest_n > -self.negative_force_n {
                return Err(Blind {
                    channel,
                    readable_n: lowest_n,
                });
            }
        }
        Ok(())
    }

    /// The lowest zero a channel of `n_per_count` may have, counts: the negative-force limit
    /// reads [`VISIBLE_MARGIN_COUNTS`] above the low rail check (0.015 N/count: 281 counts).
    pub fn min_zero_counts(&self, n_per_count: f32) -> f32 {
        self.rail_low_counts as f32 + VISIBLE_MARGIN_COUNTS + self.negative_force_n / n_per_count
    }
}
