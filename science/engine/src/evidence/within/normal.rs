//! The arrow-head normal equations of a within fit and its damped, bounded step: each
//! residual depends on θ and on its own run's mu only, so the per-run sums reduce (Schur
//! complement) to a k×k system for δθ plus R scalar ones.

use super::super::candidates::ThetaMap;
use super::super::design::Design;
use super::Weights;
use nalgebra::{DMatrix, DVector};

/// Per-run and shared sums of the normal equations.
pub(super) struct Normal {
    pub(super) d: Vec<f64>,
    pub(super) c: Vec<f64>,
    pub(super) g: Vec<f64>,
    pub(super) h: DMatrix<f64>,
    pub(super) gb: DVector<f64>,
}

/// The sums at the residuals `resid`, with each row's sensitivities to its own run's mu (`a`)
/// and to θ (`b`, row-major n×k), weighted.
pub(super) fn normal(
    d: &Design,
    k: usize,
    w: &Weights,
    resid: &[f64],
    a: &[f64],
    b: &[f64],
) -> Normal {
    let nu = d.units.len();
    let mut nm = Normal {
        d: vec![0.0; nu],
        c: vec![0.0; nu * k],
        g: vec![0.0; nu],
        h: DMatrix::zeros(k, k),
        gb: DVector::zeros(k),
    };
    for (u, rows) in d.units.iter().enumerate() {
        let (mut du, mut gu) = (0.0, 0.0);
        for &i in rows {
            let wi = w.w[i];
            du += wi * a[i] * a[i];
            gu += wi * a[i] * resid[i];
            for j in 0..k {
                let bj = b[i * k + j];
                nm.c[u * k + j] += wi * a[i] * bj;
                nm.gb[j] += wi * bj * resid[i];
                for l in 0..=j {
                    nm.h[(j, l)] += wi * bj * b[i * k + l];
                }
            }
        }
        nm.d[u] = du.max(1e-300);
        nm.g[u] = gu;
    }
    for j in 0..k {
        for l in 0..j {
            nm.h[(l, j)] = nm.h[(j, l)];
        }
    }
    nm
}

/// S = H − Σ c cᵀ/d with the run terms damped by (1 + λ) and H's diagonal by (1 + λ); the
/// runs marked `held` keep their mu (no term: their rows inform θ alone).
pub(super) fn schur(
    nm: &Normal,
    k: usize,
    lambda: f64,
    held: &[bool],
) -> (DMatrix<f64>, DVector<f64>) {
    let mut s = nm.h.clone();
    for j in 0..k {
        s[(j, j)] *= 1.0 + lambda;
    }
    let mut rhs = -nm.gb.clone();
    for (u, _) in held.iter().enumerate().filter(|(_, &h)| !h) {
        let du = nm.d[u] * (1.0 + lambda);
        let c = &nm.c[u * k..(u + 1) * k];
        for j in 0..k {
            rhs[j] += c[j] * nm.g[u] / du;
            for l in 0..k {
                s[(j, l)] -= c[j] * c[l] / du;
            }
        }
    }
    (s, rhs)
}

/// The Newton step of θ from S·δ = rhs, with any parameter that sits on a bound and would step
/// out of it held there (its row and column taken out of the system): a projected step, so an
/// effect pinned at its neutral bound (B = 0) neither creeps nor stalls the others.
pub(super) fn bounded_step(
    mut s: DMatrix<f64>,
    mut rhs: DVector<f64>,
    theta: &[f64],
    maps: &[ThetaMap],
) -> DVector<f64> {
    let k = theta.len();
    if k == 0 {
        return DVector::zeros(0);
    }
    let solve = |s: &DMatrix<f64>, rhs: &DVector<f64>| {
        s.clone()
            .lu()
            .solve(rhs)
            .unwrap_or_else(|| DVector::zeros(k))
    };
    let mut step = solve(&s, &rhs);
    for _ in 0..k {
        let pinned: Vec<usize> = (0..k)
            .filter(|&j| {
                let span = (maps[j].hi - maps[j].lo).abs().max(1e-300);
                let at_lo = theta[j] - maps[j].lo <= 1e-12 * span && step[j] < 0.0;
                let at_hi = maps[j].hi - theta[j] <= 1e-12 * span && step[j] > 0.0;
                (at_lo || at_hi) && s[(j, j)] != 1.0
            })
            .collect();
        if pinned.is_empty() {
            break;
        }
        for &j in &pinned {
            for l in 0..k {
                s[(j, l)] = 0.0;
                s[(l, j)] = 0.0;
            }
            s[(j, j)] = 1.0;
            rhs[j] = 0.0;
        }
        step = solve(&s, &rhs);
    }
    step
}
