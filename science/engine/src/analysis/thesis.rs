//! The thesis's Table 3 double exponential, applied as the thesis did: amp(T1) per wrap angle.
//!
//! amp(T1) = −Nd·exp(−ld·T1) + N0·exp(−l·T1) + SS (T1 in N). The numbers are the thesis's
//! published constants (Table 3, copied from the thesis), not fitted here.

/// One column of Table 3.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Table3 {
    /// Wrap angle, degrees.
    pub wrap_deg: f64,
    /// Steady-state amplification.
    pub ss: f64,
    /// Slow-decay amplitude.
    pub n0: f64,
    /// Slow-decay rate, 1/N.
    pub l: f64,
    /// Fast-rise amplitude.
    pub nd: f64,
    /// Fast-rise rate, 1/N.
    pub ld: f64,
}

/// The thesis's Table 3 (published constants), for the five measured angles.
pub const TABLE3: [Table3; 5] = [
    Table3 {
        wrap_deg: 270.0,
        ss: 1.75,
        n0: 0.25,
        l: 0.11,
        nd: 2.0,
        ld: 0.6,
    },
    Table3 {
        wrap_deg: 360.0,
        ss: 2.0,
        n0: 0.5,
        l: 0.11,
        nd: 2.5,
        ld: 0.7,
    },
    Table3 {
        wrap_deg: 450.0,
        ss: 2.3,
        n0: 1.0,
        l: 0.11,
        nd: 3.3,
        ld: 0.9,
    },
    Table3 {
        wrap_deg: 630.0,
        ss: 3.1,
        n0: 1.8,
        l: 0.11,
        nd: 4.9,
        ld: 1.5,
    },
    Table3 {
        wrap_deg: 720.0,
        ss: 3.4,
        n0: 2.5,
        l: 0.11,
        nd: 5.9,
        ld: 2.0,
    },
];

/// Numbers of Table 3 used for the five measured angles (5 per angle).
pub const TABLE3_N_VALUES: usize = 25;

/// The thesis's amplification at `t1_n` for `wrap_deg` (None if the angle is not in Table 3).
pub fn thesis_amp(wrap_deg: f64, t1_n: f64) -> Option<f64> {
    TABLE3
        .iter()
        .find(|c| (c.wrap_deg - wrap_deg).abs() < 1e-6)
        .map(|c| -c.nd * (-c.ld * t1_n).exp() + c.n0 * (-c.l * t1_n).exp() + c.ss)
}

/// The thesis's per-angle R² of amplification: rows of each angle pooled over both capstan
/// diameters, 1 − SS_res/SS_tot on T2/T1. Returns (angle, R², rows) for the angles of Table 3
/// present in the data.
pub fn per_angle_r2(wrap_deg: &[f64], t1_n: &[f64], t2_n: &[f64]) -> Vec<(f64, f64, usize)> {
    TABLE3
        .iter()
        .filter_map(|c| {
            let idx: Vec<usize> = (0..wrap_deg.len())
                .filter(|&i| (wrap_deg[i] - c.wrap_deg).abs() < 1e-6)
                .collect();
            if idx.len() < 2 {
                return None;
            }
            let m: Vec<f64> = idx.iter().map(|&i| t2_n[i] / t1_n[i]).collect();
            let p: Vec<f64> = idx
                .iter()
                .map(|&i| thesis_amp(c.wrap_deg, t1_n[i]).unwrap_or(f64::NAN))
                .collect();
            Some((c.wrap_deg, crate::fit::stats::r_squared(&m, &p), idx.len()))
        })
        .collect()
}
