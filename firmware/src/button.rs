//! Debouncing of the start/abort button.

/// A press is reported once the raw level has read "pressed" for `stable_samples` samples in
/// a row after having been stably released; it is not repeated until the button is released.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Debouncer {
    stable_samples: u16,
    run: u16,
    pressed: bool,
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
        }
    }

    /// Feed one raw sample; returns true exactly once per debounced press.
    pub fn step(&mut self, raw_pressed: bool) -> bool {
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
        raw_pressed
    }

    /// The debounced level.
    pub fn is_pressed(&self) -> bool {
        self.pressed
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounces_are_ignored_and_a_press_reports_once() {
        let mut d = Debouncer::new(20);
        // 10 ms of contact bounce, then a clean 50 ms press, then release.
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
}
