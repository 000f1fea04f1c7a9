//! The directed tests of the residuals: the run-centred residuals against one structure
//! inside runs (T1's shape, time, step direction). With [`MIN_CORDS`] cords or more and enough
//! of them for the structure, the cords are the units: each cord's coefficients, and Hotelling's
//! T² that their mean is zero, F(q, G − q) — a pattern the cords share must stand out against
//! how much the cords differ in it. With fewer cords, a cluster-robust Wald test with runs as
//! clusters, F(q, R − q), and the test says so. Patterns between cords (wrap, diameter) are the
//! cord-level ones ([`crate::evidence::cords`]), never tested against runs.

use super::super::cords::{hotelling, per_cord_coefficients, t1_basis, MIN_CORDS};
use super::super::design::Design;
use super::Directed;
use crate::fit::stats::f_p_upper;
use nalgebra::{DMatrix, DVector};

/// Subtract each run's mean from `v`.
fn run_centred(d: &Design, v: &[f64]) -> Vec<f64> {
    let mut out = v.to_vec();
    for rows in &d.units {
        let m = rows.iter().map(|&i| v[i]).sum::<f64>() / rows.len() as f64;
        for &i in rows {
            out[i] = v[i] - m;
        }
    }
    out
}

/// The structures to test on this design, each as its basis columns.
fn structures(d: &Design) -> Vec<(&'static str, Vec<Vec<f64>>)> {
    let mut out = vec![("t1_shape", t1_basis(d))];
    if d.columns.time_s && d.max_time_spread_s() > 0.0 {
        let t: Vec<f64> = d.op.iter().map(|o| o.time_s / 100.0).collect();
        out.push(("time", vec![t.clone(), t.iter().map(|x| x * x).collect()]));
    }
    if d.has_both_directions() {
        let f: Vec<f64> = d
            .falling
            .iter()
            .map(|f| if *f == Some(true) { 1.0 } else { 0.0 })
            .collect();
        out.push(("step_direction", vec![f]));
    }
    out
}

/// Every within-run directed test this design allows, on the standardised residuals `z`.
pub(super) fn directed_tests(d: &Design, z: &[f64]) -> Vec<Directed> {
    let y = run_centred(d, z);
    structures(d)
        .into_iter()
        .filter_map(|(name, cols)| {
            let x: Vec<Vec<f64>> = cols.iter().map(|c| run_centred(d, c)).collect();
            let (_, _, _, r2) = wald(d, &x, &y)?;
            let q = cols.len();
            let by_cords = d.cords.len() >= MIN_CORDS.max(q + 3);
            let (f, df1, df2, unit, units) = if by_cords {
                let c = per_cord_coefficients(d, &cols, z);
                let (f, q, df2) = hotelling(&c)?;
                (f, q, df2, "cords", d.cords.len())
            } else {
                let (f, q, g, _) = wald(d, &x, &y)?;
                (f, q, g - q, "runs", d.units.len())
            };
            Some(Directed {
                structure: name,
                f,
                df1,
                df2,
                p: f_p_upper(f, df1, df2),
                partial_r2: r2,
                unit,
                units,
            })
        })
        .collect()
}

/// Cluster-robust (runs) Wald test that y has no component along the columns `x`:
/// (F, q, G, share of y's sum of squares explained).
fn wald(d: &Design, x: &[Vec<f64>], y: &[f64]) -> Option<(f64, f64, f64, f64)> {
    let q = x.len();
    let g = d.units.len() as f64;
    if g <= q as f64 + 1.0 {
        return None;
    }
    let mut xtx = DMatrix::<f64>::zeros(q, q);
    let mut xty = DVector::<f64>::zeros(q);
    for i in 0..d.n() {
        for a in 0..q {
            xty[a] += x[a][i] * y[i];
            for b in 0..q {
                xtx[(a, b)] += x[a][i] * x[b][i];
            }
        }
    }
    let inv = xtx.try_inverse()?;
    let beta = &inv * &xty;
    let mut meat = DMatrix::<f64>::zeros(q, q);
    let mut rss = 0.0;
    for rows in &d.units {
        let mut s = DVector::<f64>::zeros(q);
        for &i in rows {
            let fit: f64 = (0..q).map(|a| x[a][i] * beta[a]).sum();
            let r = y[i] - fit;
            rss += r * r;
            for a in 0..q {
                s[a] += x[a][i] * r;
            }
        }
        meat += &s * s.transpose();
    }
    let cov = &inv * meat * &inv * (g / (g - 1.0));
    let w = (beta.transpose() * cov.try_inverse()? * &beta)[(0, 0)];
    let tss: f64 = y.iter().map(|v| v * v).sum();
    let f = w / q as f64 * (g - q as f64) / (g - 1.0);
    let r2 = if tss > 0.0 { 1.0 - rss / tss } else { 0.0 };
    f.is_finite().then_some((f, q as f64, g, r2))
}
