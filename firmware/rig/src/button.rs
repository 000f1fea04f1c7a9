//! The start/abort button: debounced edges, and what a press is.
//!
//! A **press** is a press and a release: the button read pressed, then released, each for
//! the debounce time, pressed for at most [`LONG_PRESS_MS`]. Held longer, it is **held**
//! (reported once, at that time): a switch that sticks or a lead that shorts to ground is
//! never a press, and what it began stops (`button_held`). The pressed edge comes first, after
//! the debounce: it aborts a run at once (a button that sticks during a run stops it), and it
//! may begin a run's tare, which moves nothing; the drive comes on only after the release.
//!
//! A button held (or stuck) when the debouncer starts is nothing at all until it has read
//! released for half the debounce time in a row (5 ms at 1 kHz, [`Debouncer::is_armed`]).
//! Before issue 24 a button held from power-up counted as a press 10 ms after boot.

/// Longest a press may be held, ms: held longer it starts nothing and is reported.
pub const LONG_PRESS_MS: u32 = 2_000;

/// What one sample of the button brought.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Edge {
    /// Nothing new.
    None,
    /// The button went down (debounced).
    Pressed,
    /// It came up after at most [`LONG_PRESS_MS`]: a press is complete (`consumed`: the rig
    /// already acted on its pressed edge).
    Released {
        /// The rig acted on this press's pressed edge already ([`Debouncer::consume`]).
        consumed: bool,
    },
    /// It has been down for [`LONG_PRESS_MS`]: held, not a press (once per hold).
    Held,
}

/// Debounced edges of the button (see the module).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Debouncer {
    stable_samples: u16,
    long_samples: u32,
    run: u16,
    pressed: bool,
    /// Samples the debounced press has lasted.
    held: u32,
    /// This press counts: it began after the button was seen released.
    counts: bool,
    /// The rig acted on this press's pressed edge.
    consumed: bool,
    /// Released samples in a row, until armed.
    released: u16,
    armed: bool,
}

impl Debouncer {
    /// A debouncer that needs `stable_samples` equal samples to change state (at least 1),
    /// a press held `long_samples` being held.
    pub const fn new(stable_samples: u16, long_samples: u32) -> Self {
        Debouncer {
            stable_samples: if stable_samples == 0 {
                1
            } else {
                stable_samples
            },
            long_samples,
            run: 0,
            pressed: false,
            held: 0,
            counts: false,
            consumed: false,
            released: 0,
            armed: false,
        }
    }

    /// Feed one raw sample.
    pub fn step(&mut self, raw_pressed: bool) -> Edge {
        if !self.armed {
            self.released = if raw_pressed { 0 } else { self.released + 1 };
            self.armed = self.released >= self.stable_samples.div_ceil(2);
        }
        let was_held = self.pressed && self.held >= self.long_samples;
        if self.pressed {
            self.held = self.held.saturating_add(1);
        }
        let edge = if raw_pressed == self.pressed {
            self.run = 0;
            Edge::None
        } else {
            self.run += 1;
            if self.run < self.stable_samples {
                Edge::None
            } else {
                self.run = 0;
                self.pressed = raw_pressed;
                self.change(raw_pressed, was_held)
            }
        };
        if edge == Edge::None
            && self.pressed
            && self.counts
            && !was_held
            && self.held >= self.long_samples
        {
            return Edge::Held;
        }
        edge
    }

    /// The debounced level changed to `pressed`.
    fn change(&mut self, pressed: bool, was_held: bool) -> Edge {
        if pressed {
            self.held = 0;
            self.counts = self.armed;
            self.consumed = false;
            return if self.counts {
                Edge::Pressed
            } else {
                Edge::None
            };
        }
        let complete = self.counts && !was_held;
        self.counts = false;
        if complete {
            Edge::Released {
                consumed: self.consumed,
            }
        } else {
            Edge::None
        }
    }

    /// The rig acted on the present press's pressed edge (an abort, a run's start): its
    /// release is not a press of its own.
    pub fn consume(&mut self) {
        self.consumed = true;
    }

    /// The debounced level.
    pub fn is_pressed(&self) -> bool {
        self.pressed
    }

    /// The button has been seen released since the start: a press can count.
    pub fn is_armed(&self) -> bool {
        self.armed
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn edges(d: &mut Debouncer, raw: impl IntoIterator<Item = bool>) -> Vec<(usize, Edge)> {
        raw.into_iter()
            .enumerate()
            .map(|(i, r)| (i, d.step(r)))
            .filter(|(_, e)| *e != Edge::None)
            .collect()
    }

    #[test]
    fn bounces_are_ignored_and_a_press_is_a_press_and_a_release() {
        let mut d = Debouncer::new(20, 2_000);
        // Released since the start (arms it), 10 ms of contact bounce, then a clean 50 ms
        // press, then release.
        let raw = (0..10)
            .map(|_| false)
            .chain((0..10).map(|i| i % 2 == 0))
            .chain((0..50).map(|_| true))
            .chain((0..50).map(|_| false));
        assert_eq!(
            edges(&mut d, raw),
            [
                (39, Edge::Pressed),
                (89, Edge::Released { consumed: false })
            ]
        );
        assert!(!d.is_pressed());
        // A glitch shorter than the debounce time is nothing.
        let mut raw: Vec<bool> = vec![true; 19];
        raw.push(false);
        assert!(edges(&mut d, raw).is_empty());
        // A press whose pressed edge the rig acted on is consumed at its release.
        assert_eq!(edges(&mut d, vec![true; 20]), [(19, Edge::Pressed)]);
        d.consume();
        assert_eq!(
            edges(&mut d, vec![false; 20]),
            [(19, Edge::Released { consumed: true })]
        );
    }

    #[test]
    fn a_button_held_longer_than_a_press_is_held_once_and_its_release_is_nothing() {
        let mut d = Debouncer::new(10, 2_000);
        let raw = (0..10).map(|_| false).chain((0..100_000).map(|_| true));
        // Pressed at 19, held 2000 samples later (the debounced press's 2000th sample), once.
        assert_eq!(
            edges(&mut d, raw),
            [(19, Edge::Pressed), (2_019, Edge::Held)]
        );
        assert!(edges(&mut d, vec![false; 50]).is_empty());
        // The next press is a press again.
        let raw = (0..30).map(|_| true).chain((0..30).map(|_| false));
        assert_eq!(
            edges(&mut d, raw),
            [(9, Edge::Pressed), (39, Edge::Released { consumed: false })]
        );
    }

    #[test]
    fn a_button_held_from_the_start_is_not_a_press_until_released() {
        let mut d = Debouncer::new(10, 2_000);
        // Held (or stuck) for 5 s from power-up: nothing, not even held.
        assert!(edges(&mut d, vec![true; 5_000]).is_empty());
        assert!(!d.is_armed());
        // A release shorter than 5 samples does not arm it.
        let raw = (0..4).map(|_| false).chain((0..100).map(|_| true));
        assert!(edges(&mut d, raw).is_empty());
        // Released for 10 ms (its release is nothing), then a press: that one counts, once.
        assert!(edges(&mut d, vec![false; 10]).is_empty());
        assert!(d.is_armed());
        let raw = (0..100).map(|_| true).chain((0..20).map(|_| false));
        assert_eq!(
            edges(&mut d, raw),
            [
                (9, Edge::Pressed),
                (109, Edge::Released { consumed: false })
            ]
        );
        // The usual start: released from power-up, a press 10 ms later counts.
        let mut d = Debouncer::new(10, 2_000);
        let t = (0..40).find(|&i| d.step(i >= 9) == Edge::Pressed).unwrap();
        assert_eq!(t, 18);
    }
}
