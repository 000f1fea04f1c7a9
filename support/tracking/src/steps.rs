//! The response to each step of the target.
//!
//! A step is a jump of the target (by at least 0.2 N and 2 % of the new target) that it then
//! holds for at least a second; a jump to 0 (the end of a run) is none. For each:
//!
//! * **steady state**: the mean measured T2 over the steady window of the hold (by default the
//!   firmware's conditioning window, from 2 s after the jump to 1 s before the next change; the
//!   last half of a shorter hold), its error from the target in N and in % of the target;
//! * **overshoot**: how far the measured T2, smoothed over 50 ms, goes beyond the steady mean
//!   in the step's direction within 3 s of the jump, in % of the step commanded (target −
//!   initial, the initial the mean over the 0.5 s before the jump: with a small steady-state
//!   error the same as the step made, and defined when the rig does not follow, e.g. a stalled
//!   drive); 0 if it never does;
//! * **rise time**: from the first time the smoothed T2 passes 10 % of the step to the first
//!   time it passes 90 %;
//! * **settling time**: from the jump to the last time the smoothed T2 is outside the band
//!   about the steady mean, before the steady window ends: the band is ±2 % of the target or
//!   three times the smoothed T2's own scatter in the steady window, whichever is larger.

use super::{mean, sd, Trace};
use serde::Serialize;

/// The smoothing of the transient, s.
pub const SMOOTH_S: f64 = 0.05;
/// How long after a jump the overshoot is looked for, s.
pub const TRANSIENT_S: f64 = 3.0;
/// The settling band, as a fraction of the target.
pub const SETTLE_FRACTION: f64 = 0.02;
/// The initial value: the mean over this long before the jump, s.
pub const BEFORE_S: f64 = 0.5;

/// Where in a hold the steady state is measured.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SteadyWindow {
    /// From this long after the jump, s.
    pub after_s: f64,
    /// To this long before the next change, s.
    pub before_s: f64,
}

impl Default for SteadyWindow {
    /// The firmware's conditioning window: 2 s after, 1 s before.
    fn default() -> Self {
        SteadyWindow {
            after_s: 2.0,
            before_s: 1.0,
        }
    }
}

/// The response to one step.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct StepResponse {
    /// When the target jumped, s (the trace's time).
    pub t_s: f64,
    /// The target before, N (0: none, at rest).
    pub from_target_n: f64,
    /// The target held, N.
    pub target_n: f64,
    /// How long it was held, s.
    pub hold_s: f64,
    /// The measured T2 before the jump (mean over 0.5 s), N.
    pub initial_n: f64,
    /// The measured T2 in the steady window (mean), N.
    pub steady_n: f64,
    /// Its standard deviation (raw samples), N.
    pub steady_sd_n: f64,
    /// Steady mean − target, N.
    pub ss_error_n: f64,
    /// The same in % of the target.
    pub ss_error_pct: f64,
    /// Overshoot beyond the steady mean, % of the step commanded (target − initial).
    pub overshoot_pct: f64,
    /// 10-90 % rise time, s (None: never reached 90 %).
    pub rise_s: Option<f64>,
    /// Settling time, s (None: not settled before the steady window's end).
    pub settling_s: Option<f64>,
    /// The settling band's half width, N.
    pub band_n: f64,
}

/// Every step of the trace, in time order.
pub fn steps(trace: &Trace, window: SteadyWindow) -> Vec<StepResponse> {
    let smooth = trace.smoothed(SMOOTH_S);
    let t = &trace.t_s;
    let x = &trace.target_n;
    let n = trace.len();
    // Where the target changes.
    let changes: Vec<usize> = (1..n)
        .filter(|&i| (x[i] - x[i - 1]).abs() > 1e-6 * x[i].abs().max(1.0))
        .collect();
    let mut out = Vec::new();
    for (k, &i) in changes.iter().enumerate() {
        let jump = x[i] - x[i - 1];
        let end = changes.get(k + 1).copied().unwrap_or(n);
        let hold_s = t[end - 1] - t[i];
        if x[i] <= 0.0 || jump.abs() < (0.2f64).max(0.02 * x[i]) || hold_s < 1.0 {
            continue;
        }
        if let Some(r) = response(trace, &smooth, i, end, window) {
            out.push(r);
        }
    }
    out
}

/// The response to the jump at sample `i`, held until sample `end` (exclusive).
fn response(
    trace: &Trace,
    smooth: &[f64],
    i: usize,
    end: usize,
    w: SteadyWindow,
) -> Option<StepResponse> {
    let t = &trace.t_s;
    let (t0, t_end) = (t[i], t[end - 1]);
    let hold_s = t_end - t0;
    let (a, b) = if hold_s >= w.after_s + w.before_s + 0.5 {
        (t0 + w.after_s, t_end - w.before_s)
    } else {
        (t0 + hold_s / 2.0, t_end)
    };
    let span = |lo: f64, hi: f64| (i..end).filter(move |&j| t[j] >= lo && t[j] <= hi);
    let steady: Vec<f64> = span(a, b).map(|j| trace.measured_n[j]).collect();
    let steady_smooth: Vec<f64> = span(a, b).map(|j| smooth[j]).collect();
    let before: Vec<f64> = (0..i)
        .filter(|&j| t[j] >= t0 - BEFORE_S)
        .map(|j| trace.measured_n[j])
        .collect();
    let (steady_n, initial_n) = (mean(&steady), mean(&before));
    if !(steady_n.is_finite() && initial_n.is_finite()) {
        return None;
    }
    let target_n = trace.target_n[i];
    let step = steady_n - initial_n;
    let commanded = target_n - initial_n;
    let dir = if commanded >= 0.0 { 1.0 } else { -1.0 };
    let transient: Vec<usize> = (i..end).filter(|&j| t[j] <= t0 + TRANSIENT_S).collect();
    let peak = transient
        .iter()
        .map(|&j| dir * (smooth[j] - steady_n))
        .fold(0.0f64, f64::max);
    let overshoot_pct = if commanded.abs() > 0.0 {
        100.0 * peak / commanded.abs()
    } else {
        0.0
    };
    let crossing = |frac: f64| {
        (i..end)
            .find(|&j| dir * (smooth[j] - initial_n) >= frac * step.abs())
            .map(|j| t[j])
    };
    let rise_s = match (crossing(0.1), crossing(0.9)) {
        (Some(a), Some(b)) => Some(b - a),
        _ => None,
    };
    let band_n = (SETTLE_FRACTION * target_n.abs()).max(3.0 * sd(&steady_smooth));
    let last_out = (i..end)
        .rev()
        .find(|&j| t[j] <= b && (smooth[j] - steady_n).abs() > band_n);
    let settling_s = match last_out {
        None => Some(0.0),
        Some(j) if t[j] < b => Some(t[j] - t0),
        Some(_) => None,
    };
    Some(StepResponse {
        t_s: t0,
        from_target_n: trace.target_n[i - 1],
        target_n,
        hold_s,
        initial_n,
        steady_n,
        steady_sd_n: sd(&steady),
        ss_error_n: steady_n - target_n,
        ss_error_pct: 100.0 * (steady_n - target_n) / target_n,
        overshoot_pct,
        rise_s,
        settling_s,
        band_n,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A second-order response (ζ, ω) to steps of the target, sampled at 100 Hz.
    fn second_order(levels: &[(f64, f64)], zeta: f64, omega: f64, gain: f64) -> Trace {
        let mut tr = Trace::default();
        let (mut y, mut v) = (0.0, 0.0);
        let dt = 0.01;
        let mut t = 0.0;
        for &(level, hold) in levels {
            let steps = (hold / dt).round() as usize;
            for _ in 0..steps {
                // Semi-implicit Euler in 100 substeps.
                for _ in 0..100 {
                    let a = omega * omega * (gain * level - y) - 2.0 * zeta * omega * v;
                    v += a * dt / 100.0;
                    y += v * dt / 100.0;
                }
                tr.push(t, level, y);
                t += dt;
            }
        }
        tr
    }

    #[test]
    fn a_second_order_step_has_its_textbook_overshoot_rise_and_settling() {
        // ζ = 0.5: overshoot e^(−πζ/√(1−ζ²)) = 16.3 %; 10-90 % rise ≈ 1.6/ω; 2 % settling
        // within 4/(ζω).
        let (zeta, omega) = (0.5, 10.0);
        let tr = second_order(&[(0.0, 1.0), (10.0, 6.0), (20.0, 6.0)], zeta, omega, 1.0);
        let r = steps(&tr, SteadyWindow::default());
        assert_eq!(r.len(), 2, "{r:?}");
        for s in &r {
            assert!((s.overshoot_pct - 16.3).abs() < 0.5, "{s:?}");
            let rise = s.rise_s.unwrap();
            assert!((rise - 0.164).abs() < 0.02, "{rise}");
            let settle = s.settling_s.unwrap();
            assert!(settle > 0.4 && settle < 0.8, "{settle}");
            assert!(s.ss_error_pct.abs() < 0.01);
        }
        assert_eq!(r[0].from_target_n, 0.0);
        assert_eq!(r[1].target_n, 20.0);
    }

    #[test]
    fn a_gain_error_is_a_steady_state_error_and_a_ramp_is_no_step() {
        let tr = second_order(&[(0.0, 1.0), (10.0, 6.0)], 1.0, 10.0, 0.95);
        let r = steps(&tr, SteadyWindow::default());
        assert!((r[0].ss_error_pct + 5.0).abs() < 0.01, "{r:?}");
        assert!(r[0].overshoot_pct < 0.1);
        let mut ramp = Trace::default();
        for i in 0..1000 {
            let t = i as f64 * 0.01;
            ramp.push(t, 5.0 + t, 5.0 + t);
        }
        assert!(steps(&ramp, SteadyWindow::default()).is_empty());
    }
}
