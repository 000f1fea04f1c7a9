//! The closed loop as the report draws it: one simulated amplification curve per cord, and
//! which cords are drawn. The loop itself (the firmware run against the simulated plant with
//! the extended model as the plant's friction law) is `capstan_validation::closed_loop`: the engine
//! runs no simulator.

/// A simulated amplification curve of one cord: (cord index, (T1, T2/T1) points by T1).
pub type SimCurve = (usize, Vec<(f64, f64)>);

/// `k` of the indices `0..n`, evenly spaced (all of them if `n <= k`).
pub fn evenly(n: usize, k: usize) -> Vec<usize> {
    if n <= k {
        return (0..n).collect();
    }
    (0..k).map(|i| i * n / k).collect()
}

/// What the closed loop simulated (`metrics.json`'s `closed_loop`).
#[derive(Clone, Debug, serde::Serialize)]
pub struct Summary {
    /// Runs simulated (one per cord simulated).
    pub runs: usize,
    /// Cords in the data set.
    pub cords: usize,
    /// Runs per simulated cord.
    pub runs_per_cord: usize,
    /// Pairs the simulated runs gave.
    pub pairs: usize,
    /// The plant the firmware ran against.
    pub plant: &'static str,
    /// Which cords were simulated.
    pub cords_note: String,
}

/// The closed loop's outcome as `metrics.json` carries it: what ran, or why it failed.
#[derive(Clone, Debug, serde::Serialize)]
#[serde(untagged)]
pub enum Outcome {
    /// It ran.
    Ran(Summary),
    /// It failed, and why.
    Failed {
        /// The error, in words.
        error: String,
    },
}
