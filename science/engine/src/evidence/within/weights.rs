//! The rows' weights: the noise's variance function, from the replicate runs' pure error or,
//! without replicates, from a smooth curve per run.

use super::{Design, WithinFit};

/// Weights of the rows: 1/(σ_a² + σ_r²·f²), the variance of a T2 reading that carries an
/// absolute part (zero errors, sensor noise) and one proportional to the tension (mu's
/// wander and scatter).
#[derive(Clone, Debug)]
pub struct Weights {
    /// Per row.
    pub w: Vec<f64>,
    /// σ_a, N.
    pub sd_abs_n: f64,
    /// σ_r (fraction of T2).
    pub sd_rel: f64,
}

impl Weights {
    /// Equal weights.
    pub fn equal(n: usize) -> Weights {
        Weights {
            w: vec![1.0; n],
            sd_abs_n: 1.0,
            sd_rel: 0.0,
        }
    }

    /// The variance function fitted to residuals `r` at fitted values `f`: least squares of
    /// r² on (1, f²) with both coefficients kept positive, then w = 1/(σ_a² + σ_r²·f²).
    pub fn from_residuals(r: &[f64], f: &[f64]) -> Weights {
        let n = r.len();
        let (mut s00, mut s01, mut s11, mut y0, mut y1) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for i in 0..n {
            if !(r[i].is_finite() && f[i].is_finite()) {
                continue;
            }
            let x = f[i] * f[i];
            let y = r[i] * r[i];
            s00 += 1.0;
            s01 += x;
            s11 += x * x;
            y0 += y;
            y1 += x * y;
        }
        let det = s00 * s11 - s01 * s01;
        let (mut a, mut b) = if det > 1e-12 * s00 * s11 {
            ((s11 * y0 - s01 * y1) / det, (s00 * y1 - s01 * y0) / det)
        } else {
            (y0 / s00.max(1.0), 0.0)
        };
        if b < 0.0 {
            b = 0.0;
            a = y0 / s00.max(1.0);
        }
        if a <= 0.0 {
            a = 0.0;
            b = if s11 > 0.0 { y1 / s11 } else { 0.0 };
        }
        // Keep a floor on both parts (a quarter of an ADC count; 0.1 % of the tension) so that
        // no row gets an unbounded weight.
        let a = a.max(0.004f64.powi(2));
        let b = b.max(1e-6);
        let w = f
            .iter()
            .map(|&fi| {
                let fi = if fi.is_finite() { fi } else { 0.0 };
                1.0 / (a + b * fi * fi)
            })
            .collect();
        Weights {
            w,
            sd_abs_n: a.sqrt(),
            sd_rel: b.sqrt(),
        }
    }
}

impl Weights {
    /// The variance function of the pure error: the residuals of every run's own mu (no
    /// effect), less their mean over the cord × step cell's runs. Whatever effect the data
    /// hold shifts a cell's runs alike and leaves the cell mean; what is left is the run-to-run
    /// noise at that step (the wander of mu, the zero errors, the sensors), scaled by
    /// √(m/(m − 1)) for the cell mean of m runs. Without replicate runs, [`Self::from_run_curves`].
    pub fn from_pure_error(d: &Design, null: &WithinFit) -> Weights {
        let n = d.n();
        let cells = d.cell.iter().flatten().map(|&c| c + 1).max().unwrap_or(0);
        let (mut sum, mut cnt) = (vec![0.0; cells], vec![0usize; cells]);
        for i in 0..n {
            if let Some(c) = d.cell[i] {
                sum[c] += d.t2[i] - null.fitted[i];
                cnt[c] += 1;
            }
        }
        let replicated = cnt.iter().filter(|&&m| m >= 2).count();
        if replicated < 4 {
            return Weights::from_run_curves(d);
        }
        let (mut r, mut f) = (vec![f64::NAN; n], vec![f64::NAN; n]);
        for i in 0..n {
            if let Some(c) = d.cell[i].filter(|&c| cnt[c] >= 2) {
                let m = cnt[c] as f64;
                r[i] = (d.t2[i] - null.fitted[i] - sum[c] / m) * (m / (m - 1.0)).sqrt();
                f[i] = null.fitted[i];
            }
        }
        let mut w = Weights::from_residuals(&r, &f);
        let (sd_abs, sd_rel) = (w.sd_abs_n, w.sd_rel);
        for ((wi, fi), fitted) in w.w.iter_mut().zip(&f).zip(&null.fitted) {
            if !fi.is_finite() {
                *wi = 1.0 / (sd_abs.powi(2) + (sd_rel * fitted.abs()).powi(2));
            }
        }
        w
    }

    /// The variance function of the residuals of a smooth curve per run: T2 on (1, T1, T1²)
    /// inside each run of five rows or more. Any catalogue effect is smooth along a run, so what
    /// such a curve leaves is the noise, whatever the effects (scaled by √(m/(m − 3)) for the
    /// curve's three values per run).
    pub fn from_run_curves(d: &Design) -> Weights {
        let n = d.n();
        let (mut r, mut f) = (vec![f64::NAN; n], vec![f64::NAN; n]);
        for rows in &d.units {
            let m = rows.len();
            if m < 5 {
                continue;
            }
            let x: Vec<Vec<f64>> = rows
                .iter()
                .map(|&i| vec![1.0, d.t1[i], d.t1[i] * d.t1[i]])
                .collect();
            let y: Vec<f64> = rows.iter().map(|&i| d.t2[i]).collect();
            let Some(reg) = crate::fit::stats::regress(&x, &y, None, None) else {
                continue;
            };
            let scale = (m as f64 / (m as f64 - 3.0)).sqrt();
            for (k, &i) in rows.iter().enumerate() {
                let fit: f64 = (0..3).map(|j| x[k][j] * reg.coef[j]).sum();
                f[i] = fit;
                r[i] = (y[k] - fit) * scale;
            }
        }
        let mut w = Weights::from_residuals(&r, &f);
        // Rows of short runs: weigh them by their own tension.
        let (sd_abs, sd_rel) = (w.sd_abs_n, w.sd_rel);
        for ((wi, fi), t2) in w.w.iter_mut().zip(&f).zip(&d.t2) {
            if !fi.is_finite() {
                *wi = 1.0 / (sd_abs.powi(2) + (sd_rel * t2.abs()).powi(2));
            }
        }
        w
    }
}
