//! The runs' mu between runs and cords: their scatter as a linear mixed model ([`fit_lmm`]),
//! and the tests of the effects that vary between cords or runs ([`between_tests`]).
//!
//! Each run's mu m_r comes from the final within-run fit (the shape effects already in). Then
//! the effects that act on mu itself are judged at the level where they vary:
//!
//! * between cords (gain: 1/β, since a T2 gain g adds ln g/β to the apparent mu; diameter:
//!   d − 12.7 mm; speed: V − 10 V): the cords' mean mu regressed on the covariates by least
//!   squares, so the error term is the cord-to-cord scatter; t with G − p degrees of freedom;
//!   forward selection among the three, each addition judged given those already in;
//! * wear (run − 1) varies within cords: the runs' mu with one intercept per cord, error term
//!   the run-to-run scatter, t with R − G − 1 degrees of freedom.
//!
//! The t statistic goes on the likelihood-ratio scale (the χ²₁ value with the same tail
//! probability, an exact small-sample correction), ΔBIC = −χ² + ln N with N the number of
//! cords (or runs, for wear). The random-intercept model
//!
//! m_r = a + u_c(r) + e_r,   u_c ~ N(0, σ_c²) (cord),   e_r ~ N(0, σ_e²) (run),
//!
//! fitted by maximum likelihood (GLS at a given ρ = σ_c²/σ_e², the profile likelihood maximised
//! over ρ), gives the scatter the engine reports.

use super::candidates::{level, practically_relevant, Level};
use super::design::Design;
use super::Evidence;
use crate::fit::stats::{self, chi2_of_t};
use capstan_physics::catalogue::cord_point;
use capstan_physics::entry::Slope;
use capstan_physics::EffectKind;

/// A between-cord effect is named when its cords' t test (cords as units) gives p below this
/// (and its size matters): the level the BIC rule had at the thesis's ten cords (ΔBIC < −6
/// with ln 10: χ²₁ > 8.3), now one level whatever the number of cords. Checked on the
/// calibration seed (11) of the thesis-design campaigns (`capstan_validation::cord_calibration`,
/// 200 per truth): a campaign with nothing between cords but the cords' scatter of mu, T2 zero
/// and heating gets a between-cord claim in 2.5 % (at 0.01: 5.5 %, over the 5 % allowed: the
/// diameter's t test rejects more often than its level on the simulated rig), and mu 10–15 %
/// apart on the two diameters is named in 46.5 % (docs/README-diagnose.md, "Between cords").
pub const CORD_ALPHA: f64 = 0.004;

/// Is `e` supported: between cords, p below [`CORD_ALPHA`]; between runs (wear), ΔBIC below
/// −`threshold`; in both, a size that matters.
pub fn supported(e: &Evidence, d: &Design, threshold: f64) -> bool {
    let relevant = practically_relevant(e.kind, e.value, d);
    relevant
        && match level(e.kind) {
            Level::BetweenCord => e.p < CORD_ALPHA,
            _ => e.delta_bic < -threshold,
        }
}

/// ML fit of the random-intercept model.
#[derive(Clone, Debug)]
pub struct LmmFit {
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
pub fn fit_lmm(y: &[f64], x: &[Vec<f64>], cord: &[usize], n_cords: usize) -> Option<LmmFit> {
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

/// The cord-level covariate of a between-cord effect (its entry's), NaN for any other.
fn covariate(kind: EffectKind, c: &super::design::Cord) -> f64 {
    kind.entry().cord.map_or(f64::NAN, |t| {
        (t.covariate)(&cord_point(c.wrap_deg, c.diameter_mm, c.drive_v))
    })
}

/// Regress the cords' mean mu on an intercept and `kinds`' covariates; the evidence of the
/// last one given the others.
fn cord_regression(d: &Design, cord_mu: &[f64], kinds: &[EffectKind]) -> Option<Evidence> {
    let g = d.cords.len();
    if g < kinds.len() + 2 {
        return None;
    }
    let x: Vec<Vec<f64>> = d
        .cords
        .iter()
        .map(|c| {
            let mut row = vec![1.0];
            row.extend(kinds.iter().map(|&k| covariate(k, c)));
            row
        })
        .collect();
    let r = stats::regress(&x, cord_mu, None, None)?;
    let j = kinds.len();
    let kind = kinds[j - 1];
    let (a, b) = (r.coef[0], r.coef[j]);
    let (value, se) = match kind.entry().cord.map(|t| t.slope) {
        Some(Slope::Exp) => (b.exp(), b.exp() * r.se[j]),
        _ => (b / a, r.se[j] / a.abs()),
    };
    let chi2 = chi2_of_t(r.t[j], r.df);
    Some(Evidence::new(
        kind,
        value,
        se,
        -chi2 + (g as f64).ln(),
        chi2,
        r.df,
    ))
}

/// An effect between runs (wear): the runs' mu on run − 1 with one intercept per cord.
fn between_runs(kind: EffectKind, d: &Design, run_mu: &[f64]) -> Option<Evidence> {
    let nc = d.cords.len();
    if run_mu.len() < nc + 2 {
        return None;
    }
    let x: Vec<Vec<f64>> = (0..run_mu.len())
        .map(|u| {
            let mut row = vec![0.0; nc + 1];
            row[d.unit_cord[u]] = 1.0;
            row[nc] = d.unit_run[u] - 1.0;
            row
        })
        .collect();
    let r = stats::regress(&x, run_mu, None, None)?;
    let a = stats::mean(&r.coef[..nc]);
    let b = r.coef[nc];
    let chi2 = chi2_of_t(r.t[nc], r.df);
    let n = run_mu.len() as f64;
    Some(Evidence::new(
        kind,
        b / a,
        r.se[nc] / a.abs(),
        -chi2 + n.ln(),
        chi2,
        r.df,
    ))
}

/// The cords' mean of their runs' mu.
pub fn cord_means(d: &Design, run_mu: &[f64]) -> Vec<f64> {
    let nc = d.cords.len();
    let (mut sum, mut cnt) = (vec![0.0; nc], vec![0.0; nc]);
    for (u, &m) in run_mu.iter().enumerate() {
        sum[d.unit_cord[u]] += m;
        cnt[d.unit_cord[u]] += 1.0;
    }
    sum.iter().zip(&cnt).map(|(s, n)| s / n).collect()
}

/// What the between-level tests found.
pub struct BetweenTests {
    /// Every testable candidate's evidence: selected ones given the other selected, the rest
    /// added to them.
    pub evidence: Vec<Evidence>,
    /// The selected effects.
    pub selected: Vec<EffectKind>,
    /// Every candidate's evidence alone.
    pub alone: Vec<Evidence>,
}

/// The between-level effects on the runs' mu: forward selection among the cord-level ones
/// (each addition must be supported given those in), wear on its own.
pub fn between_tests(
    d: &Design,
    run_mu: &[f64],
    testable: &[EffectKind],
    threshold: f64,
) -> BetweenTests {
    let cord_mu = cord_means(d, run_mu);
    let supported = |e: &Evidence| supported(e, d, threshold);
    let pool: Vec<EffectKind> = testable
        .iter()
        .copied()
        .filter(|&k| level(k) == Level::BetweenCord)
        .collect();
    let mut chosen: Vec<EffectKind> = Vec::new();
    let mut last: Vec<Evidence>;
    let mut alone: Option<Vec<Evidence>> = None;
    loop {
        last = pool
            .iter()
            .filter(|k| !chosen.contains(k))
            .filter_map(|&k| {
                let mut ks = chosen.clone();
                ks.push(k);
                cord_regression(d, &cord_mu, &ks)
            })
            .collect();
        if alone.is_none() {
            alone = Some(last.clone());
        }
        let best = last
            .iter()
            .filter(|e| supported(e))
            .min_by(|a, b| a.delta_bic.total_cmp(&b.delta_bic));
        match best {
            Some(e) => chosen.push(e.kind),
            None => break,
        }
    }
    let mut out = last;
    // The chosen ones, each given the others.
    for (i, &k) in chosen.iter().enumerate() {
        let mut ks: Vec<EffectKind> = chosen.iter().copied().filter(|&x| x != k).collect();
        ks.push(k);
        if let Some(e) = cord_regression(d, &cord_mu, &ks) {
            out.insert(i, e);
        }
    }
    let mut alone = alone.unwrap_or_default();
    for &k in testable.iter().filter(|&&k| level(k) == Level::BetweenRun) {
        if let Some(e) = between_runs(k, d, run_mu) {
            if supported(&e) {
                chosen.push(k);
            }
            alone.push(e.clone());
            out.push(e);
        }
    }
    for e in &mut alone {
        e.relevant = practically_relevant(e.kind, e.value, d);
        e.supported = supported(e);
    }
    BetweenTests {
        evidence: out,
        selected: chosen,
        alone,
    }
}
