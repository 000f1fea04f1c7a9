//! What the force sensors add to the true tensions.

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
    pub fn true_t1_n(&self, t1_measured_n: f64) -> f64 {
        t1_measured_n - self.t1_offset_n
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
