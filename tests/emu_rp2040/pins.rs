//! The pins' waveforms as the bench measured them (`capstan_emu_bench::meter::Segment` in the report).

use serde_json::Value;

/// From `t_ns` on, every period of `period_ns` is high for `high_ns`; period 0: static (duty
/// 0 low, 1 high).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    pub t_ns: f64,
    pub high_ns: f64,
    pub period_ns: f64,
    pub duty: f64,
}

impl Segment {
    pub fn switching(&self) -> bool {
        self.period_ns > 0.0
    }

    pub fn static_low(&self) -> bool {
        !self.switching() && self.duty == 0.0
    }
}

pub fn segments(v: &Value) -> Vec<Segment> {
    v.as_array()
        .expect("segments")
        .iter()
        .map(|s| Segment {
            t_ns: s["t_ns"].as_f64().unwrap(),
            high_ns: s["high_ns"].as_f64().unwrap(),
            period_ns: s["period_ns"].as_f64().unwrap(),
            duty: s["duty"].as_f64().unwrap(),
        })
        .collect()
}

/// Index of the segment in force at `t_ns`.
fn index_at(segs: &[Segment], t_ns: f64) -> usize {
    segs.iter().rposition(|s| s.t_ns <= t_ns).unwrap_or(0)
}

/// The segment in force at `t_ns`.
pub fn at(segs: &[Segment], t_ns: f64) -> Segment {
    segs[index_at(segs, t_ns)]
}

/// The first pulse that begins after `t_ns`: (its rising edge, its width), ns; None if the
/// pin does not pulse again.
pub fn first_pulse_after(segs: &[Segment], t_ns: f64) -> Option<(f64, f64)> {
    let i = index_at(segs, t_ns);
    let s = segs[i];
    let mut next = s.switching().then(|| {
        let k = ((t_ns - s.t_ns) / s.period_ns).floor() + 1.0;
        (s.t_ns + k * s.period_ns, s.high_ns)
    });
    for later in &segs[i + 1..] {
        if next.is_some_and(|(start, _)| later.t_ns > start) {
            break;
        }
        // The waveform changes before that pulse: its own first pulse, or none while static.
        next = later.switching().then_some((later.t_ns, later.high_ns));
        if next.is_some() {
            break;
        }
    }
    next
}

/// Every pulse width the pin carries from `t_ns` on (the first pulse after it, then each later
/// change), with when it begins.
pub fn widths_after(segs: &[Segment], t_ns: f64) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = first_pulse_after(segs, t_ns).into_iter().collect();
    let from = out.first().map_or(t_ns, |f| f.0);
    out.extend(
        segs.iter()
            .filter(|s| s.t_ns > from && s.switching())
            .map(|s| (s.t_ns, s.high_ns)),
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_pulse_after_an_instant() {
        let seg = |t: f64, high: f64, period: f64| Segment {
            t_ns: t,
            high_ns: high,
            period_ns: period,
            duty: if period > 0.0 { high / period } else { 0.0 },
        };
        let segs = [
            seg(0.0, 0.0, 0.0),
            seg(20.0, 2.0, 20.0),
            seg(100.0, 3.0, 20.0),
            seg(150.0, 0.0, 0.0),
            seg(170.0, 2.0, 20.0),
        ];
        assert_eq!(first_pulse_after(&segs, 10.0), Some((20.0, 2.0)));
        assert_eq!(first_pulse_after(&segs, 20.0), Some((40.0, 2.0)));
        assert_eq!(first_pulse_after(&segs, 85.0), Some((100.0, 3.0)));
        // Stopped at 150 before the pulse due at 160: the next is at 170.
        assert_eq!(first_pulse_after(&segs, 145.0), Some((170.0, 2.0)));
        assert_eq!(at(&segs, 160.0), segs[3]);
        assert_eq!(widths_after(&segs, 85.0), [(100.0, 3.0), (170.0, 2.0)]);
    }
}
