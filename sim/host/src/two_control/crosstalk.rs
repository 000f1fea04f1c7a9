//! Cross-talk: for every servo step of one channel, what each channel holding its level saw
//! across it — its T2, the capstan speed and the drive current, before and after.

use super::{ChannelResult, SeriesRow};
use capstan_rig::ServoMap;

/// What one channel saw while another stepped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CrossTalk {
    /// The channel that stepped (0-based).
    pub stepping: usize,
    /// When its servo command changed, s since the press.
    pub t_s: f64,
    /// Its commanded angle before and after, deg: the protocol's angle, read back from the
    /// pulse the plant received through the firmware's servo map (the horn itself goes where
    /// the servo's own characteristic puts it).
    pub from_deg: f64,
    /// See `from_deg`.
    pub to_deg: f64,
    /// The stepping channel's own T2 change, N.
    pub stepping_d_t2_n: f64,
    /// The channel that held (0-based).
    pub observer: usize,
    /// Its mean T2 over [t − 1 s, t − 50 ms), N.
    pub observer_t2_before_n: f64,
    /// Its mean T2 over [t + 0.5 s, t + 1.5 s), N.
    pub observer_t2_after_n: f64,
    /// Capstan speed over the same windows, rpm.
    pub rpm_before: f64,
    /// See `rpm_before`.
    pub rpm_after: f64,
    /// Drive current over the same windows, A.
    pub current_before_a: f64,
    /// See `current_before_a`.
    pub current_after_a: f64,
}

impl CrossTalk {
    /// The observer's T2 change, as a fraction of its T2 before.
    pub fn observer_d_t2_rel(&self) -> f64 {
        (self.observer_t2_after_n - self.observer_t2_before_n) / self.observer_t2_before_n
    }

    /// The capstan speed change, as a fraction.
    pub fn d_rpm_rel(&self) -> f64 {
        (self.rpm_after - self.rpm_before) / self.rpm_before
    }
}

fn mean_over(series: &[SeriesRow], a_s: f64, b_s: f64, f: impl Fn(&SeriesRow) -> f64) -> f64 {
    let v: Vec<f64> = series
        .iter()
        .filter(|r| r.t_s >= a_s && r.t_s < b_s)
        .map(f)
        .collect();
    if v.is_empty() {
        f64::NAN
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

pub(super) fn crosstalk(
    series: &[SeriesRow],
    channels: &[ChannelResult],
    servo: &ServoMap,
) -> Vec<CrossTalk> {
    let commanded_deg = |pulse_us: f32| servo.angle_deg(pulse_us) as f64;
    let mut out = Vec::new();
    for (j, ch) in channels.iter().enumerate() {
        for w in ch.servo_events.windows(2) {
            let (prev, ev) = (w[0], w[1]);
            let t = ev.t_us as f64 * 1e-6;
            let mean = |a: f64, b: f64, f: &dyn Fn(&SeriesRow) -> f64| mean_over(series, a, b, f);
            let own = mean(t + 0.5, t + 1.5, &|r| r.channels[j].t2_n)
                - mean(t - 1.0, t - 0.05, &|r| r.channels[j].t2_n);
            for (i, other) in channels.iter().enumerate() {
                if i == j {
                    continue;
                }
                let busy = other.servo_events.iter().skip(1).any(|e| {
                    let te = e.t_us as f64 * 1e-6;
                    te > t - 1.0 && te < t + 1.5
                });
                if busy {
                    continue;
                }
                let before = (t - 1.0, t - 0.05);
                let after = (t + 0.5, t + 1.5);
                let c = CrossTalk {
                    stepping: j,
                    t_s: t,
                    from_deg: commanded_deg(prev.pulse_us),
                    to_deg: commanded_deg(ev.pulse_us),
                    stepping_d_t2_n: own,
                    observer: i,
                    observer_t2_before_n: mean(before.0, before.1, &|r| r.channels[i].t2_n),
                    observer_t2_after_n: mean(after.0, after.1, &|r| r.channels[i].t2_n),
                    rpm_before: mean(before.0, before.1, &|r| r.capstan_rpm),
                    rpm_after: mean(after.0, after.1, &|r| r.capstan_rpm),
                    current_before_a: mean(before.0, before.1, &|r| r.current_a),
                    current_after_a: mean(after.0, after.1, &|r| r.current_a),
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
