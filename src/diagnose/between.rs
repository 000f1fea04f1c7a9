//! The runs' mu as a linear mixed model: the cord-to-cord and run-to-run scatter.
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
