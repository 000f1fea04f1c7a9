//! Small statistics: summaries (mean, variance, median, R², jackknife), distributions, least
//! squares with cluster-robust errors, rank correlation, two-sample and one-sample t tests.

use nalgebra::{DMatrix, DVector};
use serde::Serialize;

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

/// ln Γ(x) (Lanczos, |error| < 1e-14 for x > 0).
pub fn ln_gamma(x: f64) -> f64 {
    const G: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = G[0];
    let t = x + 7.5;
    for (i, g) in G.iter().enumerate().skip(1) {
        a += g / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Regularised incomplete beta I_x(a, b).
pub fn inc_beta(a: f64, b: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let ln_front = ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * x.ln() + b * (1.0 - x).ln();
    if x < (a + 1.0) / (a + b + 2.0) {
        ln_front.exp() * beta_cf(a, b, x) / a
    } else {
        1.0 - ln_front.exp() * beta_cf(b, a, 1.0 - x) / b
    }
}

fn beta_cf(a: f64, b: f64, x: f64) -> f64 {
    let tiny = 1e-300;
    let (qab, qap, qam) = (a + b, a + 1.0, a - 1.0);
    let mut c = 1.0;
    let mut d = 1.0 - qab * x / qap;
    if d.abs() < tiny {
        d = tiny;
    }
    d = 1.0 / d;
    let mut h = d;
    for m in 1..400 {
        let m = m as f64;
        let m2 = 2.0 * m;
        let aa = m * (b - m) * x / ((qam + m2) * (a + m2));
        d = 1.0 + aa * d;
        d = if d.abs() < tiny { tiny } else { d };
        c = 1.0 + aa / c;
        c = if c.abs() < tiny { tiny } else { c };
        d = 1.0 / d;
        h *= d * c;
        let aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
        d = 1.0 + aa * d;
        d = if d.abs() < tiny { tiny } else { d };
        c = 1.0 + aa / c;
        c = if c.abs() < tiny { tiny } else { c };
        d = 1.0 / d;
        let del = d * c;
        h *= del;
        if (del - 1.0).abs() < 1e-15 {
            break;
        }
    }
    h
}

/// Two-sided p-value of a t statistic with `df` degrees of freedom.
pub fn t_p_two_sided(t: f64, df: f64) -> f64 {
    if !t.is_finite() {
        return 0.0;
    }
    inc_beta(0.5 * df, 0.5, df / (df + t * t))
}

/// Upper-tail p-value of an F statistic.
pub fn f_p_upper(f: f64, d1: f64, d2: f64) -> f64 {
    if f <= 0.0 {
        return 1.0;
    }
    inc_beta(0.5 * d2, 0.5 * d1, d2 / (d2 + d1 * f))
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
            let mut meat = DMatrix::<f64>::zeros(k, k);
            let mut n_g = 0;
            for g in 0..g_max {
                let mut s = DVector::<f64>::zeros(k);
                let mut any = false;
                for i in 0..n {
                    if cl[i] == g {
                        any = true;
                        for j in 0..k {
                            s[j] += xw[(i, j)] * resid[i];
                        }
                    }
                }
                if any {
                    n_g += 1;
                    meat += &s * s.transpose();
                }
            }
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
        assert!((ln_gamma(5.0) - 24f64.ln()).abs() < 1e-12);
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
}
