//! Small statistics: summaries (mean, variance, median, R², jackknife), distributions, least
//! squares with cluster-robust errors, rank correlation, two-sample and one-sample t tests.

use nalgebra::{DMatrix, DVector};
use serde::Serialize;
use statrs::distribution::{ChiSquared, ContinuousCDF, FisherSnedecor, StudentsT};

/// Arithmetic mean (NaN for an empty slice).
pub fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

/// Sample variance Σ(x − x̄)²/(n − 1).
pub fn variance(v: &[f64]) -> f64 {
    let m = mean(v);
    v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() as f64 - 1.0)
}

/// Median (mean of the middle two for an even count; NaN for an empty slice). Sorts `v`.
pub fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        return f64::NAN;
    }
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// The distinct values, ascending (equal when bit-identical).
pub fn distinct(v: impl IntoIterator<Item = f64>) -> Vec<f64> {
    let mut out: Vec<f64> = v.into_iter().collect();
    out.sort_by(f64::total_cmp);
    out.dedup_by(|a, b| a.to_bits() == b.to_bits());
    out
}

/// R² = 1 − SS_res/SS_tot of measured against predicted values.
pub fn r_squared(measured: &[f64], predicted: &[f64]) -> f64 {
    let m = mean(measured);
    let ss_res: f64 = measured
        .iter()
        .zip(predicted)
        .map(|(y, p)| (y - p).powi(2))
        .sum();
    let ss_tot: f64 = measured.iter().map(|y| (y - m).powi(2)).sum();
    1.0 - ss_res / ss_tot
}

/// Jackknife standard error of an estimate from its leave-one-out values:
/// √((G − 1)/G · Σ(v − v̄)²).
pub fn jackknife_se(values: &[f64]) -> f64 {
    let g = values.len() as f64;
    let m = mean(values);
    let ss: f64 = values.iter().map(|v| (v - m).powi(2)).sum();
    ((g - 1.0) / g * ss).sqrt()
}

/// Two-sided p-value of a t statistic with `df` degrees of freedom (statrs' Student t).
pub fn t_p_two_sided(t: f64, df: f64) -> f64 {
    if !t.is_finite() {
        return 0.0;
    }
    match StudentsT::new(0.0, 1.0, df.max(1e-9)) {
        Ok(d) => 2.0 * d.sf(t.abs()),
        Err(_) => f64::NAN,
    }
}

/// Upper-tail p-value of an F statistic (statrs' Fisher-Snedecor).
pub fn f_p_upper(f: f64, d1: f64, d2: f64) -> f64 {
    if f <= 0.0 {
        return 1.0;
    }
    if !f.is_finite() {
        return 0.0;
    }
    match FisherSnedecor::new(d1.max(1e-9), d2.max(1e-9)) {
        Ok(d) => d.sf(f),
        Err(_) => f64::NAN,
    }
}

/// The χ² value with `df` degrees of freedom whose upper-tail probability is `p`: puts any
/// test on the likelihood-ratio scale of an information criterion. Far in the tail (p below
/// 1e-300, where the quantile no longer resolves) it returns `fallback`.
pub fn chi2_with_tail(p: f64, df: f64, fallback: f64) -> f64 {
    if p.is_nan() {
        return 0.0;
    }
    if p >= 1.0 {
        return 0.0;
    }
    if p <= 1e-300 {
        return fallback;
    }
    match ChiSquared::new(df) {
        // Quantile of the upper tail: for small p through the lower tail of the complement
        // loses digits, so use the inverse survival function by bisection on sf.
        Ok(d) => {
            let (mut lo, mut hi) = (0.0f64, fallback.max(1.0));
            while d.sf(hi) > p && hi < 1e6 {
                hi *= 2.0;
            }
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if d.sf(mid) > p {
                    lo = mid;
                } else {
                    hi = mid;
                }
                if hi - lo <= 1e-12 * hi {
                    break;
                }
            }
            0.5 * (lo + hi)
        }
        Err(_) => fallback,
    }
}

/// A t statistic with `df` degrees of freedom on the χ²₁ scale (same two-sided tail).
pub fn chi2_of_t(t: f64, df: f64) -> f64 {
    if !t.is_finite() {
        return 0.0;
    }
    chi2_with_tail(t_p_two_sided(t, df), 1.0, t * t)
}

/// Upper-tail p of a χ² value with `df` degrees of freedom (1 for NaN or below 0: no evidence).
pub fn chi2_p_upper(chi2: f64, df: f64) -> f64 {
    if chi2.is_nan() || chi2 <= 0.0 {
        return 1.0;
    }
    if chi2.is_infinite() {
        return 0.0;
    }
    ChiSquared::new(df).map_or(f64::NAN, |d| d.sf(chi2))
}

/// An F statistic with (d1, d2) degrees of freedom on the χ²_{d1} scale (same upper tail): a
/// quasi-likelihood ratio divided by an overdispersion estimated from d2 clusters.
pub fn chi2_of_f(f: f64, d1: f64, d2: f64) -> f64 {
    if !(f.is_finite() && f > 0.0) {
        return 0.0;
    }
    chi2_with_tail(f_p_upper(f, d1, d2), d1, f * d1)
}

/// A linear regression with standard errors.
#[derive(Clone, Debug, Serialize)]
pub struct Regression {
    /// Coefficients.
    pub coef: Vec<f64>,
    /// Standard errors (cluster-robust if clusters were given).
    pub se: Vec<f64>,
    /// t statistics.
    pub t: Vec<f64>,
    /// Two-sided p-values (df = n − k, or G − 1 with clusters).
    pub p: Vec<f64>,
    /// Residual sum of squares.
    pub rss: f64,
    /// Degrees of freedom used for p.
    pub df: f64,
    /// R².
    pub r2: f64,
}

/// Weighted least squares y ~ X (rows of `x`), with optional weights and clusters (CR1
/// sandwich, G − 1 degrees of freedom). Returns None if XᵀWX is singular.
pub fn regress(
    x: &[Vec<f64>],
    y: &[f64],
    weights: Option<&[f64]>,
    clusters: Option<&[usize]>,
) -> Option<Regression> {
    let n = y.len();
    let k = x.first()?.len();
    let xm = DMatrix::from_fn(n, k, |i, j| x[i][j]);
    let w: Vec<f64> = weights.map_or_else(|| vec![1.0; n], <[f64]>::to_vec);
    let sw = DVector::from_iterator(n, w.iter().map(|v| v.sqrt()));
    let xw = DMatrix::from_fn(n, k, |i, j| xm[(i, j)] * sw[i]);
    let yw = DVector::from_fn(n, |i, _| y[i] * sw[i]);
    let xtx_inv = (xw.transpose() * &xw).try_inverse()?;
    let coef = &xtx_inv * xw.transpose() * &yw;
    let resid = &yw - &xw * &coef;
    let rss = resid.norm_squared();
    let ybar = y.iter().zip(&w).map(|(a, b)| a * b).sum::<f64>() / w.iter().sum::<f64>();
    let tss: f64 = y.iter().zip(&w).map(|(a, b)| b * (a - ybar).powi(2)).sum();
    let (cov, df) = match clusters {
        None => {
            let df = (n - k) as f64;
            (xtx_inv.clone() * (rss / df), df)
        }
        Some(cl) => {
            let g_max = cl.iter().copied().max().unwrap_or(0) + 1;
            // Each cluster's score, accumulated in one pass over the rows.
            let mut scores = vec![DVector::<f64>::zeros(k); g_max];
            let mut seen = vec![false; g_max];
            for i in 0..n {
                seen[cl[i]] = true;
                for j in 0..k {
                    scores[cl[i]][j] += xw[(i, j)] * resid[i];
                }
            }
            let mut meat = DMatrix::<f64>::zeros(k, k);
            for s in scores.iter() {
                meat += s * s.transpose();
            }
            let n_g = seen.iter().filter(|&&x| x).count();
            let g = n_g as f64;
            let c = g / (g - 1.0) * (n as f64 - 1.0) / (n as f64 - k as f64);
            (&xtx_inv * meat * &xtx_inv * c, g - 1.0)
        }
    };
    let coef: Vec<f64> = coef.iter().copied().collect();
    let se: Vec<f64> = (0..k).map(|j| cov[(j, j)].max(0.0).sqrt()).collect();
    let t: Vec<f64> = coef.iter().zip(&se).map(|(c, s)| c / s).collect();
    let p = t.iter().map(|&t| t_p_two_sided(t, df)).collect();
    Some(Regression {
        coef,
        se,
        t,
        p,
        rss,
        df,
        r2: 1.0 - rss / tss,
    })
}

/// Average ranks (ties share their mean rank), 1-based.
pub fn ranks(v: &[f64]) -> Vec<f64> {
    let mut idx: Vec<usize> = (0..v.len()).collect();
    idx.sort_by(|&a, &b| v[a].total_cmp(&v[b]));
    let mut r = vec![0.0; v.len()];
    let mut i = 0;
    while i < idx.len() {
        let mut j = i;
        while j + 1 < idx.len() && v[idx[j + 1]] == v[idx[i]] {
            j += 1;
        }
        let avg = 0.5 * (i + j) as f64 + 1.0;
        for k in i..=j {
            r[idx[k]] = avg;
        }
        i = j + 1;
    }
    r
}

/// Pearson correlation.
pub fn pearson(a: &[f64], b: &[f64]) -> f64 {
    let (ma, mb) = (mean(a), mean(b));
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma).powi(2);
        sbb += (y - mb).powi(2);
    }
    sab / (saa * sbb).sqrt()
}

/// Spearman rank correlation.
pub fn spearman(a: &[f64], b: &[f64]) -> f64 {
    pearson(&ranks(a), &ranks(b))
}

/// Share of the variance of `y` explained by the levels of `level` (η²), and the one-way
/// ANOVA F test (observations treated as independent).
pub fn eta_squared(y: &[f64], level: &[usize]) -> (f64, f64, f64) {
    let n = y.len() as f64;
    let k = level.iter().copied().max().map_or(0, |m| m + 1);
    let ybar = mean(y);
    let mut sums = vec![0.0; k];
    let mut counts = vec![0.0; k];
    for (v, &l) in y.iter().zip(level) {
        sums[l] += v;
        counts[l] += 1.0;
    }
    let ssb: f64 = (0..k)
        .filter(|&l| counts[l] > 0.0)
        .map(|l| counts[l] * (sums[l] / counts[l] - ybar).powi(2))
        .sum();
    let sst: f64 = y.iter().map(|v| (v - ybar).powi(2)).sum();
    let levels = counts.iter().filter(|c| **c > 0.0).count() as f64;
    let (d1, d2) = (levels - 1.0, n - levels);
    let f = if d1 > 0.0 && sst > ssb {
        (ssb / d1) / ((sst - ssb) / d2)
    } else {
        0.0
    };
    (ssb / sst, f, f_p_upper(f, d1.max(1.0), d2.max(1.0)))
}

/// Welch's two-sample t test: (t, df, p).
pub fn welch(a: &[f64], b: &[f64]) -> (f64, f64, f64) {
    let mv = |v: &[f64]| (mean(v), variance(v), v.len() as f64);
    let (ma, va, na) = mv(a);
    let (mb, vb, nb) = mv(b);
    let se2 = va / na + vb / nb;
    let t = (ma - mb) / se2.sqrt();
    let df = se2 * se2 / ((va / na).powi(2) / (na - 1.0) + (vb / nb).powi(2) / (nb - 1.0));
    (t, df, t_p_two_sided(t, df))
}

/// One-sample t test of the mean against zero: (mean, t, p).
pub fn one_sample_t(v: &[f64]) -> (f64, f64, f64) {
    let n = v.len() as f64;
    let m = mean(v);
    let sd = variance(v).sqrt();
    let t = m / (sd / n.sqrt());
    (m, t, t_p_two_sided(t, n - 1.0))
}

/// Holm's step-down adjustment of a family of p-values (strong control of the family-wise
/// error rate, never less powerful than Bonferroni's): the i-th smallest p times (m − i), kept
/// non-decreasing, at most 1. Non-finite p-values are not tests: they stay NaN and do not
/// count in m. By hand because `adjustp`, the crate for p-value adjustments, has Bonferroni
/// and Benjamini's procedures but not Holm's.
pub fn holm(p: &[f64]) -> Vec<f64> {
    let mut order: Vec<usize> = (0..p.len()).filter(|&i| p[i].is_finite()).collect();
    order.sort_by(|&i, &j| p[i].total_cmp(&p[j]));
    let m = order.len();
    let mut out = vec![f64::NAN; p.len()];
    let mut running = 0.0_f64;
    for (k, &i) in order.iter().enumerate() {
        running = running.max(((m - k) as f64 * p[i]).min(1.0));
        out[i] = running;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn summaries() {
        let v = [3.0, 1.0, 4.0, 1.0, 5.0];
        assert_eq!(mean(&v), 2.8);
        assert!((variance(&v) - 3.2).abs() < 1e-12);
        assert_eq!(median(&mut v.clone()), 3.0);
        assert_eq!(median(&mut [4.0, 1.0, 2.0, 3.0]), 2.5);
        assert_eq!(distinct(v), vec![1.0, 3.0, 4.0, 5.0]);
        assert_eq!(r_squared(&[1.0, 2.0, 3.0], &[1.0, 2.0, 3.0]), 1.0);
        assert_eq!(r_squared(&[1.0, 2.0, 3.0], &[2.0, 2.0, 2.0]), 0.0);
        // Leave-one-out means of 1..=4: the jackknife SE equals the SE of the mean.
        let loo: Vec<f64> = (1..=4).map(|k| (10.0 - k as f64) / 3.0).collect();
        let se_mean = (variance(&[1.0, 2.0, 3.0, 4.0]) / 4.0).sqrt();
        assert!((jackknife_se(&loo) - se_mean).abs() < 1e-12);
    }

    #[test]
    fn distributions_match_tables() {
        // t(10) two-sided 5 % critical value 2.228; F(2, 20) 5 % critical value 3.493.
        assert!((t_p_two_sided(2.228_138_9, 10.0) - 0.05).abs() < 1e-6);
        assert!((f_p_upper(3.492_828, 2.0, 20.0) - 0.05).abs() < 1e-6);
        // χ² scale: a two-sided t of 1.96 with many df is χ²₁ = 3.84; F(1, ∞) = χ²₁.
        assert!((chi2_of_t(1.959_964, 1e6) - 3.841_459).abs() < 1e-4);
        assert!((chi2_of_f(3.841_459, 1.0, 1e7) - 3.841_459).abs() < 1e-3);
        // Few clusters make the same statistic weaker evidence.
        assert!(chi2_of_f(10.0, 1.0, 9.0) < 7.0);
        assert_eq!(chi2_with_tail(1e-320, 1.0, 1234.0), 1234.0);
    }

    #[test]
    fn regression_recovers_a_line_and_spearman_ranks() {
        let x: Vec<Vec<f64>> = (0..20).map(|i| vec![1.0, i as f64]).collect();
        let y: Vec<f64> = (0..20)
            .map(|i| 2.0 + 0.5 * i as f64 + if i % 2 == 0 { 0.1 } else { -0.1 })
            .collect();
        let r = regress(&x, &y, None, None).unwrap();
        assert!((r.coef[1] - 0.5).abs() < 0.01);
        let cl: Vec<usize> = (0..20).map(|i| i / 5).collect();
        let rc = regress(&x, &y, None, Some(&cl)).unwrap();
        assert_eq!(rc.df, 3.0);
        assert!((spearman(&[1.0, 2.0, 3.0], &[10.0, 20.0, 25.0]) - 1.0).abs() < 1e-12);
        assert_eq!(ranks(&[3.0, 1.0, 3.0]), vec![2.5, 1.0, 2.5]);
    }

    #[test]
    fn holm_steps_down() {
        let a = super::holm(&[0.01, 0.04, 0.03, f64::NAN, 0.5]);
        // m = 4: 0.01·4, then max(0.04, 0.03·3), 0.04·2, 0.5·1.
        let want = [0.04, 0.09, 0.09, f64::NAN, 0.5];
        for (x, w) in a.iter().zip(want) {
            assert!(x.is_nan() && w.is_nan() || (x - w).abs() < 1e-12, "{a:?}");
        }
    }
}
