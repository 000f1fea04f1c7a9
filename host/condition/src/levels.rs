//! Where the tension levels change in a raw series: from the logger trigger (its rising edge is
//! the run's time zero, and the protocol places the levels), from the protocol's first change
//! and dwell, or found from the tensions themselves.
//!
//! Finding them: at every sample, the median of the next `h` samples minus the median of the
//! `h` before, for each channel, in units of that statistic's own spread where nothing changes
//! (its median absolute value over the series: the changes are a few samples in thousands; never
//! below what the median absolute first difference says for white noise, nor one count of a
//! quantised reading); a change is a local peak of the larger of the two above a threshold, and peaks
//! closer than `min_dwell` keep only the largest (a transient after a change, an overshoot,
//! is not a change of its own), and a change under [`RELATIVE_FLOOR`] of the median change
//! is a drift inside a level, not a level. Medians make it robust to spikes and to the servo's transient;
//! the sign does not matter, so up-down and pulse orders are found as monotone ones are.
//! (Noise that is smooth from sample to sample — a logger's anti-alias filter at 20-50 Hz on a
//! 1 kHz series — has small first differences but medians that wander: its spread is measured
//! on the statistic itself, or every wander would be a level.) Above [`DETECT_MAX_HZ`] the
//! changes are found on block medians of the series (5 ms is finer than any window needs;
//! the medians of `h` samples at every sample cost `n·h`).

use super::table::Series;

/// How the levels are placed.
#[derive(Clone, Debug, PartialEq)]
pub enum Placement {
    /// Found from the tensions; changes at least this far apart, s.
    Detect {
        /// Shortest dwell, s.
        min_dwell_s: f64,
    },
    /// The protocol: the first change at `first_s` (run time), one every `dwell_s`, `levels`
    /// levels (and the return to rest after them).
    Protocol {
        /// First change (rest to level 1), s.
        first_s: f64,
        /// Dwell, s.
        dwell_s: f64,
        /// Levels.
        levels: u32,
    },
    /// The trigger's first rising edge is time zero; then as `Protocol`, with `first_s` after
    /// the edge.
    Trigger {
        /// First change after the edge, s.
        first_s: f64,
        /// Dwell, s.
        dwell_s: f64,
        /// Levels.
        levels: u32,
    },
}

/// Why a series has no segments (a problem of its run, reported with it).
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum NoSegments {
    /// The series is empty.
    #[error("no samples")]
    NoSamples,
    /// The levels are placed from the trigger, which never rises.
    #[error("the trigger column never rises")]
    TriggerNeverRises,
}

/// The segments between changes, [start, end) in the series' time, s: the rest before the
/// first change and after the last included.
pub fn segments(s: &Series, how: &Placement) -> Result<Vec<(f64, f64)>, NoSegments> {
    let (t0, t_end) = match (s.t_s.first(), s.t_s.last()) {
        (Some(&a), Some(&b)) => (a, b),
        _ => return Err(NoSegments::NoSamples),
    };
    let changes = match how {
        Placement::Detect { min_dwell_s } => detect(s, *min_dwell_s),
        Placement::Protocol {
            first_s,
            dwell_s,
            levels,
        } => (0..=*levels)
            .map(|k| first_s + k as f64 * dwell_s)
            .collect(),
        Placement::Trigger {
            first_s,
            dwell_s,
            levels,
        } => {
            let zero = trigger_edge(s).ok_or(NoSegments::TriggerNeverRises)?;
            (0..=*levels)
                .map(|k| zero + first_s + k as f64 * dwell_s)
                .collect()
        }
    };
    let mut bounds = vec![t0];
    bounds.extend(changes);
    // The end of the data ends the last segment (a sample period past the last sample).
    let period = if s.t_s.len() > 1 {
        (t_end - t0) / (s.t_s.len() - 1) as f64
    } else {
        0.0
    };
    bounds.push(t_end + period);
    Ok(bounds.windows(2).map(|w| (w[0], w[1])).collect())
}

/// The first rising edge of the trigger column (halfway between its lowest and highest).
fn trigger_edge(s: &Series) -> Option<f64> {
    let lo = s.trigger.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = s.trigger.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let mid = (lo + hi) / 2.0;
    (1..s.trigger.len())
        .find(|&i| s.trigger[i - 1] < mid && s.trigger[i] >= mid)
        .map(|i| s.t_s[i])
}

fn median(v: &mut [f64]) -> f64 {
    let n = v.len();
    let (_, m, _) = v.select_nth_unstable_by(n / 2, f64::total_cmp);
    *m
}

/// Noise of a channel: the median absolute first difference (a change is one difference in
/// thousands, so it does not move it), as the sd of one sample.
fn noise(x: &[f64]) -> f64 {
    let mut d: Vec<f64> = x.windows(2).map(|w| (w[1] - w[0]).abs()).collect();
    if d.is_empty() {
        return 0.0;
    }
    // For white noise, |x_i+1 - x_i| has median 0.954 sd·√2.
    median(&mut d) / (0.954 * std::f64::consts::SQRT_2)
}

/// How many noise units a change must reach to count.
pub const THRESHOLD_SIGMAS: f64 = 8.0;

/// A change must also be at least this fraction of the median change found.
pub const RELATIVE_FLOOR: f64 = 0.15;

/// Above this sampling rate, Hz, the changes are found on block medians at about this rate.
pub const DETECT_MAX_HZ: f64 = 200.0;

/// `s` as medians of blocks of `k` samples (each at its block's first time), or `None` when
/// it is sampled at [`DETECT_MAX_HZ`] or less.
fn reduced(s: &Series) -> Option<Series> {
    let n = s.t_s.len();
    let span = s.t_s.last()? - s.t_s.first()?;
    let rate = (n.saturating_sub(1)) as f64 / span;
    if rate.is_nan() || rate <= DETECT_MAX_HZ {
        return None;
    }
    let k = (rate / DETECT_MAX_HZ).ceil() as usize;
    let mut r = Series::default();
    let mut buf = Vec::with_capacity(k);
    for b in (0..n).step_by(k) {
        let e = (b + k).min(n);
        r.t_s.push(s.t_s[b]);
        for (x, out) in [(&s.t1_n, &mut r.t1_n), (&s.t2_n, &mut r.t2_n)] {
            buf.clear();
            buf.extend_from_slice(&x[b..e]);
            out.push(median(&mut buf));
        }
        r.line.push(s.line[b]);
    }
    Some(r)
}

/// The change times found in `s` (changes at least `min_dwell_s` apart).
pub fn detect(s: &Series, min_dwell_s: f64) -> Vec<f64> {
    match reduced(s) {
        Some(r) => detect_at_rate(&r, min_dwell_s),
        None => detect_at_rate(s, min_dwell_s),
    }
}

fn detect_at_rate(s: &Series, min_dwell_s: f64) -> Vec<f64> {
    let n = s.t_s.len();
    if n < 8 {
        return Vec::new();
    }
    let span = s.t_s[n - 1] - s.t_s[0];
    let rate = (n - 1) as f64 / span;
    // Half a second each side (at least 3 samples), never more than a third of a dwell.
    let h = ((0.5 * rate).round() as usize).clamp(3, ((min_dwell_s * rate / 3.0) as usize).max(3));
    let score = change_score(s, h);
    // The quantum below which a step is not a level: a noise floor for quiet series.
    let mut peaks: Vec<(usize, f64)> = (1..n - 1)
        .filter(|&i| {
            score[i] >= THRESHOLD_SIGMAS && score[i] >= score[i - 1] && score[i] > score[i + 1]
        })
        .map(|i| (i, score[i]))
        .collect();
    peaks.sort_by(|a, b| b.1.total_cmp(&a.1));
    let mut kept: Vec<usize> = Vec::new();
    for (i, _) in peaks {
        if kept
            .iter()
            .all(|&k| (s.t_s[k] - s.t_s[i]).abs() >= min_dwell_s)
        {
            kept.push(i);
        }
    }
    // A drift inside a level (creep, a wandering friction) can pass the noise threshold in a
    // quiet series; it is tiny against the steps between levels, which are alike in size.
    let mut strong: Vec<f64> = kept.iter().map(|&i| score[i]).collect();
    if !strong.is_empty() {
        let typical = median(&mut strong);
        kept.retain(|&i| score[i] >= RELATIVE_FLOOR * typical);
    }
    kept.sort_unstable();
    // Around a clean step the median difference is flat for about h samples (either median
    // flips once more than half its window is on the new level): the change is the middle of
    // the run of samples within 80 % of the peak, the first sample of the new level.
    kept.iter()
        .map(|&i| {
            let floor = 0.8 * score[i];
            let (mut a, mut b) = (i, i);
            while a > 0 && score[a - 1] >= floor {
                a -= 1;
            }
            while b + 1 < n && score[b + 1] >= floor {
                b += 1;
            }
            s.t_s[(a + b).div_ceil(2)]
        })
        .collect()
}

/// The step of a quantised, noise-dithered channel (an ADC count in newtons): its smallest
/// non-zero first difference, when at least a quarter of the differences are non-zero (the
/// noise moves the reading between counts); 0 otherwise — a noiseless staircase's only
/// differences are its changes of level.
fn quantum(x: &[f64]) -> f64 {
    let moves: Vec<f64> = x
        .windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .filter(|d| *d > 0.0)
        .collect();
    if moves.is_empty() || moves.len() * 4 < x.len().saturating_sub(1) {
        return 0.0;
    }
    moves.into_iter().fold(f64::INFINITY, f64::min)
}

/// At each sample i: |median(x[i..i+h]) - median(x[i-h..i])| in units of its spread where
/// nothing changes, the larger of the two channels. The spread is the median absolute value
/// of the difference over the series / 0.6745 (a normal's MAD), never below white noise's
/// (noise·√(π/2h)·√2: a median of h samples has sd ≈ σ·√(π/2h)), nor below the channel's
/// quantum: the median of a quantised reading moves by whole counts, and with the noise under
/// a count it flips by one whenever the level sits near a count's edge — a one-count change
/// is not a change of level (the thesis-noise series split every dwell in two without this).
fn change_score(s: &Series, h: usize) -> Vec<f64> {
    let n = s.t_s.len();
    let mut score = vec![0.0; n];
    let unit = (std::f64::consts::PI / (2.0 * h as f64)).sqrt() * std::f64::consts::SQRT_2;
    let mut buf = Vec::with_capacity(h);
    let mut diff = vec![0.0; n];
    for x in [&s.t1_n, &s.t2_n] {
        let q = quantum(x);
        let white = noise(x).max(1e-6) * unit;
        let range = h..=n.saturating_sub(h);
        for i in range.clone() {
            buf.clear();
            buf.extend_from_slice(&x[i - h..i]);
            let before = median(&mut buf);
            buf.clear();
            buf.extend_from_slice(&x[i..i + h]);
            let after = median(&mut buf);
            diff[i] = (after - before).abs();
        }
        let mut null: Vec<f64> = range.clone().map(|i| diff[i]).collect();
        let spread = if null.is_empty() {
            0.0
        } else {
            median(&mut null) / 0.6745
        };
        let unit_n = spread.max(white).max(q);
        for i in range {
            let z = diff[i] / unit_n;
            if i < n && z > score[i] {
                score[i] = z;
            }
        }
    }
    score
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 30 Hz, the thesis protocol's timing (rest, 12 levels of 10 s from 10.5 s, rest), the
    /// levels in `order`, white noise and a spike train; the trigger high from 0 to 0.5 s
    /// after a 2 s lead-in.
    fn series(order: &[u32], noise: f64, lead_s: f64) -> Series {
        let mut s = Series::default();
        let mut x = 12345u64;
        let mut gauss = || {
            let mut u = || {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                ((x >> 11) as f64 + 0.5) / (1u64 << 53) as f64
            };
            let (a, b) = (u(), u());
            (-2.0 * a.ln()).sqrt() * (2.0 * std::f64::consts::PI * b).cos()
        };
        for i in 0..((140.0 + lead_s) * 30.0) as usize {
            let t = i as f64 / 30.0;
            let since = t - lead_s;
            let k = ((since - 0.5) / 10.0).floor();
            let level = if (1.0..=12.0).contains(&k) {
                order[k as usize - 1] as f64
            } else {
                0.0
            };
            let spike = if i % 97 == 0 { 3.0 } else { 0.0 };
            s.t_s.push(t);
            s.t1_n.push(1.5 * level + 0.3 + noise * gauss() + spike);
            s.t2_n.push(3.0 * level + 0.3 + noise * gauss());
            s.trigger.push(if (0.0..0.5).contains(&since) {
                5.0
            } else {
                0.0
            });
            s.line.push(i as u64 + 2);
        }
        s
    }

    /// The thesis protocol's levels (1.5 N and 3 N a level) at `hz`, with noise of sd `sd`
    /// low-pass filtered (first order) at `corner_hz`, as a logger's anti-alias filter does.
    fn filtered(hz: f64, sd: f64, corner_hz: f64, seed: u64) -> Series {
        let mut x = seed;
        let mut gauss = || {
            let mut u = || {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                ((x >> 11) as f64 + 0.5) / (1u64 << 53) as f64
            };
            let (a, b) = (u(), u());
            (-2.0 * a.ln()).sqrt() * (2.0 * std::f64::consts::PI * b).cos()
        };
        let alpha = 1.0 - (-2.0 * std::f64::consts::PI * corner_hz / hz).exp();
        // The input sd that gives `sd` after the filter.
        let sd_in = sd / (alpha / (2.0 - alpha)).sqrt();
        let (mut e1, mut e2) = (0.0, 0.0);
        let mut s = Series::default();
        for i in 0..(140.0 * hz) as usize {
            let t = i as f64 / hz;
            let k = ((t - 0.5) / 10.0).floor();
            let level = if (1.0..=12.0).contains(&k) { k } else { 0.0 };
            e1 += alpha * (sd_in * gauss() - e1);
            e2 += alpha * (sd_in * gauss() - e2);
            s.t_s.push(t);
            s.t1_n.push(1.5 * level + 0.3 + e1);
            s.t2_n.push(3.0 * level + 0.3 + e2);
            s.line.push(i as u64 + 2);
        }
        s
    }

    /// A 1 kHz series whose noise is filtered at 20-50 Hz wanders between samples: its first
    /// differences understate it, and every wander was a level (32-35 found instead of 12).
    #[test]
    fn smooth_noise_at_1_khz_gives_the_twelve_levels() {
        for (corner, seed) in [(20.0, 3), (35.0, 4), (50.0, 5)] {
            let s = filtered(1000.0, 0.05, corner, seed);
            let found = starts(&segments(&s, &Placement::Detect { min_dwell_s: 3.0 }).unwrap());
            assert_eq!(found.len(), 13, "{corner} Hz: {found:?}");
            for (k, t) in found.iter().enumerate() {
                let want = 10.5 + 10.0 * k as f64;
                assert!((t - want).abs() <= 0.02, "{corner} Hz: change {k} at {t}");
            }
        }
    }

    /// At 10 kHz the changes are found on 200 Hz block medians: the same changes, within a
    /// block (5 ms), from a fiftieth of the samples.
    #[test]
    fn a_10_khz_series_is_searched_at_200_hz() {
        let s = filtered(10_000.0, 0.05, 1000.0, 6);
        let r = reduced(&s).expect("reduced");
        assert_eq!(r.t_s.len(), s.t_s.len().div_ceil(50));
        assert!(reduced(&filtered(200.0, 0.05, 50.0, 7)).is_none());
        let found = starts(&segments(&s, &Placement::Detect { min_dwell_s: 3.0 }).unwrap());
        assert_eq!(found.len(), 13, "{found:?}");
        for (k, t) in found.iter().enumerate() {
            let want = 10.5 + 10.0 * k as f64;
            assert!((t - want).abs() <= 0.006, "change {k} at {t}");
        }
    }

    fn starts(segs: &[(f64, f64)]) -> Vec<f64> {
        segs.iter().skip(1).map(|s| s.0).collect()
    }

    #[test]
    fn changes_are_found_in_any_order_through_noise_and_spikes() {
        let pulse = [1, 12, 2, 11, 3, 10, 4, 9, 5, 8, 6, 7];
        let updown = [2, 4, 6, 8, 10, 12, 11, 9, 7, 5, 3, 1];
        for order in [pulse, updown] {
            let s = series(&order, 0.08, 0.0);
            let segs = segments(&s, &Placement::Detect { min_dwell_s: 3.0 }).unwrap();
            let found = starts(&segs);
            assert_eq!(found.len(), 13, "{order:?}: {found:?}");
            for (k, t) in found.iter().enumerate() {
                let want = 10.5 + 10.0 * k as f64;
                assert!(
                    (t - want).abs() <= 2.0 / 30.0 + 1e-9,
                    "{order:?}: change {k} at {t}"
                );
            }
        }
    }

    #[test]
    fn the_trigger_edge_is_time_zero() {
        let s = series(&[1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12], 0.02, 2.0);
        let how = Placement::Trigger {
            first_s: 10.5,
            dwell_s: 10.0,
            levels: 12,
        };
        let segs = segments(&s, &how).unwrap();
        assert_eq!(segs.len(), 14);
        assert!((segs[1].0 - 12.5).abs() < 1e-9, "{segs:?}");
        assert!((segs[13].0 - 132.5).abs() < 1e-9, "{segs:?}");
        let mut flat = s.clone();
        flat.trigger.iter_mut().for_each(|v| *v = 0.0);
        assert_eq!(
            segments(&flat, &how),
            Err(NoSegments::TriggerNeverRises),
            "a trigger that never rises is said"
        );
    }
}
