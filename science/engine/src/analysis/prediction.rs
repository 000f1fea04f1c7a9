//! The fitted model as something to use: T2 and amplification at a wrap, diameter and T1 of
//! the user's choosing, with a 95 % confidence interval (the mean curve) and a 95 % prediction
//! interval (a new measurement on a new cord).
//!
//! [`PredictionModel`] is what `metrics.json` carries under `prediction_model` (schema
//! [`SCHEMA`]): the population-averaged model (the named causes and one mu for all cords, by
//! least squares in T2: a new cord's own mu is unknown, so it is predicted by the curve averaged
//! over cords), the covariance of its free values over its leave-one-cord-out refits (a cord
//! jackknife: cords as the independent units), and a new cord's error around that curve
//! ([`NewCordError`]): a² + (b·T2)², fitted to the held-out residuals of the whole procedure
//! (every cord predicted by the causes chosen and fitted without it) beyond the curve's own
//! uncertainty — so what a new cord really does, its mu, T2 zero and heating scattered, the
//! runs' scatter and the noise, all at once, and growing with T2 as the held-out residuals do.
//! No variance component of a fit's penalty enters (a penalty capped to keep the parameter
//! count collapses the cords' scatter). `capstan predict` reads it back ([`predict`]);
//! [`coverage`] checks it cord by cord.
//!
//! The operating point of a prediction: the given wrap, diameter and drive voltage, the first
//! run of a fresh cord at the trigger (time 0), and the contact's load memory settled under the
//! held T1 (H = τ·(T2 − T1): the thesis's 10 s steps are 40 τ long). Physical predictions use
//! the friction law alone (sensor terms off): T2 ≥ T1 whatever the parameters, since the law's
//! mu is never negative. `as_measured` adds the fitted sensor terms (what the rig would read).

use crate::fit::Param;
use capstan_physics::{Model, Operating, REF_DRIVE_V};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Version of the `prediction_model` object; `capstan predict` refuses another. 2 added
/// `model_error`; 4 is the population-averaged model with a new cord's error from the held-out
/// residuals (`new_cord_error`), in place of the mixed model's variance components.
pub const SCHEMA: u32 = 4;

/// A closed range of the fitted data.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Span {
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
}

impl Span {
    fn of(v: impl Iterator<Item = f64>) -> Span {
        v.filter(|x| x.is_finite()).fold(
            Span {
                min: f64::INFINITY,
                max: f64::NEG_INFINITY,
            },
            |s, x| Span {
                min: s.min.min(x),
                max: s.max.max(x),
            },
        )
    }

    /// True when `x` lies in the span (with a relative slack of 1e-9).
    pub fn contains(&self, x: f64) -> bool {
        let eps = 1e-9 * self.max.abs().max(1.0);
        x >= self.min - eps && x <= self.max + eps
    }
}

/// The fitted data's ranges: a prediction outside them extrapolates.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FittedRange {
    /// Wraps fitted, deg.
    pub wrap_deg: Span,
    /// Capstan diameters fitted, mm.
    pub diameter_mm: Span,
    /// Measured T1, N.
    pub t1_n: Span,
    /// Drive voltages (the reference voltage when the data have none), V.
    pub drive_v: Span,
}

/// The population-averaged model with its uncertainty, as `metrics.json` carries it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PredictionModel {
    /// [`SCHEMA`].
    pub schema: u32,
    /// Population value of every model parameter, by name (`capstan_engine::fit::Param`).
    pub values: BTreeMap<String, f64>,
    /// The free parameters, in the order of `covariance`.
    pub free: Vec<String>,
    /// Covariance of the free parameters' values over the leave-one-cord-out refits (cord
    /// jackknife, (k − 1)/k Σ (v_k − v̄)(v_k − v̄)ᵀ).
    pub covariance: Vec<Vec<f64>>,
    /// Folds behind `covariance` (cords or groups of cords left out).
    pub folds: usize,
    /// A new cord's error around the curve.
    pub new_cord_error: NewCordError,
    /// What extrapolating in wrap adds: the residuals of fits without the smallest or the
    /// largest wrap, on that wrap, beyond the curve's uncertainty and `new_cord_error` (see
    /// [`wrap_extrapolation`]); in the prediction interval only at wraps outside the fitted
    /// ones' span, growing with the distance (see [`PredictionModel::wrap_extrapolation_sd`]).
    /// No rows: not measured (fewer than three wraps).
    pub wrap_extrapolation_error: ModelError,
    /// The distance, deg, over which `wrap_extrapolation_error` was measured: the mean gap
    /// between the smallest wrap and the next, and the largest and the one before (0 when not
    /// measured).
    pub wrap_extrapolation_step_deg: f64,
    /// What the fitted data span.
    pub fitted_range: FittedRange,
    /// The operating point and intervals in words.
    pub note: String,
}

/// A new cord's error in T2 around the population-averaged curve: variance a² + (b·T2)²,
/// fitted by least squares to the squared held-out residuals of the whole procedure less the
/// curve's own variance at each row (a method-of-moments estimate, both parts kept ≥ 0). The
/// mean square, not the variance about the mean: a cord that sits off the curve is a new
/// cord's error too. The prediction interval takes Student's t with `dof` degrees of freedom
/// (cords − 2: the two parts come from that many cords' residuals).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct NewCordError {
    /// a, N.
    pub abs_n: f64,
    /// b, fraction of T2.
    pub rel: f64,
    /// Degrees of freedom of the interval's t.
    pub dof: usize,
    /// RMS of the held-out residuals behind it, N.
    pub heldout_rms_n: f64,
    /// Rows behind it.
    pub rows: usize,
    /// Cords behind it.
    pub cords: usize,
}

impl NewCordError {
    /// The variance at `t2_n`, N².
    pub fn variance(&self, t2_n: f64) -> f64 {
        self.abs_n.powi(2) + (self.rel * t2_n).powi(2)
    }
}

/// An error in T2 beyond what the model accounts for, from held-out residuals: sd² =
/// max(0, mean e² − mean v), v what the model's own components give at those rows (a
/// method-of-moments estimate, one constant in N², clamped at 0). Used for what extrapolating
/// in wrap costs.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModelError {
    /// SD of the model error, N (enters the prediction interval as sd²).
    pub sd_n: f64,
    /// RMS of the held-out residuals, N.
    pub heldout_rms_n: f64,
    /// RMS the other components account for at those rows (√mean v), N.
    pub accounted_rms_n: f64,
    /// Rows with a held-out prediction behind the estimate.
    pub rows: usize,
}

impl ModelError {
    /// No error, from no rows.
    pub const NONE: ModelError = ModelError {
        sd_n: 0.0,
        heldout_rms_n: 0.0,
        accounted_rms_n: 0.0,
        rows: 0,
    };
}

/// The note every prediction model carries.
pub const NOTE: &str = "Predictions are for the first run of a fresh cord at the trigger (time 0), with the contact's load memory settled under the held T1, by the population-averaged model (the named causes and one mu for all cords, least squares in T2). Confidence interval: the curve's uncertainty (cord jackknife covariance of the fitted values, Student t with folds − 1 degrees of freedom). Prediction interval: that plus a new cord's error around the curve, a² + (b·T2)² fitted to the held-out residuals of the whole procedure (every cord predicted by the causes chosen and fitted without it), and at a wrap outside the fitted wraps' span what extrapolating in wrap cost on the fitted data (fits without the smallest or the largest wrap, their residuals there beyond all that), scaled by the distance beyond the span over the distance it was measured at; Student t with cords − 2 degrees of freedom. Physical predictions use the friction law alone (sensor terms off), so T2 ≥ T1 and the interval's lower end is held at T1; as-measured ones add the fitted sensor terms.";

/// One operating point to predict at.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Query {
    /// Wrap, deg.
    pub wrap_deg: f64,
    /// Capstan diameter, mm.
    pub diameter_mm: f64,
    /// Drive voltage, V.
    pub drive_v: f64,
    /// T1, N (true tension when physical, the reading when as measured).
    pub t1_n: f64,
    /// Include the fitted sensor terms.
    pub as_measured: bool,
}

/// A 95 % interval.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Interval {
    /// Lower end.
    pub lo: f64,
    /// Upper end.
    pub hi: f64,
}

/// One prediction (the JSON contract of `capstan predict --json`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Prediction {
    /// T1, N.
    pub t1_n: f64,
    /// Predicted T2, N.
    pub t2_n: f64,
    /// T2/T1.
    pub amplification: f64,
    /// 95 % confidence interval of the mean T2, N.
    pub t2_ci95: Interval,
    /// 95 % prediction interval of a new measurement on a new cord, N.
    pub t2_pi95: Interval,
}

impl PredictionModel {
    /// The model at the population values, with the free values replaced by `free` (when given).
    pub(super) fn model(&self, free: Option<&[f64]>) -> Model {
        let mut m = Model::euler_eytelwein(0.0);
        for p in Param::ALL {
            if let Some(v) = self.values.get(p.name()) {
                p.set(&mut m, *v);
            }
        }
        if let Some(f) = free {
            for (name, v) in self.free.iter().zip(f) {
                if let Some(p) = Param::ALL.iter().find(|p| p.name() == name) {
                    p.set(&mut m, *v);
                }
            }
        }
        m
    }

    fn free_values(&self) -> Vec<f64> {
        self.free
            .iter()
            .map(|n| self.values.get(n).copied().unwrap_or(f64::NAN))
            .collect()
    }

    /// Each quantity of a query with its value, the fitted span and its unit.
    fn quantities(&self, q: &Query) -> [(&'static str, f64, Span, &'static str); 4] {
        let r = &self.fitted_range;
        [
            ("wrap", q.wrap_deg, r.wrap_deg, "°"),
            ("diameter", q.diameter_mm, r.diameter_mm, " mm"),
            ("T1", q.t1_n, r.t1_n, " N"),
            ("drive voltage", q.drive_v, r.drive_v, " V"),
        ]
    }

    /// `wrap_deg` lies outside the fitted wraps' span: there the prediction interval holds
    /// [`PredictionModel::wrap_extrapolation_error`] too.
    pub fn extrapolates_in_wrap(&self, wrap_deg: f64) -> bool {
        !self.fitted_range.wrap_deg.contains(wrap_deg)
    }

    /// The error of extrapolating to `wrap_deg`, N: 0 inside the fitted span; beyond it the
    /// measured SD scaled by the distance from the span over the distance it was measured at
    /// (an extrapolation's error grows with how far it reaches; the interval is continuous at
    /// the span's edge). `None` beyond the span when it was not measured (fewer than three
    /// fitted wraps): the interval then holds no extrapolation error, and the output says so.
    pub fn wrap_extrapolation_sd(&self, wrap_deg: f64) -> Option<f64> {
        let s = self.fitted_range.wrap_deg;
        let beyond = (s.min - wrap_deg).max(wrap_deg - s.max).max(0.0);
        if beyond == 0.0 {
            return Some(0.0);
        }
        let e = &self.wrap_extrapolation_error;
        (e.rows > 0 && self.wrap_extrapolation_step_deg > 0.0)
            .then(|| e.sd_n * beyond / self.wrap_extrapolation_step_deg)
    }

    /// Why the data cannot give the intervals at `q`, in the interval's words (`None`: they
    /// can). An interval is only as good as the error measured behind it: the new cord's error
    /// was measured on the fitted diameters and drive voltages, and beyond the fitted wraps
    /// only when three wraps or more let it be. Beyond those, and wherever the fitted law's
    /// linear change of mu with diameter or voltage takes mu to 0 or below (the law then holds
    /// T2 at T1, and every refit agrees on that, so the interval would have no width exactly
    /// where the model knows least), the interval is not identified.
    pub fn unidentified(&self, q: &Query) -> Option<String> {
        let m = self.model(None);
        let law = &m.law;
        let r = &self.fitted_range;
        let mut why = Vec::new();
        for (name, per, x, x0, unit) in [
            (
                "diameter",
                law.mu_change_per_mm,
                q.diameter_mm,
                capstan_physics::REF_DIAMETER_MM,
                " mm",
            ),
            (
                "drive voltage",
                law.mu_change_per_v,
                q.drive_v,
                REF_DRIVE_V,
                " V",
            ),
        ] {
            if 1.0 + per * (x - x0) <= 0.0 {
                why.push(format!(
                    "the fitted change of mu with {name} takes mu to 0 or below at {}{unit} (T2 is held at T1 there)",
                    short(x)
                ));
            }
        }
        let mut op = Operating::from_wrap_deg(q.wrap_deg);
        op.diameter_mm = q.diameter_mm;
        op.drive_v = q.drive_v;
        if why.is_empty() && law.mu > 0.0 && law.effective_mu(&op) <= 0.0 {
            why.push("the fitted law takes mu to 0 or below there (T2 is held at T1)".into());
        }
        for (name, x, s, unit) in [
            ("diameter", q.diameter_mm, r.diameter_mm, " mm"),
            ("drive voltage", q.drive_v, r.drive_v, " V"),
        ] {
            if !s.contains(x) {
                why.push(format!(
                    "{name} {}{unit} is outside the fitted {}{unit} to {}{unit}, where no held-out cord measured the model's error",
                    short(x),
                    short(s.min),
                    short(s.max)
                ));
            }
        }
        if self.wrap_extrapolation_sd(q.wrap_deg).is_none() {
            why.push(format!(
                "wrap {}° is outside the fitted {}° to {}°, and with fewer than three fitted wraps what extrapolating in wrap costs could not be measured",
                short(q.wrap_deg),
                short(r.wrap_deg.min),
                short(r.wrap_deg.max)
            ));
        }
        (!why.is_empty()).then(|| format!("not identified: {}", why.join("; ")))
    }

    /// The query's quantities outside the fitted data's ranges, one sentence each (empty when
    /// it lies inside them).
    pub fn extrapolates(&self, q: &Query) -> Vec<String> {
        self.extrapolation(std::slice::from_ref(q))
    }

    /// The quantities of `queries` outside the fitted data's ranges: one sentence per quantity,
    /// however many values lie outside ("wrap 900° is outside the fitted 270° to 720°"; for a
    /// list, how many lie below and above and their range).
    pub fn extrapolation(&self, queries: &[Query]) -> Vec<String> {
        let Some(first) = queries.first() else {
            return Vec::new();
        };
        let mut out = Vec::new();
        for (k, (name, v0, s, unit)) in self.quantities(first).into_iter().enumerate() {
            let values = || queries.iter().map(|q| self.quantities(q)[k].1);
            if !values().any(|v| !s.contains(v)) {
                continue;
            }
            let fitted = format!(
                "the fitted {}{unit} to {}{unit}",
                short(s.min),
                short(s.max)
            );
            if values().all(|v| v == v0) {
                out.push(format!("{name} {}{unit} is outside {fitted}", short(v0)));
                continue;
            }
            let side = |below: bool, word: &str| -> Option<String> {
                let o: Vec<f64> = values()
                    .filter(|v| !s.contains(*v) && (*v < s.min) == below)
                    .collect();
                let r = Span::of(o.iter().copied());
                let range = if r.min == r.max {
                    format!("{}{unit}", short(r.min))
                } else {
                    format!("{}{unit} to {}{unit}", short(r.min), short(r.max))
                };
                (!o.is_empty()).then(|| format!("{} {word} ({range})", o.len()))
            };
            let parts: Vec<String> = [side(true, "below"), side(false, "above")]
                .into_iter()
                .flatten()
                .collect();
            out.push(format!(
                "{name} outside {fitted}: {} of {} values",
                parts.join(", "),
                queries.len()
            ));
        }
        out
    }
}

/// A value in a sentence: six decimals at most, trailing zeros dropped (a range's 1:30:0.1
/// steps give 22.500000000000004, which reads 22.5); below 1e-3 in scientific notation.
fn short(v: f64) -> String {
    if v != 0.0 && v.abs() < 1e-3 {
        return format!("{v:.3e}");
    }
    let s = format!("{v:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.into()
    }
}

/// T2 at a query for a model, the load memory settled under the held T1.
pub(super) fn t2_of(m: &Model, q: &Query) -> f64 {
    let mut op = Operating::from_wrap_deg(q.wrap_deg);
    op.diameter_mm = q.diameter_mm;
    op.drive_v = q.drive_v;
    let (t1_true, sensors) = if q.as_measured {
        (m.sensors.true_t1_n(q.t1_n), m.sensors)
    } else {
        (q.t1_n, capstan_physics::SensorArtefacts::IDEAL)
    };
    let law = m.law;
    let t2_at = |h: f64| {
        let mut o = op;
        o.load_memory_ns = h;
        law.t2_n(t1_true, &o)
    };
    let mut t2 = t2_at(0.0);
    if law.heat_per_ns != 0.0 && law.heat_tau_s > 0.0 && t2.is_finite() {
        // H = τ·(T2(H) − T1): the left side grows and the right falls with H, so the root in
        // [0, τ·(T2(0) − T1)] is unique; bisection finds it.
        let (mut lo, mut hi) = (0.0, law.heat_tau_s * (t2 - t1_true).max(0.0));
        for _ in 0..80 {
            let mid = 0.5 * (lo + hi);
            if mid - law.heat_tau_s * (t2_at(mid) - t1_true).max(0.0) > 0.0 {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        t2 = t2_at(0.5 * (lo + hi));
    }
    sensors.measured_t2_n(t2)
}

/// Two-sided 95 % quantile of Student's t with `dof` degrees of freedom (normal beyond 200).
pub(super) fn t95(dof: usize) -> f64 {
    t_quantile(0.975, dof)
}

/// The `p` quantile of Student's t with `dof` degrees of freedom (the normal's beyond 200).
pub(super) fn t_quantile(p: f64, dof: usize) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal, StudentsT};
    let normal = Normal::new(0.0, 1.0).map_or(f64::NAN, |n| n.inverse_cdf(p));
    if dof == 0 || dof > 200 {
        return normal;
    }
    StudentsT::new(0.0, 1.0, dof as f64).map_or(normal, |t| t.inverse_cdf(p))
}

/// The predicted T2 at a query and the variance of the curve there.
pub(super) struct Spread {
    /// T2, N.
    pub(super) t2: f64,
    /// Variance of the population curve (delta method through the covariance), N².
    pub(super) var_mean: f64,
}

/// Gradient of T2 in the free values, central differences.
fn gradient(pm: &PredictionModel, q: &Query) -> Vec<f64> {
    let v0 = pm.free_values();
    (0..v0.len())
        .map(|k| {
            let h = 1e-5 * v0[k].abs().max(1e-3);
            let at = |d: f64| {
                let mut v = v0.clone();
                v[k] += d;
                t2_of(&pm.model(Some(&v)), q)
            };
            (at(h) - at(-h)) / (2.0 * h)
        })
        .collect()
}

pub(super) fn spread(pm: &PredictionModel, q: &Query) -> Spread {
    let t2 = t2_of(&pm.model(None), q);
    let grad = gradient(pm, q);
    let mut var_mean = 0.0;
    for (a, ga) in grad.iter().enumerate() {
        for (b, gb) in grad.iter().enumerate() {
            let c = pm
                .covariance
                .get(a)
                .and_then(|r| r.get(b))
                .copied()
                .unwrap_or(0.0);
            var_mean += ga * c * gb;
        }
    }
    // A variance that overflows stays infinite (an interval without bounds, which `predict`
    // refuses to print), never 0 (an interval of no width that looks certain).
    Spread {
        t2,
        var_mean: if var_mean.is_nan() {
            f64::INFINITY
        } else {
            var_mean.max(0.0)
        },
    }
}

/// T2 at `q` with its intervals.
pub fn predict(pm: &PredictionModel, q: &Query) -> Prediction {
    let Spread { t2, var_mean } = spread(pm, q);
    let var_new = pm.new_cord_error.variance(t2)
        + pm.wrap_extrapolation_sd(q.wrap_deg).unwrap_or(0.0).powi(2);
    let ci = t95(pm.folds.saturating_sub(1)) * var_mean.sqrt();
    let pi = t95(pm.new_cord_error.dof.max(1)) * (var_mean + var_new).sqrt();
    // Physics: a capstan that is not driven backwards does not lose tension.
    let floor = if q.as_measured {
        f64::NEG_INFINITY
    } else {
        q.t1_n
    };
    Prediction {
        t1_n: q.t1_n,
        t2_n: t2,
        amplification: t2 / q.t1_n,
        t2_ci95: Interval {
            lo: (t2 - ci).max(floor),
            hi: t2 + ci,
        },
        t2_pi95: Interval {
            lo: (t2 - pi).max(floor),
            hi: t2 + pi,
        },
    }
}

/// Each row's query as measured (its wrap, diameter, drive voltage and T1 reading).
fn query_of(r: &crate::fit::obs::Row) -> Query {
    Query {
        wrap_deg: r.op.wrap_rad.to_degrees(),
        diameter_mm: r.op.diameter_mm,
        drive_v: r.op.drive_v,
        t1_n: r.t1_n,
        as_measured: true,
    }
}

/// A new cord's error from the held-out predictions `heldout` of the rows of `obs` (NaN where a
/// row has none), beyond the curve's variance of `pm` at each row: see [`NewCordError`].
pub fn new_cord_error(
    pm: &PredictionModel,
    obs: &crate::fit::Observations,
    heldout: &[f64],
) -> NewCordError {
    let mut pts: Vec<(f64, f64)> = Vec::new();
    let mut cords = std::collections::BTreeSet::new();
    let mut e2sum = 0.0;
    for (r, p) in obs.rows.iter().zip(heldout) {
        let e = r.t2_n - p;
        if !e.is_finite() {
            continue;
        }
        let var_mean = spread(pm, &query_of(r)).var_mean;
        if !var_mean.is_finite() {
            continue;
        }
        pts.push((p * p, e * e - var_mean));
        cords.insert(r.group);
        e2sum += e * e;
    }
    let (a2, b2) = nonnegative_line(&pts);
    NewCordError {
        abs_n: a2.sqrt(),
        rel: b2.sqrt(),
        dof: cords.len().saturating_sub(2).max(1),
        heldout_rms_n: if pts.is_empty() {
            0.0
        } else {
            (e2sum / pts.len() as f64).sqrt()
        },
        rows: pts.len(),
        cords: cords.len(),
    }
}

/// Least squares y ≈ A + B·x with A, B ≥ 0 (the better of the free fit if it is non-negative
/// and the two one-term fits).
fn nonnegative_line(pts: &[(f64, f64)]) -> (f64, f64) {
    let n = pts.len() as f64;
    if pts.is_empty() {
        return (0.0, 0.0);
    }
    let (sx, sy) = pts.iter().fold((0.0, 0.0), |(a, b), (x, y)| (a + x, b + y));
    let (sxx, sxy) = pts
        .iter()
        .fold((0.0, 0.0), |(a, b), (x, y)| (a + x * x, b + x * y));
    let sse = |a: f64, b: f64| {
        pts.iter()
            .map(|(x, y)| (y - a - b * x).powi(2))
            .sum::<f64>()
    };
    let mut best = ((sy / n).max(0.0), 0.0);
    if sxx > 0.0 {
        let b = (sxy / sxx).max(0.0);
        if sse(0.0, b) < sse(best.0, best.1) {
            best = (0.0, b);
        }
    }
    let det = n * sxx - sx * sx;
    if det > 1e-12 * n * sxx {
        let b = (n * sxy - sx * sy) / det;
        let a = (sy - b * sx) / n;
        if a >= 0.0 && b >= 0.0 && sse(a, b) < sse(best.0, best.1) {
            best = (a, b);
        }
    }
    best
}

/// The error of extrapolating in wrap, from the held-out predictions `edge` of the smallest
/// and the largest wrap by fits on the other wraps: their mean square beyond the curve's
/// variance and a new cord's error, sd² = max(0, mean e² − mean v). Zero, from no rows, with
/// fewer than three wraps.
pub fn wrap_extrapolation(
    pm: &PredictionModel,
    obs: &crate::fit::Observations,
    edge: &[f64],
) -> ModelError {
    let (mut n, mut sum_e2, mut sum_v) = (0usize, 0.0, 0.0);
    for (r, p) in obs.rows.iter().zip(edge) {
        let e = r.t2_n - p;
        if !e.is_finite() {
            continue;
        }
        let s = spread(pm, &query_of(r));
        n += 1;
        sum_e2 += e * e;
        sum_v += s.var_mean + pm.new_cord_error.variance(s.t2);
    }
    if n == 0 {
        return ModelError::NONE;
    }
    let (e2, v) = (sum_e2 / n as f64, sum_v / n as f64);
    ModelError {
        sd_n: (e2 - v).max(0.0).sqrt(),
        heldout_rms_n: e2.sqrt(),
        accounted_rms_n: v.sqrt(),
        rows: n,
    }
}

/// The mean of the gaps between the two smallest and the two largest wraps, deg (0 with fewer
/// than three wraps).
fn edge_step_deg(obs: &crate::fit::Observations) -> f64 {
    let w = crate::fit::stats::distinct(obs.groups.iter().map(|g| g.wrap_deg));
    if w.len() < 3 {
        return 0.0;
    }
    let n = w.len();
    0.5 * ((w[1] - w[0]) + (w[n - 1] - w[n - 2]))
}

/// The cord-jackknife covariance of the values in `folds` ((k − 1)/k Σ (v − v̄)(v − v̄)ᵀ;
/// NaN with fewer than two folds).
fn jackknife_covariance(folds: &[Vec<(&'static str, f64)>], k_free: usize) -> Vec<Vec<f64>> {
    let k = folds.len();
    if k < 2 {
        return vec![vec![f64::NAN; k_free]; k_free];
    }
    let mut cov = vec![vec![0.0; k_free]; k_free];
    let mean: Vec<f64> = (0..k_free)
        .map(|j| folds.iter().map(|f| f[j].1).sum::<f64>() / k as f64)
        .collect();
    for f in folds {
        for a in 0..k_free {
            for b in 0..k_free {
                cov[a][b] += (f[a].1 - mean[a]) * (f[b].1 - mean[b]) * (k as f64 - 1.0) / k as f64;
            }
        }
    }
    cov
}

/// The prediction model of a fitted analysis: the population-averaged fit's values, their
/// cord-jackknife covariance, and a new cord's error from the whole procedure's held-out
/// predictions (`fits.pred.extended_loco`).
pub fn build(obs: &crate::fit::Observations, fits: &super::fits::Fits) -> PredictionModel {
    let pop = &fits.population;
    let m = pop.model(None);
    let values: BTreeMap<String, f64> = Param::ALL
        .iter()
        .map(|p| (p.name().to_string(), p.get(&m)))
        .collect();
    let free: Vec<String> = pop
        .spec
        .free
        .iter()
        .map(|f| f.param.name().to_string())
        .collect();
    let folds = &fits.population_loco.fold_values;
    let rows = &obs.rows;
    let mut pm = PredictionModel {
        schema: SCHEMA,
        values,
        covariance: jackknife_covariance(folds, free.len()),
        free,
        folds: folds.len(),
        new_cord_error: NewCordError {
            abs_n: 0.0,
            rel: 0.0,
            dof: 1,
            heldout_rms_n: 0.0,
            rows: 0,
            cords: 0,
        },
        wrap_extrapolation_error: ModelError::NONE,
        wrap_extrapolation_step_deg: 0.0,
        fitted_range: FittedRange {
            wrap_deg: Span::of(obs.groups.iter().map(|g| g.wrap_deg)),
            diameter_mm: Span::of(obs.groups.iter().map(|g| g.diameter_mm)),
            t1_n: Span::of(rows.iter().map(|r| r.t1_n)),
            drive_v: Span::of(rows.iter().map(|r| r.op.drive_v)),
        },
        note: NOTE.into(),
    };
    pm.new_cord_error = new_cord_error(&pm, obs, &fits.pred.extended_loco);
    pm.wrap_extrapolation_error = wrap_extrapolation(&pm, obs, &fits.pred.extended_edge_wrap);
    if pm.wrap_extrapolation_error.rows > 0 {
        pm.wrap_extrapolation_step_deg = edge_step_deg(obs);
    }
    pm
}

/// The reference drive voltage (the thesis's runs) for a query that gives none.
pub const DEFAULT_DRIVE_V: f64 = REF_DRIVE_V;

#[cfg(test)]
mod tests {
    use super::short;

    #[test]
    fn values_in_warnings_read_short() {
        assert_eq!(short(22.500000000000004), "22.5");
        assert_eq!(short(0.072014), "0.072014");
        assert_eq!(short(720.0), "720");
        assert_eq!(short(-0.0), "0");
        assert_eq!(short(1e-7), "1.000e-7");
    }
}
