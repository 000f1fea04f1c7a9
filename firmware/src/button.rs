//! Debouncing of the start/abort button.

/// A press is reported once the raw level has read "pressed" for `stable_samples` samples in
/// a row after having been stably released; it is not repeated until the button is released.
///
/// A button held (or stuck) when the debouncer starts is not a press: nothing is reported
/// until the button has read released for half the debounce time in a row (5 ms at 1 kHz,
/// [`Debouncer::is_armed`]). Before, a button held from power-up counted as a press 10 ms after
/// boot, and started a run with nobody there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Debouncer {
    stable_samples: u16,
    run: u16,
    pressed: bool,
    /// Released samples in a row, until armed.
    released: u16,
    armed: bool,
}

impl Debouncer {
    /// A debouncer that needs `stable_samples` equal samples to change state (at least 1).
    pub const fn new(stable_samples: u16) -> Self {
        Debouncer {
            stable_samples: if stable_samples == 0 {
                1
            } else {
                stable_samples
            },
            run: 0,
            pressed: false,
            released: 0,
            armed: false,
        }
    }

    /// Feed one raw sample; returns true exactly once per debounced press, and never for one
    /// that began before the button was first seen released.
    pub fn step(&mut self, raw_pressed: bool) -> bool {
        if !self.armed {
            self.released = if raw_pressed { 0 } else { self.released + 1 };
            self.armed = self.released >= self.stable_samples.div_ceil(2);
        }
        if raw_pressed == self.pressed {
            self.run = 0;
            return false;
        }
        self.run += 1;
        if self.run < self.stable_samples {
            return false;
        }
        self.run = 0;
        self.pressed = raw_pressed;
        raw_pressed && self.armed
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

    #[test]
    fn bounces_are_ignored_and_a_press_reports_once() {
        let mut d = Debouncer::new(20);
        // Released since the start (arms it), 10 ms of contact bounce, then a clean 50 ms
        // press, then release.
        for _ in 0..10 {
            assert!(!d.step(false));
        }
        let mut presses = 0;
        for i in 0..10 {
            presses += d.step(i % 2 == 0) as u32;
        }
        assert_eq!(presses, 0);
        let mut at = None;
        for i in 0..50 {
            if d.step(true) {
                presses += 1;
                at = Some(i);
            }
        }
        assert_eq!((presses, at), (1, Some(19)));
        for _ in 0..50 {
            assert!(!d.step(false));
        }
        assert!(!d.is_pressed());
        // A glitch shorter than the debounce time is not a press.
        for _ in 0..19 {
            assert!(!d.step(true));
        }
        assert!(!d.step(false));
    }

    #[test]
    fn a_button_held_from_the_start_is_not_a_press_until_released() {
        let mut d = Debouncer::new(10);
        // Held (or stuck) for 5 s from power-up: nothing.
        for _ in 0..5_000 {
            assert!(!d.step(true));
        }
        assert!(!d.is_armed());
        // A release shorter than 5 samples does not arm it.
        for _ in 0..4 {
            assert!(!d.step(false));
        }
        assert!((0..100).all(|_| !d.step(true)));
        // Released for 10 ms, then a press: that one counts, once.
        for _ in 0..10 {
            assert!(!d.step(false));
        }
        assert!(d.is_armed());
        let presses = (0..100).filter(|_| d.step(true)).count();
        assert_eq!(presses, 1);
        // The usual start: released from power-up, a press 10 ms later counts.
        let mut d = Debouncer::new(10);
        let t = (0..40).find(|&i| d.step(i >= 9)).unwrap();
        assert_eq!(t, 18);
    }
}
