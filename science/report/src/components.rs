//! The variance components of the parameter table with their 95 % intervals, each by a
//! stated method. The estimates are the engine's; only their intervals are computed here, from
//! the estimates and the design's counts (cords, runs per cord, rows, the residuals' lag-1
//! autocorrelation):
//!
//! * an SD of a normal sample on ν degrees of freedom: ν·s²/σ² ~ χ²(ν), so the interval is
//!   s·√(ν/χ²₀.₉₇₅(ν)) to s·√(ν/χ²₀.₀₂₅(ν)) and the large-sample SE s/√(2ν);
//! * the run-to-run SD (the runs' mu about their cord's mean): ν = runs − cords, exact for a
//!   balanced one-way layout under normality;
//! * the cord-to-cord SD, σ_c² = (MSB − MSW)/n₀ of that layout: ν by Satterthwaite's
//!   approximation, (n₀σ_c²)² / (MSB²/(cords − 1) + MSW²/(runs − cords)), with MSW = σ_e² and
//!   MSB = n₀σ_c² + σ_e² (n₀ the runs per cord, Searle's n₀ when unbalanced);
//! * the extended model's σ_u: ν = cords − 1 (as if the cord effects were seen without error;
//!   shrinkage and their own noise are ignored, so the interval is approximate);
//! * the within-run noise: ν = (rows − runs)·(1 − ρ)/(1 + ρ), the rows' residual degrees of
//!   freedom deflated for the lag-1 autocorrelation ρ inside runs (an AR(1) effective sample
//!   size); the two parts of the noise move together;
//! * a model error estimated as √(mean e² − mean v) from held-out residuals e: the mean square
//!   gets a χ² interval with the held-out units (cords) as its degrees of freedom, and mean v
//!   is subtracted from each end (clamped at 0).

use statrs::distribution::{ChiSquared, ContinuousCDF};

/// An interval and an SE.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    /// 95 % lower end.
    pub lo: f64,
    /// 95 % upper end.
    pub hi: f64,
    /// Standard error (None where the method gives none).
    pub se: Option<f64>,
    /// Degrees of freedom behind it.
    pub df: f64,
}

/// The χ² quantiles (2.5 %, 97.5 %) on `df` degrees of freedom.
fn chi2_quantiles(df: f64) -> Option<(f64, f64)> {
    if !(df.is_finite() && df > 0.0) {
        return None;
    }
    let c = ChiSquared::new(df).ok()?;
    Some((c.inverse_cdf(0.025), c.inverse_cdf(0.975)))
}

/// The 95 % interval of an SD `s` estimated on `df` degrees of freedom.
pub fn sd(s: f64, df: f64) -> Option<Interval> {
    if !(s.is_finite() && s > 0.0) {
        return None;
    }
    let (q_lo, q_hi) = chi2_quantiles(df)?;
    Some(Interval {
        lo: s * (df / q_hi).sqrt(),
        hi: s * (df / q_lo).sqrt(),
        se: Some(s / (2.0 * df).sqrt()),
        df,
    })
}

/// Searle's n₀: the runs per cord of an unbalanced one-way layout.
fn n0(runs_per_cord: &[usize]) -> f64 {
    let k = runs_per_cord.len() as f64;
    let n: f64 = runs_per_cord.iter().map(|&r| r as f64).sum();
    let sq: f64 = runs_per_cord.iter().map(|&r| (r * r) as f64).sum();
    if k < 2.0 || n <= 0.0 {
        return f64::NAN;
    }
    (n - sq / n) / (k - 1.0)
}

/// Satterthwaite's degrees of freedom of the cord component σ_c of a one-way layout with run
/// component σ_e.
pub fn cord_df(sigma_c: f64, sigma_e: f64, runs_per_cord: &[usize]) -> f64 {
    let k = runs_per_cord.len() as f64;
    let n: f64 = runs_per_cord.iter().map(|&r| r as f64).sum();
    let n0 = n0(runs_per_cord);
    let within = n - k;
    let msw = sigma_e * sigma_e;
    let msb = n0 * sigma_c * sigma_c + msw;
    let between = (n0 * sigma_c * sigma_c).powi(2);
    let denom = msb * msb / (k - 1.0)
        + if within > 0.0 {
            msw * msw / within
        } else {
            0.0
        };
    if denom > 0.0 {
        between / denom
    } else {
        f64::NAN
    }
}

/// The effective degrees of freedom of the within-run residuals.
pub fn noise_df(rows: usize, runs: usize, lag1: f64) -> f64 {
    let rho = if lag1.is_finite() {
        lag1.clamp(0.0, 0.95)
    } else {
        0.0
    };
    rows.saturating_sub(runs) as f64 * (1.0 - rho) / (1.0 + rho)
}

/// The interval of an excess SD √(h² − a²) from a held-out RMS `h` over `units` independent
/// units and the RMS `a` the other components account for.
pub fn excess_sd(h: f64, a: f64, units: usize) -> Option<Interval> {
    let df = units as f64;
    let (q_lo, q_hi) = chi2_quantiles(df)?;
    if !(h.is_finite() && a.is_finite() && h > 0.0) {
        return None;
    }
    let end = |q: f64| (h * h * df / q - a * a).max(0.0).sqrt();
    Some(Interval {
        lo: end(q_hi),
        hi: end(q_lo),
        se: None,
        df,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_sd_interval_is_the_textbook_one() {
        // s = 1 on 10 df: χ²(10) quantiles 3.247 and 20.483 give 0.699 to 1.755.
        let i = sd(1.0, 10.0).unwrap();
        assert!(
            (i.lo - 0.6987).abs() < 1e-3 && (i.hi - 1.7549).abs() < 1e-3,
            "{i:?}"
        );
        assert!((i.se.unwrap() - 1.0 / 20f64.sqrt()).abs() < 1e-12);
        assert!(sd(0.0, 10.0).is_none() && sd(1.0, 0.0).is_none());
    }

    #[test]
    fn satterthwaite_reduces_to_cords_minus_one_without_run_scatter() {
        // No run component: MSB = n₀σ_c², so ν = cords − 1.
        assert!((cord_df(0.05, 0.0, &[6; 10]) - 9.0).abs() < 1e-9);
        // Run scatter as large as the cord scatter lowers it.
        let df = cord_df(0.05, 0.05, &[6; 10]);
        assert!(df > 5.0 && df < 9.0, "{df}");
        // Unbalanced: n₀ below the mean.
        assert!(n0(&[2, 10]) < 6.0);
    }

    #[test]
    fn the_noise_df_deflates_for_autocorrelation() {
        assert_eq!(noise_df(720, 60, 0.0), 660.0);
        assert!((noise_df(720, 60, 0.5) - 220.0).abs() < 1e-9);
    }

    #[test]
    fn an_excess_sd_interval_holds_its_estimate_and_stops_at_zero() {
        let (h, a) = (1.2, 0.8);
        let i = excess_sd(h, a, 10).unwrap();
        let est = (h * h - a * a).sqrt();
        assert!(i.lo < est && est < i.hi, "{i:?}");
        // Nothing beyond the accounted part: the lower end is 0.
        assert_eq!(excess_sd(0.8, 0.8, 10).unwrap().lo, 0.0);
    }
}
