//! The runs' mu between runs and cords: their scatter as a linear mixed model, and the tests of
//! the covariates that vary between cords or runs ([`between_test`]).
//!
//! Each run's mu m_r comes from the within-run Euler-Eytelwein fit. Then
//!
//! m_r = a + b·x_r + u_c(r) + e_r,   u_c ~ N(0, σ_c²) (cord),   e_r ~ N(0, σ_e²) (run),
//!
//! fitted by maximum likelihood (GLS for a, b at a given ρ = σ_c²/σ_e², the profile likelihood
//! maximised over ρ). The diagnosis uses it (with x = 1) for the scatter it reports; its tests
//! of covariates use exact small-sample regressions at the cord or run level instead (ML
//! variance components from a handful of cords are biased low, which makes likelihood-ratio
//! tests anti-conservative).

use super::prep::{self, Prepared};
use super::Level;
use crate::fit::stats;
use capstan_friction::{EffectKind, REF_DIAMETER_MM, REF_DRIVE_V};

/// ML fit of the random-intercept model.
#[derive(Clone, Debug)]
#[allow(dead_code)] // coef/se: kept for callers that want the fixed effects
pub(crate) struct LmmFit {
    /// Fixed effects (intercept first).
    pub coef: Vec<f64>,
    /// Their standard errors (at the fitted ρ).
    pub se: Vec<f64>,
    /// Maximised log-likelihood.
    pub loglik: f64,
    /// Run-level variance σ_e².
    pub sigma2_e: f64,
    /// Cord-level variance σ_c².
    pub sigma2_c: f64,
}

/// Profile log-likelihood and GLS at ρ. `x` has one row per run (intercept included).
fn at_rho(y: &[f64], x: &[Vec<f64>], cord: &[usize], n_cords: usize, rho: f64) -> Option<LmmFit> {
    let n = y.len();
    let k = x[0].len();
    let mut size = vec![0usize; n_cords];
    for &c in cord {
        size[c] += 1;
    }
    let w: Vec<f64> = size.iter().map(|&s| rho / (1.0 + rho * s as f64)).collect();
    // Cord sums of x and y.
    let mut sx = vec![vec![0.0; k]; n_cords];
    let mut sy = vec![0.0; n_cords];
    for r in 0..n {
        for j in 0..k {
            sx[cord[r]][j] += x[r][j];
        }
        sy[cord[r]] += y[r];
    }
    // XᵀV⁻¹X and XᵀV⁻¹y up to σ²: Σ x xᵀ − Σ_c w_c (Σx)(Σx)ᵀ.
    let mut a = nalgebra::DMatrix::<f64>::zeros(k, k);
    let mut bvec = nalgebra::DVector::<f64>::zeros(k);
    for r in 0..n {
        for i in 0..k {
            bvec[i] += x[r][i] * y[r];
            for j in 0..k {
                a[(i, j)] += x[r][i] * x[r][j];
            }
        }
    }
    for c in 0..n_cords {
        for i in 0..k {
            bvec[i] -= w[c] * sx[c][i] * sy[c];
            for j in 0..k {
                a[(i, j)] -= w[c] * sx[c][i] * sx[c][j];
            }
        }
    }
    let inv = a.clone().try_inverse()?;
    let coef = &inv * &bvec;
    // Quadratic form of the residuals.
    let mut res = vec![0.0; n];
    let mut sres = vec![0.0; n_cords];
    for r in 0..n {
        let fit: f64 = (0..k).map(|j| x[r][j] * coef[j]).sum();
        res[r] = y[r] - fit;
        sres[cord[r]] += res[r];
    }
    let q: f64 = res.iter().map(|e| e * e).sum::<f64>()
        - (0..n_cords).map(|c| w[c] * sres[c] * sres[c]).sum::<f64>();
    let sigma2 = (q / n as f64).max(1e-300);
    let logdet: f64 = size.iter().map(|&s| (1.0 + rho * s as f64).ln()).sum();
    let nf = n as f64;
    let loglik = -0.5 * (nf * (2.0 * std::f64::consts::PI * sigma2).ln() + logdet + nf);
    let se = (0..k)
        .map(|j| (sigma2 * inv[(j, j)]).max(0.0).sqrt())
        .collect();
    Some(LmmFit {
        coef: coef.iter().copied().collect(),
        se,
        loglik,
        sigma2_e: sigma2,
        sigma2_c: rho * sigma2,
    })
}

/// Maximum-likelihood fit over ρ ∈ [0, 10⁶] (golden section on ln ρ, and ρ = 0).
pub(crate) fn fit_lmm(y: &[f64], x: &[Vec<f64>], cord: &[usize], n_cords: usize) -> Option<LmmFit> {
    let f = |lr: f64| at_rho(y, x, cord, n_cords, lr.exp());
    let ll = |lr: f64| f(lr).map_or(f64::NEG_INFINITY, |m| m.loglik);
    // Coarse grid, then golden section around the best grid point.
    let grid: Vec<f64> = (0..=16).map(|i| -8.0 + i as f64 * 1.4).collect();
    let vals: Vec<f64> = grid.iter().map(|&g| ll(g)).collect();
    let ib = (0..grid.len())
        .max_by(|&i, &j| vals[i].total_cmp(&vals[j]))
        .unwrap_or(0);
    let (mut lo, mut hi) = (
        grid[ib.saturating_sub(1)],
        grid[(ib + 1).min(grid.len() - 1)],
    );
    let gr = 0.5 * (5f64.sqrt() - 1.0);
    let mut c = hi - gr * (hi - lo);
    let mut d = lo + gr * (hi - lo);
    let (mut fc, mut fd) = (ll(c), ll(d));
    for _ in 0..40 {
        if fc > fd {
            hi = d;
            d = c;
            fd = fc;
            c = hi - gr * (hi - lo);
            fc = ll(c);
        } else {
            lo = c;
            c = d;
            fc = fd;
            d = lo + gr * (hi - lo);
            fd = ll(d);
        }
    }
    let best_lr = if fc > fd { c } else { d };
    let best = f(best_lr)?;
    // The boundary ρ = 0 (no cord scatter).
    match at_rho(y, x, cord, n_cords, 0.0) {
        Some(z) if z.loglik > best.loglik => Some(z),
        _ => Some(best),
    }
}

/// A cord-level or run-level regression test of the runs' mu.
pub(super) struct BetweenTest {
    /// The catalogue parameter.
    pub value: f64,
    /// Its standard error.
    pub se: f64,
    /// t statistic of the slope.
    pub t: f64,
    /// Its degrees of freedom.
    pub df: f64,
    /// Cords (or runs, for wear): the N of ln N in ΔBIC.
    pub n_units: usize,
    /// Where the evidence comes from.
    pub level: Level,
}

/// Regress the runs' mu `y` on the effect's covariate, at the level where it varies.
///
/// * Between cords (gain: 1/β; diameter: d − 12.7 mm; speed: V − 10 V): the cord means of mu
///   against the covariate by least squares, t with G − 2 degrees of freedom. The cord mean
///   carries the cord's own scatter, so the error term is the cord-to-cord scatter.
/// * Wear: the runs' mu against run − 1 with a separate intercept per cord, t with
///   R − G − 1 degrees of freedom: the error term is the run-to-run scatter within cords.
pub(super) fn between_test(kind: EffectKind, p: &Prepared, y: &[f64]) -> Option<BetweenTest> {
    let nc = p.cords.len();
    if kind == EffectKind::Wear {
        let x: Vec<Vec<f64>> = (0..y.len())
            .map(|u| {
                let mut row = vec![0.0; nc + 1];
                row[p.unit_cord[u]] = 1.0;
                row[nc] = p.unit_run[u] - 1.0;
                row
            })
            .collect();
        if y.len() < nc + 2 {
            return None;
        }
        let r = stats::regress(&x, y, None, None)?;
        let a = stats::mean(&r.coef[..nc]);
        let b = r.coef[nc];
        return Some(BetweenTest {
            value: b / a,
            se: r.se[nc] / a.abs(),
            t: r.t[nc],
            df: r.df,
            n_units: y.len(),
            level: Level::BetweenRun,
        });
    }
    // Cord means.
    let mut sum = vec![0.0; nc];
    let mut cnt = vec![0.0; nc];
    for (u, &m) in y.iter().enumerate() {
        sum[p.unit_cord[u]] += m;
        cnt[p.unit_cord[u]] += 1.0;
    }
    let covariate = |c: &prep::Cord| match kind {
        EffectKind::SensorGain => 1.0 / c.wrap_deg.to_radians(),
        EffectKind::DiameterDependence => c.diameter_mm - REF_DIAMETER_MM,
        _ => c.drive_v - REF_DRIVE_V,
    };
    let x: Vec<Vec<f64>> = p.cords.iter().map(|c| vec![1.0, covariate(c)]).collect();
    let ym: Vec<f64> = sum.iter().zip(&cnt).map(|(s, n)| s / n).collect();
    if nc < 3 {
        return None;
    }
    let r = stats::regress(&x, &ym, None, None)?;
    let (a, b) = (r.coef[0], r.coef[1]);
    let (value, se) = if kind == EffectKind::SensorGain {
        (b.exp(), b.exp() * r.se[1])
    } else {
        (b / a, r.se[1] / a.abs())
    };
    Some(BetweenTest {
        value,
        se,
        t: r.t[1],
        df: r.df,
        n_units: nc,
        level: Level::BetweenCord,
    })
}
