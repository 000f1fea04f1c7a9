//! Cross-talk between force-controlled channels: for every step of one channel's T2 target,
//! what each other channel holding a steady target saw across it (its true T2 before, after and
//! its largest excursion in between) and what the drive did.

use super::{ChannelResult, SeriesRow};
use capstan_tracking::SteadyWindow;

/// The steady window of a force channel's tracking: the firmware's conditioning window.
pub const TRACKING_WINDOW: SteadyWindow = SteadyWindow {
    after_s: 2.0,
    before_s: 1.0,
};

/// What one channel saw while another's target stepped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ForceCrossTalk {
    /// The channel whose target stepped (0-based).
    pub stepping: usize,
    /// When, s (plant time).
    pub t_s: f64,
    /// Its target before and after, N.
    pub from_n: f64,
    /// See `from_n`.
    pub to_n: f64,
    /// The channel that held (0-based).
    pub observer: usize,
    /// Its target, N.
    pub observer_target_n: f64,
    /// Its true T2, mean over [t − 1 s, t − 50 ms), N.
    pub observer_t2_before_n: f64,
    /// Its true T2, mean over [t + 1.5 s, t + 2.5 s) (after its feedback settled), N.
    pub observer_t2_after_n: f64,
    /// Its largest |T2 − before| in [t, t + 1.5 s), N: the transient the drive passed on.
    pub observer_peak_dev_n: f64,
    /// Capstan speed before and after (same windows), rpm.
    pub rpm_before: f64,
    /// See `rpm_before`.
    pub rpm_after: f64,
    /// Drive current before and after, A.
    pub current_before_a: f64,
    /// See `current_before_a`.
    pub current_after_a: f64,
}

impl ForceCrossTalk {
    /// The observer's largest excursion, as a fraction of its T2 before.
    pub fn peak_dev_rel(&self) -> f64 {
        self.observer_peak_dev_n / self.observer_t2_before_n
    }

    /// The capstan speed change, as a fraction.
    pub fn d_rpm_rel(&self) -> f64 {
        (self.rpm_after - self.rpm_before) / self.rpm_before
    }
}

fn mean(series: &[SeriesRow], a: f64, b: f64, f: impl Fn(&SeriesRow) -> f64) -> f64 {
    let v: Vec<f64> = series
        .iter()
        .filter(|r| r.t_s >= a && r.t_s < b)
        .map(f)
        .collect();
    if v.is_empty() {
        f64::NAN
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

/// (plant time s, target before, target after) of every jump of a channel's target.
fn target_steps(ch: &ChannelResult) -> Vec<(f64, f64, f64)> {
    let Some(rise) = ch.trigger_rise_us else {
        return Vec::new();
    };
    ch.log
        .raw
        .windows(2)
        .filter_map(|w| {
            let (a, b) = (f64::from(w[0].t2_target_n), f64::from(w[1].t2_target_n));
            let jump = (b - a).abs() >= (0.2f64).max(0.02 * b);
            (jump && b > 0.0).then(|| ((rise as f64 + w[1].t_us as f64) * 1e-6, a, b))
        })
        .collect()
}

/// The target a channel held over [a, b] s (plant time), if it held one steady above 0.
fn held_target(ch: &ChannelResult, a: f64, b: f64) -> Option<f64> {
    let rise = ch.trigger_rise_us? as f64;
    let mut held = None;
    let mut seen = false;
    for r in &ch.log.raw {
        let t = (rise + r.t_us as f64) * 1e-6;
        if t < a || t > b {
            continue;
        }
        seen = true;
        let x = f64::from(r.t2_target_n);
        match held {
            None => held = Some(x),
            Some(h) if h != x => return None,
            _ => {}
        }
    }
    held.filter(|&x| seen && x > 0.0)
}

pub(super) fn crosstalk(series: &[SeriesRow], channels: &[ChannelResult]) -> Vec<ForceCrossTalk> {
    let mut out = Vec::new();
    for (j, ch) in channels.iter().enumerate() {
        for (t, from_n, to_n) in target_steps(ch) {
            for (i, other) in channels.iter().enumerate() {
                if i == j {
                    continue;
                }
                let Some(held) = held_target(other, t - 1.0, t + 2.5) else {
                    continue;
                };
                let t2 = |r: &SeriesRow| r.channels[i].t2_n;
                let before = mean(series, t - 1.0, t - 0.05, t2);
                let peak = series
                    .iter()
                    .filter(|r| r.t_s >= t && r.t_s < t + 1.5)
                    .map(|r| (t2(r) - before).abs())
                    .fold(0.0, f64::max);
                let c = ForceCrossTalk {
                    stepping: j,
                    t_s: t,
                    from_n,
                    to_n,
                    observer: i,
                    observer_target_n: held,
                    observer_t2_before_n: before,
                    observer_t2_after_n: mean(series, t + 1.5, t + 2.5, t2),
                    observer_peak_dev_n: peak,
                    rpm_before: mean(series, t - 1.0, t - 0.05, |r| r.capstan_rpm),
                    rpm_after: mean(series, t + 1.5, t + 2.5, |r| r.capstan_rpm),
                    current_before_a: mean(series, t - 1.0, t - 0.05, |r| r.current_a),
                    current_after_a: mean(series, t + 1.5, t + 2.5, |r| r.current_a),
                };
                if c.observer_t2_before_n.is_finite() && c.observer_t2_after_n.is_finite() {
                    out.push(c);
                }
            }
        }
    }
    out.sort_by(|a, b| a.t_s.total_cmp(&b.t_s).then(a.observer.cmp(&b.observer)));
    out
}
