//! A run's steps as they come, sample by sample: which step is held, its servo angle, when the
//! cord-break checks arm, and its conditioning window, whose pair is due on the window's last
//! sample. Pure: the protocol's schedule (`protocol.rs`) applied to the run's clock.

use super::CORD_CHECK_SETTLE_MS;
use crate::calib::Calibration;
use crate::condition::Window;
use crate::protocol::Protocol;
use crate::record::StepPair;

/// The step being held and its conditioning. Updated in place (the window is too large to
/// copy every sample).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Steps {
    step: u32,
    window: Window,
    /// The step's pair is emitted on the last sample before this, µs from the press (the end
    /// of its window; `u64::MAX`: no pair to come in this step).
    pair_due_us: u64,
    /// When the next step starts, ms from the press (`u32::MAX`: the run is over). The step is
    /// worked out anew only then, not with a division every sample.
    next_ms: u32,
    /// From when the step's level is held (the cord-break checks arm), ms (`u32::MAX`: never).
    armed_ms: u32,
    /// The step's servo angle, deg.
    servo_deg: f32,
}

impl Steps {
    /// Step 0 (rest, no window) until the first step starts.
    pub(super) fn new(p: &Protocol) -> Steps {
        Steps {
            step: 0,
            window: Window::new(0, 0),
            pair_due_us: u64::MAX,
            next_ms: p.step_start_ms(0),
            armed_ms: u32::MAX,
            servo_deg: p.rest_deg,
        }
    }

    /// The sample at `elapsed_us` (its counts, if both converted): moves to the step being
    /// held then, and offers the counts to its window.
    #[inline]
    pub(super) fn sample(&mut self, p: &Protocol, elapsed_us: u64, counts: Option<[u16; 2]>) {
        let elapsed_ms = (elapsed_us / 1000) as u32;
        if elapsed_ms >= self.next_ms {
            self.advance(p, elapsed_ms);
        }
        if let Some(c) = counts {
            self.window.push(elapsed_us, c);
        }
    }

    /// Which step is being held at `elapsed_ms` (steps start at `step_start_ms(k)`), and when
    /// the next one starts.
    #[inline]
    fn advance(&mut self, p: &Protocol, elapsed_ms: u32) {
        let n = p.levels();
        let k = ((elapsed_ms - p.step_start_ms(0)) / p.dwell_ms).min(n + 1);
        if k != self.step {
            self.step = k;
            let (a, b) = p.window_ms(k);
            self.window = Window::new(a as u64 * 1000, b as u64 * 1000);
            self.pair_due_us = if k == 0 || k > n {
                u64::MAX
            } else {
                b as u64 * 1000
            };
            self.servo_deg = p.angle_deg(k);
            self.armed_ms = if k >= 1 && p.level(k) >= 1 {
                p.step_start_ms(k) + CORD_CHECK_SETTLE_MS
            } else {
                u32::MAX
            };
        }
        self.next_ms = if k > n {
            u32::MAX
        } else {
            p.step_start_ms(k + 1)
        };
    }

    /// The step's pair, on the last sample of its window (the sample at `elapsed_us`, the next
    /// `period_us` later); once.
    #[inline]
    pub(super) fn pair_due(
        &mut self,
        p: &Protocol,
        cal: &Calibration,
        elapsed_us: u64,
        period_us: u64,
    ) -> Option<StepPair> {
        if elapsed_us + period_us < self.pair_due_us {
            return None;
        }
        self.pair_due_us = u64::MAX;
        let (a, b) = p.window_ms(self.step);
        let [t1, t2] = self.window.stats(cal);
        let mid_in_ms = (a + b) / 2 - p.step_start_ms(self.step);
        Some(StepPair {
            step: self.step,
            level: p.level(self.step),
            angle_deg: self.servo_deg,
            t_mid_ms: (a + b) / 2 - p.trigger_at_ms(),
            t1,
            t2,
            t2_target_n: p.force.nominal_n(self.step, mid_in_ms, p.dwell_ms),
        })
    }

    /// The last step is over.
    pub(super) fn ended(&self) -> bool {
        self.next_ms == u32::MAX
    }

    /// The servo angle of the step, deg.
    pub(super) fn servo_deg(&self) -> f32 {
        self.servo_deg
    }

    /// The step being held (0: rest before the first).
    pub(super) fn step(&self) -> u32 {
        self.step
    }

    /// Force control's servo command now (the pair's angle is the command at its end).
    pub(super) fn set_servo_deg(&mut self, deg: f32) {
        self.servo_deg = deg;
    }

    /// The step's tension level has been held for [`CORD_CHECK_SETTLE_MS`] at `elapsed_ms`.
    pub(super) fn level_held(&self, elapsed_ms: u32) -> bool {
        elapsed_ms >= self.armed_ms
    }
}
