//! Measuring a PWM output from its pin's edges, as a logic analyser would: each period's high
//! time and length, and when the pin stops switching.
//!
//! A period is known once the next rising edge comes; a pin that stops switching is known to
//! be static once 1.5 periods have passed without a rising edge ([`PwmMeter::settle`]), and it
//! is then static from the end of its last period.

use serde::Serialize;

/// A stretch of the waveform: from `t_ns` on, every period of `period_ns` is high for
/// `high_ns`; `period_ns` 0 means the pin is static, low (`duty` 0) or high (`duty` 1).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Segment {
    /// Start of the first period of this shape (a rising edge), or when the pin became static,
    /// ns.
    pub t_ns: f64,
    /// High time per period, ns.
    pub high_ns: f64,
    /// Period, ns (0: static).
    pub period_ns: f64,
    /// High time / period (0 or 1 when static).
    pub duty: f64,
}

impl Segment {
    fn periodic(t_ns: f64, high_ns: f64, period_ns: f64) -> Segment {
        Segment {
            t_ns,
            high_ns,
            period_ns,
            duty: high_ns / period_ns,
        }
    }

    fn static_at(t_ns: f64, high: bool) -> Segment {
        Segment {
            t_ns,
            high_ns: 0.0,
            period_ns: 0.0,
            duty: if high { 1.0 } else { 0.0 },
        }
    }

    /// Is the pin static (not switching) in this stretch?
    pub fn is_static(&self) -> bool {
        self.period_ns == 0.0
    }

    fn same_shape(&self, other: &Segment) -> bool {
        self.is_static() == other.is_static()
            && (self.high_ns - other.high_ns).abs() < 0.5
            && (self.period_ns - other.period_ns).abs() < 0.5
            && self.duty == other.duty
    }
}

/// What an edge (or the passing of time) tells about the waveform.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Event {
    /// A pulse ended: it rose at `rise_ns` and was `width_ns` long. `period_ns` is the length
    /// of the periods before it (None for the first pulse after the pin was static).
    PulseEnd {
        /// Its rising edge, ns.
        rise_ns: f64,
        /// Its width, ns.
        width_ns: f64,
        /// The period the pin has been switching at, ns.
        period_ns: Option<f64>,
    },
    /// A period is complete: it started at `start_ns`, was high for `high_ns` of `period_ns`.
    Period {
        /// Its start (rising edge), ns.
        start_ns: f64,
        /// High time, ns.
        high_ns: f64,
        /// Length, ns.
        period_ns: f64,
    },
    /// The pin has been static at `high` since `since_ns`.
    Static {
        /// Since when, ns.
        since_ns: f64,
        /// Its level.
        high: bool,
    },
}

/// One PWM pin's meter.
#[derive(Clone, Debug)]
pub struct PwmMeter {
    high: bool,
    last_rise: Option<f64>,
    last_fall: Option<f64>,
    period: Option<f64>,
    is_static: bool,
    /// A pin static for longer than this, without a known period, has stopped switching, ns.
    longest_period_ns: f64,
    /// The waveform, one entry per change of shape.
    pub segments: Vec<Segment>,
    /// Rising edges seen.
    pub rises: u64,
}

impl PwmMeter {
    /// A meter on a pin that is low and static, for PWMs no longer than `longest_period_ns`.
    pub fn new(longest_period_ns: f64) -> Self {
        PwmMeter {
            high: false,
            last_rise: None,
            last_fall: None,
            period: None,
            is_static: true,
            longest_period_ns,
            segments: vec![Segment::static_at(0.0, false)],
            rises: 0,
        }
    }

    /// The pin's level now.
    pub fn is_high(&self) -> bool {
        self.high
    }

    /// The shape the pin has now (the last segment).
    pub fn current(&self) -> Segment {
        *self.segments.last().expect("a meter always has a segment")
    }

    /// The period the pin switches at, once known, ns.
    pub fn period_ns(&self) -> Option<f64> {
        self.period
    }

    fn push(&mut self, s: Segment) {
        if !self.current().same_shape(&s) {
            self.segments.push(s);
        }
    }

    /// The pin changed to `high` at `t_ns`. Call [`PwmMeter::settle`] first.
    pub fn edge(&mut self, t_ns: f64, high: bool) -> Option<Event> {
        if high == self.high {
            return None;
        }
        self.high = high;
        if high {
            self.rises += 1;
            let event = match (self.last_rise, self.last_fall) {
                (Some(r), Some(f)) if f > r && !self.is_static => {
                    let period = t_ns - r;
                    self.period = Some(period);
                    self.push(Segment::periodic(r, f - r, period));
                    Some(Event::Period {
                        start_ns: r,
                        high_ns: f - r,
                        period_ns: period,
                    })
                }
                _ => None,
            };
            if self.is_static {
                self.period = None;
            }
            self.is_static = false;
            self.last_rise = Some(t_ns);
            event
        } else {
            self.last_fall = Some(t_ns);
            let r = self.last_rise.filter(|_| !self.is_static)?;
            Some(Event::PulseEnd {
                rise_ns: r,
                width_ns: t_ns - r,
                period_ns: self.period,
            })
        }
    }

    /// Time has reached `t_ns` with no edge since the last one: has the pin stopped switching?
    /// Returns the last period (if it is complete only now) and the static level, in order.
    pub fn settle(&mut self, t_ns: f64) -> [Option<Event>; 2] {
        let Some(r) = self.last_rise.filter(|_| !self.is_static) else {
            return [None, None];
        };
        let limit = self.period.unwrap_or(self.longest_period_ns);
        if t_ns <= r + 1.5 * limit {
            return [None, None];
        }
        self.is_static = true;
        if self.high {
            // High since the last rising edge and still high: stuck high.
            self.push(Segment::static_at(r, true));
            return [
                None,
                Some(Event::Static {
                    since_ns: r,
                    high: true,
                }),
            ];
        }
        // The last pulse's period ended without a new rising edge.
        let f = self.last_fall.expect("a low pin that rose has fallen");
        let period = self.period.unwrap_or(f - r);
        let last = self.period.map(|p| {
            self.push(Segment::periodic(r, f - r, p));
            Event::Period {
                start_ns: r,
                high_ns: f - r,
                period_ns: p,
            }
        });
        let since = r + period;
        self.push(Segment::static_at(since, false));
        [
            last,
            Some(Event::Static {
                since_ns: since,
                high: false,
            }),
        ]
    }

    /// The pin was released (chip reset: every pin an input, its pull-down holds it low) at
    /// `t_ns`.
    pub fn release(&mut self, t_ns: f64) -> Vec<Event> {
        let mut out: Vec<Event> = self.settle(t_ns).into_iter().flatten().collect();
        if let Some(e) = self.edge(t_ns, false) {
            out.push(e);
        }
        if !self.is_static {
            self.is_static = true;
            self.push(Segment::static_at(t_ns, false));
            out.push(Event::Static {
                since_ns: t_ns,
                high: false,
            });
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Feed a PWM of `high`/`period` ns from `t0` for `n` periods; returns the events.
    fn pulses(m: &mut PwmMeter, t0: f64, high: f64, period: f64, n: usize) -> Vec<Event> {
        let mut ev = Vec::new();
        for k in 0..n {
            let r = t0 + k as f64 * period;
            ev.extend(m.settle(r).into_iter().flatten());
            ev.extend(m.edge(r, true));
            ev.extend(m.settle(r + high).into_iter().flatten());
            ev.extend(m.edge(r + high, false));
        }
        ev
    }

    #[test]
    fn a_servo_signal_is_measured_pulse_by_pulse_and_its_stop_is_seen() {
        let mut m = PwmMeter::new(25e6);
        let ev = pulses(&mut m, 20e6, 1_832_960.0, 20e6, 3);
        // First pulse: its width at once, the period only from the second rising edge on.
        assert_eq!(
            ev[0],
            Event::PulseEnd {
                rise_ns: 20e6,
                width_ns: 1_832_960.0,
                period_ns: None
            }
        );
        assert_eq!(
            ev[1],
            Event::Period {
                start_ns: 20e6,
                high_ns: 1_832_960.0,
                period_ns: 20e6
            }
        );
        assert_eq!(m.period_ns(), Some(20e6));
        // A new width from the fourth frame on.
        let ev = pulses(&mut m, 80e6, 1_781_440.0, 20e6, 2);
        assert!(matches!(ev[1], Event::PulseEnd { width_ns, .. } if width_ns == 1_781_440.0));
        // Nothing yet 25 ms after the last rising edge; static low from the end of its period
        // once 30 ms have passed.
        assert_eq!(m.settle(100e6 + 25e6), [None, None]);
        let ev = m.settle(100e6 + 31e6);
        assert_eq!(
            ev[1],
            Some(Event::Static {
                since_ns: 120e6,
                high: false
            })
        );
        let shapes: Vec<(f64, f64)> = m.segments.iter().map(|s| (s.t_ns, s.high_ns)).collect();
        assert_eq!(
            shapes,
            [
                (0.0, 0.0),
                (20e6, 1_832_960.0),
                (80e6, 1_781_440.0),
                (120e6, 0.0)
            ]
        );
    }

    #[test]
    fn a_fast_pwm_duty_and_a_release_at_reset() {
        let mut m = PwmMeter::new(100e3);
        pulses(&mut m, 1e6, 24_816.0, 32_768.0, 10);
        let s = m.current();
        assert_eq!((s.high_ns, s.period_ns), (24_816.0, 32_768.0));
        assert!((s.duty - 3102.0 / 4096.0).abs() < 1e-12);
        // Reset in the middle of a high time: low from then on.
        let t = 1e6 + 10.0 * 32_768.0 + 1_000.0;
        m.edge(t - 1_000.0, true);
        let ev = m.release(t);
        assert!(ev.contains(&Event::Static {
            since_ns: t,
            high: false
        }));
        assert!(m.current().is_static() && m.current().duty == 0.0);
        // Stuck high is static high.
        let mut m = PwmMeter::new(100e3);
        pulses(&mut m, 0.0, 100.0, 1_000.0, 3);
        m.edge(3_000.0, true);
        let ev = m.settle(10_000.0);
        assert_eq!(
            ev[1],
            Some(Event::Static {
                since_ns: 3_000.0,
                high: true
            })
        );
    }
}
