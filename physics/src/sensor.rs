//! What the force sensors add to the true tensions.

/// The true T1 (N) that a positive reading at or below the T1 offset stands for: an (almost)
/// slack cord, never a negative tension.
pub const SLACK_T1_N: f64 = 0.005;

/// Zero offsets on both channels and a gain error of the T2 channel relative to T1.
///
/// measured T1 = T1 + `t1_offset_n`; measured T2 = `t2_gain`·T2 + `t2_offset_n`.
/// A constant loss in the T1 path (e.g. friction in a guide) behaves as a positive T1 offset.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensorArtefacts {
    /// Zero offset of the T1 (servo-side) reading, N.
    pub t1_offset_n: f64,
    /// Zero offset of the T2 (fixed-side) reading, N.
    pub t2_offset_n: f64,
    /// Gain of the T2 reading relative to T1 (measured/true).
    pub t2_gain: f64,
}

impl SensorArtefacts {
    /// Perfect sensors.
    pub const IDEAL: SensorArtefacts = SensorArtefacts {
        t1_offset_n: 0.0,
        t2_offset_n: 0.0,
        t2_gain: 1.0,
    };

    /// The T1 reading of a true tension, N.
    pub fn measured_t1_n(&self, t1_true_n: f64) -> f64 {
        t1_true_n + self.t1_offset_n
    }

    /// The true T1 behind a reading, N.
    ///
    /// A positive reading that does not exceed a positive offset by [`SLACK_T1_N`] stands for
    /// a slack cord: min(reading, [`SLACK_T1_N`]). Non-positive readings pass through.
    pub fn true_t1_n(&self, t1_measured_n: f64) -> f64 {
        let t = t1_measured_n - self.t1_offset_n;
        if self.t1_offset_n > 0.0 && t1_measured_n > 0.0 && t < SLACK_T1_N {
            SLACK_T1_N.min(t1_measured_n)
        } else {
            t
        }
    }

    /// The T2 reading of a true tension, N.
    pub fn measured_t2_n(&self, t2_true_n: f64) -> f64 {
        self.t2_gain * t2_true_n + self.t2_offset_n
    }
}

impl Default for SensorArtefacts {
    fn default() -> Self {
        Self::IDEAL
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_reading_below_the_offset_is_a_slack_cord() {
        let s = SensorArtefacts {
            t1_offset_n: 0.2,
            ..SensorArtefacts::IDEAL
        };
        assert!((s.true_t1_n(1.2) - 1.0).abs() < 1e-12);
        assert_eq!(s.true_t1_n(0.1), SLACK_T1_N);
        assert_eq!(s.true_t1_n(0.003), 0.003);
        assert!((s.true_t1_n(-0.1) + 0.3).abs() < 1e-12);
        assert_eq!(SensorArtefacts::IDEAL.true_t1_n(0.001), 0.001);
        // Round trip above the floor.
        assert!((s.true_t1_n(s.measured_t1_n(3.0)) - 3.0).abs() < 1e-12);
    }
}
