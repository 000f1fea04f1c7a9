//! Where the tension levels change in a raw series: from the logger trigger (its rising edge is
//! the run's time zero, and the protocol places the levels), from the protocol's first change
//! and dwell, or found from the tensions themselves.
//!
//! Finding them: at every sample, the median of the next `h` samples minus the median of the
//! `h` before, for each channel, in units of that channel's noise (the median absolute first
//! difference); a change is a local peak of the larger of the two above a threshold, and peaks
//! closer than `min_dwell` keep only the largest (a transient after a change, an overshoot,
//! is not a change of its own), and a change under [`RELATIVE_FLOOR`] of the median change
//! is a drift inside a level, not a level. Medians make it robust to spikes and to the servo's transient;
//! the sign does not matter, so up-down and pulse orders are found as monotone ones are.

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

/// The segments between changes, [start, end) in the series' time, s: the rest before the
/// first change and after the last included.
pub fn segments(s: &Series, how: &Placement) -> Result<Vec<(f64, f64)>, String> {
    let (t0, t_end) = match (s.t_s.first(), s.t_s.last()) {
        (Some(&a), Some(&b)) => (a, b),
        _ => return Err("no samples".into()),
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
            let zero = trigger_edge(s).ok_or("the trigger column never rises")?;
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

/// The change times found in `s`.
fn detect(s: &Series, min_dwell_s: f64) -> Vec<f64> {
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
    // A change happens between the samples either side of the peak: its time is the first
    // sample of the new level.
    kept.iter().map(|&i| s.t_s[i]).collect()
}

/// At each sample i: |median(x[i..i+h]) - median(x[i-h..i])| / (noise·√(π/2h)·√2), the
/// larger of the two channels (a median of h samples has sd ≈ σ·√(π/2h)).
fn change_score(s: &Series, h: usize) -> Vec<f64> {
    let n = s.t_s.len();
    let mut score = vec![0.0; n];
    let unit = (std::f64::consts::PI / (2.0 * h as f64)).sqrt() * std::f64::consts::SQRT_2;
    let mut buf = Vec::with_capacity(h);
    for x in [&s.t1_n, &s.t2_n] {
        let sd = noise(x).max(1e-6);
        for i in h..=n.saturating_sub(h) {
            buf.clear();
            buf.extend_from_slice(&x[i - h..i]);
            let before = median(&mut buf);
            buf.clear();
            buf.extend_from_slice(&x[i..i + h]);
            let after = median(&mut buf);
            let z = (after - before).abs() / (sd * unit);
            if i < n && z > score[i] {
                score[i] = z;
            }
        }
    }
    score
}
