//! The closed loop's frequency response, from a stepped sine sweep of the target.
//!
//! The sweep's segments are found from the target alone: its crossings of the mean it swings
//! about (the level held before the sweep), grouped into runs of equal half-periods (within
//! 10 %); each run is one frequency, f = 1/(2 × its mean half-period). In each, the first
//! second is left out as the transient, and over the whole cycles (at least one)
//! after it the target and the measured T2 are each fitted by least squares with
//! a + b·sin(2πft) + c·cos(2πft): the gain is the ratio of their amplitudes, the phase the
//! difference of their phases (measured − target: negative is a lag; in (−180°, 180°] at the
//! sweep's first frequency, then unwrapped along the sweep), and the residual the
//! RMS of what the measured T2's sine does not explain, in % of its amplitude (noise, the
//! servo's dead band, distortion when the servo's speed limit clips the sine).
//!
//! The −3 dB bandwidth is where the gain first falls below 1/√2, interpolated linearly in
//! log-frequency between the two frequencies around it (gain in dB), with the phase there
//! interpolated the same way.

use super::Trace;
use serde::Serialize;

/// The transient left out of each frequency, s.
pub const SETTLE_S: f64 = 1.0;

/// The closed loop at one frequency.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct BodePoint {
    /// Frequency, Hz.
    pub freq_hz: f64,
    /// When its fit starts, s (the trace's time).
    pub t_s: f64,
    /// Cycles fitted.
    pub cycles: u32,
    /// The target's amplitude, N.
    pub target_amp_n: f64,
    /// The measured T2's amplitude, N.
    pub measured_amp_n: f64,
    /// Their ratio.
    pub gain: f64,
    /// The same in dB.
    pub gain_db: f64,
    /// Measured phase − target phase, deg (negative: a lag), unwrapped along the sweep.
    pub phase_deg: f64,
    /// RMS of the measured T2 about its fitted sine, % of its amplitude.
    pub residual_pct: f64,
}

/// Where the closed loop's gain falls to −3 dB.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(tag = "found", rename_all = "snake_case")]
pub enum Bandwidth {
    /// Between two swept frequencies.
    Within {
        /// −3 dB frequency, Hz.
        freq_hz: f64,
        /// The phase there, deg.
        phase_deg: f64,
    },
    /// The gain stays above −3 dB at every swept frequency: the bandwidth is above the last.
    Above {
        /// The highest frequency swept, Hz.
        freq_hz: f64,
    },
    /// Already below −3 dB at the lowest frequency swept.
    Below {
        /// The lowest frequency swept, Hz.
        freq_hz: f64,
    },
    /// No sine in the trace.
    None,
}

/// Every frequency of the sweeps in the trace, in time order.
pub fn bode(trace: &Trace) -> Vec<BodePoint> {
    let mut out = Vec::new();
    for (a, b) in moving_spans(trace) {
        // The mean it swings about: the target where the span begins.
        let mean = trace.target_n[a.saturating_sub(1)];
        let crossings = crossings(trace, a, b, mean);
        let mut sweep: Vec<BodePoint> = Vec::new();
        for run in equal_half_periods(&crossings) {
            if let Some(mut p) = fit(trace, &crossings[run.0..=run.1]) {
                // Unwrapped: no jump of more than half a turn from the last frequency.
                if let Some(last) = sweep.last() {
                    while p.phase_deg - last.phase_deg > 180.0 {
                        p.phase_deg -= 360.0;
                    }
                    while p.phase_deg - last.phase_deg <= -180.0 {
                        p.phase_deg += 360.0;
                    }
                }
                sweep.push(p);
            }
        }
        out.extend(sweep);
    }
    out
}

/// The −3 dB bandwidth of `points` (sorted by frequency here).
pub fn bandwidth(points: &[BodePoint]) -> Bandwidth {
    let mut p: Vec<BodePoint> = points.to_vec();
    p.sort_by(|a, b| a.freq_hz.total_cmp(&b.freq_hz));
    let limit_db = -3.0103;
    let Some(first) = p.first() else {
        return Bandwidth::None;
    };
    if first.gain_db < limit_db {
        return Bandwidth::Below {
            freq_hz: first.freq_hz,
        };
    }
    for w in p.windows(2) {
        let (lo, hi) = (w[0], w[1]);
        if hi.gain_db < limit_db {
            let frac = (limit_db - lo.gain_db) / (hi.gain_db - lo.gain_db);
            let lf = lo.freq_hz.ln() + frac * (hi.freq_hz.ln() - lo.freq_hz.ln());
            return Bandwidth::Within {
                freq_hz: lf.exp(),
                phase_deg: lo.phase_deg + frac * (hi.phase_deg - lo.phase_deg),
            };
        }
    }
    Bandwidth::Above {
        freq_hz: p.last().map_or(0.0, |x| x.freq_hz),
    }
}

/// Spans [a, b) where the target changes from sample to sample (a ramp or a sine).
fn moving_spans(trace: &Trace) -> Vec<(usize, usize)> {
    let x = &trace.target_n;
    let moving = |i: usize| i > 0 && (x[i] - x[i - 1]).abs() > 1e-9 * x[i].abs().max(1.0);
    let mut spans = Vec::new();
    let mut i = 1;
    while i < x.len() {
        if !moving(i) {
            i += 1;
            continue;
        }
        let a = i;
        // A sine holds still for a sample now and then (at its crests, in f32): a span ends only
        // after 0.2 s without a change.
        let mut last = i;
        while i < x.len() && trace.t_s[i] - trace.t_s[last] < 0.2 {
            if moving(i) {
                last = i;
            }
            i += 1;
        }
        spans.push((a, last + 1));
    }
    spans
}

/// Times the target crosses `mean` in [a, b): where its side of the mean flips (a sample
/// exactly on it takes no side), interpolated between the two samples either side.
fn crossings(trace: &Trace, a: usize, b: usize, mean: f64) -> Vec<f64> {
    let (t, x) = (&trace.t_s, &trace.target_n);
    let mut out = Vec::new();
    let mut last: Option<usize> = None;
    for j in a..b {
        let v = x[j] - mean;
        if v == 0.0 {
            continue;
        }
        if let Some(i) = last {
            let u = x[i] - mean;
            if (u < 0.0) != (v < 0.0) {
                let frac = u / (u - v);
                out.push(t[i] + frac * (t[j] - t[i]));
            }
        }
        last = Some(j);
    }
    out
}

/// Runs [i, j] of crossings whose half-periods agree within 10 %, at least three half-periods.
fn equal_half_periods(c: &[f64]) -> Vec<(usize, usize)> {
    let mut runs = Vec::new();
    let mut i = 0;
    while i + 1 < c.len() {
        let h = c[i + 1] - c[i];
        let mut j = i + 1;
        while j + 1 < c.len() && ((c[j + 1] - c[j]) / h - 1.0).abs() < 0.1 {
            j += 1;
        }
        if j - i >= 3 {
            runs.push((i, j));
        }
        i = j;
    }
    runs
}

/// a + b sin + c cos by least squares over the samples in [t0, t1]: (b, c, rms residual).
fn sine_fit(trace: &Trace, y: &[f64], t0: f64, t1: f64, w: f64) -> Option<(f64, f64, f64)> {
    let idx: Vec<usize> = (0..trace.len())
        .filter(|&j| trace.t_s[j] >= t0 && trace.t_s[j] < t1)
        .collect();
    if idx.len() < 8 {
        return None;
    }
    // Normal equations of [1, s, c] (3×3), solved by Cramer's rule.
    let mut m = [[0.0f64; 3]; 3];
    let mut r = [0.0f64; 3];
    for &j in &idx {
        let th = w * (trace.t_s[j] - t0);
        let basis = [1.0, th.sin(), th.cos()];
        for p in 0..3 {
            r[p] += basis[p] * y[j];
            for q in 0..3 {
                m[p][q] += basis[p] * basis[q];
            }
        }
    }
    let det = |m: &[[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(&m);
    if d.abs() < 1e-12 {
        return None;
    }
    let solve = |k: usize| {
        let mut mk = m;
        for p in 0..3 {
            mk[p][k] = r[p];
        }
        det(&mk) / d
    };
    let (a, b, c) = (solve(0), solve(1), solve(2));
    let ss: f64 = idx
        .iter()
        .map(|&j| {
            let th = w * (trace.t_s[j] - t0);
            let e = y[j] - (a + b * th.sin() + c * th.cos());
            e * e
        })
        .sum();
    Some((b, c, (ss / idx.len() as f64).sqrt()))
}

/// The closed loop at the frequency of the crossings `c` (one run).
fn fit(trace: &Trace, c: &[f64]) -> Option<BodePoint> {
    // The mean half-period over the run (the crossings' interpolation errors average out; a
    // sweep's frequency is a whole number of cycles per dwell).
    let period = 2.0 * (c[c.len() - 1] - c[0]) / (c.len() - 1) as f64;
    let f = 1.0 / period;
    // Whole cycles from the first crossing after the transient to the last crossing.
    let start = c.iter().position(|&x| x >= c[0] + SETTLE_S)?;
    let t0 = c[start];
    let cycles = ((c[c.len() - 1] - t0) / period + 0.01).floor();
    if cycles < 1.0 {
        return None;
    }
    let t1 = t0 + cycles * period;
    let w = 2.0 * core::f64::consts::PI * f;
    let (bt, ct, _) = sine_fit(trace, &trace.target_n, t0, t1, w)?;
    let (bm, cm, rms) = sine_fit(trace, &trace.measured_n, t0, t1, w)?;
    let (at, am) = (bt.hypot(ct), bm.hypot(cm));
    if at.is_nan() || at <= 0.0 {
        return None;
    }
    let phase = |b: f64, c: f64| c.atan2(b).to_degrees();
    let mut dphi = phase(bm, cm) - phase(bt, ct);
    while dphi > 180.0 {
        dphi -= 360.0;
    }
    while dphi <= -180.0 {
        dphi += 360.0;
    }
    let gain = am / at;
    Some(BodePoint {
        freq_hz: f,
        t_s: t0,
        cycles: cycles as u32,
        target_amp_n: at,
        measured_amp_n: am,
        gain,
        gain_db: 20.0 * gain.log10(),
        phase_deg: dphi,
        residual_pct: if am > 0.0 { 100.0 * rms / am } else { f64::NAN },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A first-order lag (corner `fc`) following a stepped sine sweep about 15 N.
    fn first_order_sweep(fc: f64, freqs: &[f64]) -> Trace {
        let mut tr = Trace::default();
        let dt = 0.001;
        let tau = 1.0 / (2.0 * core::f64::consts::PI * fc);
        let (mut t, mut y) = (0.0, 15.0);
        let mut push = |target: f64, t: &mut f64, y: &mut f64| {
            *y += (target - *y) * (1.0 - (-dt / tau).exp());
            tr.push(*t, target, *y);
            *t += dt;
        };
        for _ in 0..2000 {
            push(15.0, &mut t, &mut y);
        }
        for &f in freqs {
            let n = (10.0 / dt) as usize;
            for k in 0..n {
                let x = 15.0 + 5.0 * (2.0 * core::f64::consts::PI * f * k as f64 * dt).sin();
                push(x, &mut t, &mut y);
            }
        }
        tr
    }

    #[test]
    fn a_first_order_lag_has_its_textbook_bode_and_bandwidth() {
        let fc = 1.5;
        let freqs = [0.2, 0.5, 1.0, 2.0, 4.0];
        let tr = first_order_sweep(fc, &freqs);
        let p = bode(&tr);
        assert_eq!(p.len(), freqs.len(), "{p:?}");
        for (pt, f) in p.iter().zip(freqs) {
            let want = 1.0 / (1.0 + (f / fc) * (f / fc)).sqrt();
            assert!((pt.freq_hz / f - 1.0).abs() < 0.01, "{pt:?}");
            assert!(
                (pt.gain / want - 1.0).abs() < 0.02,
                "{f}: {} vs {want}",
                pt.gain
            );
            let phase = -(f / fc).atan().to_degrees();
            assert!((pt.phase_deg - phase).abs() < 2.0, "{f}: {}", pt.phase_deg);
        }
        match bandwidth(&p) {
            // Linear interpolation between 1 and 2 Hz of a first order: within 10 % of 1.5 Hz,
            // and the phase near −45°.
            Bandwidth::Within { freq_hz, phase_deg } => {
                assert!((freq_hz / fc - 1.0).abs() < 0.1, "{freq_hz}");
                assert!((phase_deg + 45.0).abs() < 8.0, "{phase_deg}");
            }
            b => panic!("{b:?}"),
        }
        assert!(matches!(bandwidth(&p[..2]), Bandwidth::Above { .. }));
        assert_eq!(bandwidth(&[]), Bandwidth::None);
    }
}
