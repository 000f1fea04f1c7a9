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
