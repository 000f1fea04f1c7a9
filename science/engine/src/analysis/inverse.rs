//! The design question read backwards: the T1 that gives a wanted T2 at a wrap, diameter and
//! drive voltage, by the same population-averaged model and intervals as
//! [`super::prediction::predict`].
//!
//! - `t1_n`: the T1 at which the mean curve reaches the target.
//! - `t1_ci95`: the T1 values at which the curve's 95 % confidence band reaches it (the
//!   inverse-regression, Fieller-type interval: every T1 whose confidence interval holds the
//!   target). Its low end is where the band's upper edge reaches the target, its high end where
//!   the lower edge does.
//! - `t1_for_sure`: the T1 at which a new cord reaches the target with probability `sure`.
//!   This is where the new-cord predictive distribution's lower `1 − sure` quantile meets it:
//!   T2 − t(sure, dof)·√(curve variance + new cord's error), the distribution of the forward
//!   prediction interval. At `sure` = 0.975 it is the T1 whose forward 95 % prediction
//!   interval begins at the target.
//!
//! Each is the root of a curve in T1 that rises with T1 (the friction law's T2 does, and so
//! do its band edges at these error sizes). A bisection finds it. It is safe on any bracketed
//! sign change, needs no derivative of the heating's fixed point, and converges to 1e-13
//! relative in about 45 halvings. Brent's method would save a few dozen evaluations, which is
//! not worth a dependency here.

use super::prediction::{spread, t2_of, t95, t_quantile, Interval, PredictionModel, Query};

/// One required T2 with the T1 it needs (the JSON contract of `capstan predict --t2-n`).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Needed {
    /// The wanted T2, N.
    pub t2_n: f64,
    /// T1 at which the mean curve gives `t2_n`, N (`None`: no T1 in range gives it).
    pub t1_n: Option<f64>,
    /// The T1 values whose 95 % confidence interval of the mean T2 holds `t2_n`, N.
    pub t1_ci95: Option<Interval>,
    /// T1 at which a new cord reaches `t2_n` with probability `sure`, N.
    pub t1_for_sure: Option<f64>,
    /// That probability.
    pub sure: f64,
}

/// The largest T1 searched, N (the data's tension range).
const T1_MAX_N: f64 = 1.0e4;
/// The smallest T1 searched, N.
const T1_MIN_N: f64 = 1.0e-9;

/// The root in T1 of `g(T1) = target`, `g` rising in T1, bracketed in [T1_MIN_N, T1_MAX_N]
/// (`None` when `g` is above the target already at the bottom or below it at the top).
fn solve(target: f64, g: impl Fn(f64) -> f64) -> Option<f64> {
    let (mut lo, mut hi) = (T1_MIN_N, target.clamp(T1_MIN_N, T1_MAX_N));
    // The physical T2 is at least T1, so T1 = target is above the root; as measured, a sensor
    // offset or gain may put it below: widen until the curve passes the target.
    while g(hi) < target {
        if hi >= T1_MAX_N {
            return None;
        }
        lo = hi;
        hi = (hi * 2.0).min(T1_MAX_N);
    }
    if g(lo) > target {
        return None;
    }
    if g(hi) == target {
        return Some(hi);
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if g(mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo <= 1e-13 * hi {
            break;
        }
    }
    Some(0.5 * (lo + hi))
}

/// The T1 that gives `t2_n` at `at`'s wrap, diameter and voltage (its `t1_n` is ignored), with
/// its intervals; no intervals where [`PredictionModel::unidentified`] says the data cannot
/// give them.
pub fn t1_for(pm: &PredictionModel, at: &Query, t2_n: f64, sure: f64) -> Needed {
    let q = |t1_n: f64| Query { t1_n, ..*at };
    let model = pm.model(None);
    let floor = |t1: f64| {
        if at.as_measured {
            f64::NEG_INFINITY
        } else {
            t1
        }
    };
    let t1_n = solve(t2_n, |t1| t2_of(&model, &q(t1)));
    let identified = pm.unidentified(at).is_none();
    let t_ci = t95(pm.folds.saturating_sub(1));
    let t_new = t_quantile(sure, pm.new_cord_error.dof.max(1));
    // A band edge: T2 + k·SD at T1, held at T1 as the forward interval is.
    let ci_edge = |k: f64| {
        move |t1: f64| {
            let s = spread(pm, &q(t1));
            (s.t2 + k * t_ci * s.var_mean.sqrt()).max(floor(t1))
        }
    };
    let t1_ci95 = identified
        .then(|| Some((solve(t2_n, ci_edge(1.0))?, solve(t2_n, ci_edge(-1.0))?)))
        .flatten()
        .map(|(lo, hi)| Interval { lo, hi });
    let sure_edge = |t1: f64| {
        let s = spread(pm, &q(t1));
        let var_new = pm.new_cord_error.variance(s.t2)
            + pm.wrap_extrapolation_sd(at.wrap_deg).unwrap_or(0.0).powi(2);
        (s.t2 - t_new * (s.var_mean + var_new).sqrt()).max(floor(t1))
    };
    let t1_for_sure = identified.then(|| solve(t2_n, sure_edge)).flatten();
    Needed {
        t2_n,
        t1_n,
        t1_ci95,
        t1_for_sure,
        sure,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::prediction::{
        predict, FittedRange, ModelError, NewCordError, Span, NOTE, SCHEMA,
    };
    use std::collections::BTreeMap;

    /// Euler-Eytelwein with mu = 0.2 (no heating, no sensor terms), mu's SD 0.01 between
    /// cords' refits (10 folds), a new cord's error √(0.5² + (0.05·T2)²) N over 10 cords,
    /// fitted on 12.7–25.4 mm, 270–720°, 0.1–25 N, 10 V.
    fn plain(mu_change_per_mm: f64) -> PredictionModel {
        let mut values = BTreeMap::new();
        for (k, v) in [
            ("mu", 0.2),
            ("mu_change_per_mm", mu_change_per_mm),
            ("n", 1.0),
            ("t2_gain", 1.0),
        ] {
            values.insert(k.to_string(), v);
        }
        PredictionModel {
            schema: SCHEMA,
            values,
            free: vec!["mu".into()],
            covariance: vec![vec![1e-4]],
            folds: 10,
            new_cord_error: NewCordError {
                abs_n: 0.5,
                rel: 0.05,
                dof: 8,
                heldout_rms_n: 1.0,
                rows: 100,
                cords: 10,
            },
            wrap_extrapolation_error: ModelError::NONE,
            wrap_extrapolation_step_deg: 0.0,
            fitted_range: FittedRange {
                wrap_deg: Span {
                    min: 270.0,
                    max: 720.0,
                },
                diameter_mm: Span {
                    min: 12.7,
                    max: 25.4,
                },
                t1_n: Span {
                    min: 0.1,
                    max: 25.0,
                },
                drive_v: Span {
                    min: 10.0,
                    max: 10.0,
                },
            },
            note: NOTE.into(),
        }
    }

    fn at(wrap_deg: f64, diameter_mm: f64) -> Query {
        Query {
            wrap_deg,
            diameter_mm,
            drive_v: 10.0,
            t1_n: 1.0,
            as_measured: false,
        }
    }

    /// T2 = T1·e^(0.2·2π) = 3.5136·T1 at 360°: 30 N needs 8.5383 N, and the forward
    /// prediction at each solved T1 gives back the wanted T2 on the curve, the band edges and
    /// the 97.5 % prediction interval's lower end.
    #[test]
    fn t1_for_a_wanted_t2_inverts_the_forward_prediction() {
        let pm = plain(0.0);
        let q = at(360.0, 20.0);
        let n = t1_for(&pm, &q, 30.0, 0.975);
        let t1 = n.t1_n.unwrap();
        assert!(
            (t1 - 30.0 / (0.4 * std::f64::consts::PI).exp()).abs() < 1e-9,
            "{t1}"
        );
        assert!((t1 - 8.5383).abs() < 1e-4, "{t1}");
        // Round trip T1 → T2 → T1.
        for t1_0 in [0.3, 2.0, 8.0, 20.0] {
            let t2 = predict(&pm, &Query { t1_n: t1_0, ..q }).t2_n;
            let back = t1_for(&pm, &q, t2, 0.975).t1_n.unwrap();
            assert!((back - t1_0).abs() < 1e-6, "{t1_0} → {t2} → {back}");
        }
        let ci = n.t1_ci95.unwrap();
        assert!(ci.lo < t1 && t1 < ci.hi, "{ci:?}");
        let fwd = |t1_n: f64| predict(&pm, &Query { t1_n, ..q });
        assert!((fwd(ci.lo).t2_ci95.hi - 30.0).abs() < 1e-6);
        assert!((fwd(ci.hi).t2_ci95.lo - 30.0).abs() < 1e-6);
        // The band is T2 ± t(9)·T2·2π·0.01 (delta method in mu) with T2 = 3.5136·T1, so its
        // edges reach 30 N at T1 = 30 / (3.5136·(1 ± 2π·0.01·2.262)): 7.4756 and 9.9530 N.
        let (e, k) = (
            (0.4 * std::f64::consts::PI).exp(),
            0.02 * std::f64::consts::PI * t_quantile(0.975, 9),
        );
        assert!((ci.lo - 30.0 / (e * (1.0 + k))).abs() < 1e-5, "{ci:?}");
        assert!((ci.hi - 30.0 / (e * (1.0 - k))).abs() < 1e-5, "{ci:?}");
        assert!(
            (ci.lo - 7.4756).abs() < 1e-3 && (ci.hi - 9.9530).abs() < 1e-3,
            "{ci:?}"
        );
        let sure = n.t1_for_sure.unwrap();
        assert!((fwd(sure).t2_pi95.lo - 30.0).abs() < 1e-6, "{sure}");
        assert!(
            sure > ci.hi,
            "a new cord needs more margin than the mean curve"
        );
        // Surer needs more T1; a coin toss needs about the mean curve's.
        let s99 = t1_for(&pm, &q, 30.0, 0.99).t1_for_sure.unwrap();
        let s50 = t1_for(&pm, &q, 30.0, 0.5).t1_for_sure.unwrap();
        assert!(s99 > sure && (s50 - t1).abs() < 1e-6, "{s99} {s50}");
    }

    /// mu falling 1 % per mm reaches 0 at 12.7 + 100 = 112.7 mm: at 1000 mm the law holds T2
    /// at T1, every refit agrees, and the interval would have no width. It is not identified
    /// there, nor anywhere outside the fitted diameters; inside it is.
    #[test]
    fn where_the_clamp_binds_or_the_diameter_leaves_the_fitted_the_interval_is_not_identified() {
        let pm = plain(-0.01);
        let far = at(360.0, 1000.0);
        let p = predict(&pm, &Query { t1_n: 5.0, ..far });
        assert_eq!(p.t2_n, 5.0);
        assert_eq!(p.t2_ci95.hi - p.t2_ci95.lo, 0.0);
        let why = pm.unidentified(&far).unwrap();
        assert!(why.contains("mu to 0 or below at 1000 mm"), "{why}");
        assert!(why.contains("diameter 1000 mm is outside"), "{why}");
        let n = t1_for(&pm, &far, 30.0, 0.975);
        assert_eq!(n.t1_n, Some(30.0));
        assert_eq!((n.t1_ci95, n.t1_for_sure), (None, None));
        let near = at(360.0, 30.0);
        assert!(pm.unidentified(&near).unwrap().contains("diameter 30 mm"));
        assert!(pm.unidentified(&at(360.0, 20.0)).is_none());
        let volts = Query {
            drive_v: 12.0,
            ..at(360.0, 20.0)
        };
        assert!(pm
            .unidentified(&volts)
            .unwrap()
            .contains("drive voltage 12 V"));
        // Beyond the fitted wraps with no measured extrapolation error: not identified either.
        assert!(pm
            .unidentified(&at(900.0, 20.0))
            .unwrap()
            .contains("wrap 900°"));
    }
}
