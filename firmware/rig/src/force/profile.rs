//! The T2 target of a force run, segment by segment. Segment k (1..=N) is the protocol's step
//! k: it starts at `step_start_ms(k)` and lasts `dwell_ms`, and its window gives its pair.
//! Segment 0 (before the first) and the return to rest after the last have no target.
//!
//! * steps: segment k holds `levels_n[k − 1]`; the list ends at the first 0;
//! * ramp: hold `levels_n[0]`, ramp linearly to `levels_n[1]` over one dwell, hold it;
//! * sine: hold the mean `levels_n[0]`, then `sine_steps` segments of a sine of amplitude
//!   `levels_n[1]` about it, at frequencies log-spaced from `sine_hz` to `sine_to_hz`, each
//!   rounded to a whole number of cycles per dwell (so the target is continuous from segment
//!   to segment: each starts and ends at the mean).

use super::{ForceConfig, ForceError, ForceProfile, MAX_TARGET_N, MIN_TARGET_N};
use libm::{powf, roundf};

pub(super) fn segments(c: &ForceConfig) -> u32 {
    match c.profile {
        ForceProfile::Steps => c.levels_n.iter().take_while(|&&l| l > 0.0).count() as u32,
        ForceProfile::Ramp => 3,
        ForceProfile::Sine => 1 + c.sine_steps,
    }
}

pub(super) fn validate(c: &ForceConfig) -> Result<(), ForceError> {
    let [a, b, ..] = c.levels_n;
    let ok = match c.profile {
        ForceProfile::Steps => {
            let n = segments(c) as usize;
            n >= 1 && c.levels_n[n..].iter().all(|&l| l == 0.0)
        }
        ForceProfile::Ramp => a > 0.0 && b > 0.0,
        ForceProfile::Sine => b > 0.0 && a - b >= MIN_TARGET_N && a + b <= MAX_TARGET_N,
    };
    ok.then_some(()).ok_or(ForceError::Level)
}

/// The frequency of sine segment `k` (≥ 2), Hz, rounded to whole cycles per dwell; 0 for any
/// other segment.
pub(super) fn sine_hz(c: &ForceConfig, k: u32, dwell_ms: u32) -> f32 {
    if c.profile != ForceProfile::Sine || k < 2 || k > 1 + c.sine_steps {
        return 0.0;
    }
    let j = (k - 2) as f32;
    let span = (c.sine_steps.max(2) - 1) as f32;
    let f = c.sine_hz * powf(c.sine_to_hz / c.sine_hz, j / span);
    let dwell_s = dwell_ms as f32 * 1e-3;
    roundf(f * dwell_s).max(1.0) / dwell_s
}

/// sin(2π·x) for x in [0, 1): folded onto a quarter turn, then its Taylor series to x⁹ (error
/// below 4e-6). libm's `sinf` would bring its reduction of huge arguments, 6.5 KiB of flash,
/// for arguments that are never above 2π here.
fn sin_turns(x: f32) -> f32 {
    let (x, sign) = if x < 0.5 { (x, 1.0) } else { (x - 0.5, -1.0) };
    // Now 0 ≤ x < ½ turn: sin is symmetric about ¼.
    let x = if x > 0.25 { 0.5 - x } else { x };
    let t = 2.0 * core::f32::consts::PI * x;
    let t2 = t * t;
    let s = t * (1.0 - t2 / 6.0 * (1.0 - t2 / 20.0 * (1.0 - t2 / 42.0 * (1.0 - t2 / 72.0))));
    sign * s
}

pub(super) fn target_n(c: &ForceConfig, k: u32, in_ms: u32, dwell_ms: u32) -> f32 {
    if k == 0 || k > segments(c) {
        return 0.0;
    }
    let [a, b, ..] = c.levels_n;
    match c.profile {
        ForceProfile::Steps => c.levels_n[(k - 1) as usize],
        ForceProfile::Ramp => match k {
            1 => a,
            2 => a + (b - a) * (in_ms.min(dwell_ms) as f32 / dwell_ms as f32),
            _ => b,
        },
        ForceProfile::Sine if k == 1 => a,
        ForceProfile::Sine => {
            // The phase from whole cycles' worth of ms: exact at every segment's start and end.
            let f = sine_hz(c, k, dwell_ms);
            let cycles = f * in_ms as f32 * 1e-3;
            a + b * sin_turns(cycles - libm::floorf(cycles))
        }
    }
}

/// The target a segment's pair is logged with: the target at the middle of its window
/// (`mid_ms` into the segment), the mean for a sine.
pub(super) fn nominal_n(c: &ForceConfig, k: u32, mid_ms: u32, dwell_ms: u32) -> f32 {
    match c.profile {
        ForceProfile::Sine if k >= 2 && k <= segments(c) => c.levels_n[0],
        _ => target_n(c, k, mid_ms, dwell_ms),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::force::ControlMode;

    fn force(profile: ForceProfile, levels_n: [f32; 4]) -> ForceConfig {
        ForceConfig {
            mode: ControlMode::Force,
            profile,
            levels_n,
            ..ForceConfig::default()
        }
    }

    #[test]
    fn the_sine_of_a_turn_is_the_sine() {
        for i in 0..1000 {
            let x = i as f32 / 1000.0;
            let want = (2.0 * core::f64::consts::PI * x as f64).sin();
            assert!((sin_turns(x) as f64 - want).abs() < 5e-6, "{x}");
        }
    }

    #[test]
    fn steps_end_at_the_first_zero_and_must_be_contiguous() {
        let c = force(ForceProfile::Steps, [5.0, 10.0, 0.0, 0.0]);
        assert_eq!(segments(&c), 2);
        assert_eq!(target_n(&c, 2, 500, 10_000), 10.0);
        assert_eq!(target_n(&c, 3, 0, 10_000), 0.0);
        assert_eq!(validate(&c), Ok(()));
        let gap = force(ForceProfile::Steps, [5.0, 0.0, 20.0, 0.0]);
        assert_eq!(validate(&gap), Err(ForceError::Level));
    }

    #[test]
    fn a_ramp_is_linear_between_two_holds() {
        let c = force(ForceProfile::Ramp, [4.0, 24.0, 0.0, 0.0]);
        assert_eq!(segments(&c), 3);
        assert_eq!(target_n(&c, 1, 9_000, 10_000), 4.0);
        assert_eq!(target_n(&c, 2, 2_500, 10_000), 9.0);
        assert_eq!(target_n(&c, 3, 0, 10_000), 24.0);
    }

    #[test]
    fn a_sine_sweep_has_whole_cycles_per_segment_and_stays_in_range() {
        let mut c = force(ForceProfile::Sine, [15.0, 10.0, 0.0, 0.0]);
        c.sine_hz = 0.2;
        c.sine_to_hz = 5.0;
        c.sine_steps = 5;
        assert_eq!(segments(&c), 6);
        let f: std::vec::Vec<f32> = (2..=6).map(|k| sine_hz(&c, k, 10_000)).collect();
        assert_eq!(f[0], 0.2);
        assert_eq!(f[4], 5.0);
        // 0.2 × 25^(1/4) = 0.447 Hz → 4 cycles in 10 s: 0.4 Hz.
        assert!((f[1] - 0.4).abs() < 1e-6, "{f:?}");
        for k in 2..=6 {
            assert!((target_n(&c, k, 0, 10_000) - 15.0).abs() < 1e-4);
            assert!((target_n(&c, k, 10_000, 10_000) - 15.0).abs() < 1e-3);
        }
        // A quarter cycle at 0.2 Hz is the crest.
        assert!((target_n(&c, 2, 1_250, 10_000) - 25.0).abs() < 1e-3);
        assert_eq!(validate(&c), Ok(()));
        c.levels_n[1] = 14.5;
        assert_eq!(validate(&c), Err(ForceError::Level));
    }
}
