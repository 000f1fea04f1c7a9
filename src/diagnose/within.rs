//! Within-run fits: every run (unit) has its own mu, and one effect parameter θ is shared.
//!
//! T2ᵢ = Model(mu_r(i), θ).predict_t2_n(T1ᵢ, opᵢ), least squares in T2 (N). Giving every run its
//! own mu conditions out everything that varies between runs and cords (scatter of mu, wear,
//! diameter and speed dependence, a gain error): what is left to θ is the *shape* of T2 against
//! T1, time and wrap inside runs. This is the within (fixed-run-effects) estimator of a mixed
//! model whose run effects are far larger than the measurement noise.
//!
//! The problem is solved by Levenberg-Marquardt on (θ, mu_1..mu_R) exploiting its arrow-head
//! structure: each residual depends on θ and on its own run's mu only, so the normal equations
//! reduce (Schur complement) to one scalar equation for δθ plus R independent ones. Jacobians
//! are forward differences of `capstan_friction::Model::predict_t2_n`, the shared model.

use super::prep::Prepared;
use capstan_friction::{Effect, EffectKind, Model};

/// How θ maps to the catalogue parameter, and its bounds (in θ).
#[derive(Clone, Copy, Debug)]
pub(crate) struct ThetaMap {
    pub kind: EffectKind,
    pub lo: f64,
    pub hi: f64,
}

impl ThetaMap {
    /// The θ range and map for a within-run candidate on this data set.
    pub fn for_kind(kind: EffectKind, p: &Prepared) -> ThetaMap {
        let (lo, hi) = match kind {
            EffectKind::PressureFriction => (0.4, 1.6),
            // θ = √B (√(N m²)): the lift-off loss grows as √B, so θ is smooth at B = 0.
            EffectKind::BendingStiffness => (0.0, 1e-3f64.sqrt()),
            EffectKind::T1Offset => {
                let min_t1 = p.t1.iter().copied().fold(f64::INFINITY, f64::min);
                (-3.0, 0.98 * min_t1)
            }
            EffectKind::T2Offset => (-5.0, 5.0),
            EffectKind::ThermalDrift => {
                let t_max = p.op.iter().map(|o| o.time_s).fold(1.0, f64::max);
                (-0.8 * 100.0 / t_max, 5.0)
            }
            _ => (0.0, 0.0),
        };
        ThetaMap { kind, lo, hi }
    }

    /// Catalogue value of θ.
    pub fn value(&self, theta: f64) -> f64 {
        match self.kind {
            EffectKind::BendingStiffness => theta * theta,
            _ => theta,
        }
    }

    /// θ of a catalogue value.
    pub fn theta(&self, value: f64) -> f64 {
        match self.kind {
            EffectKind::BendingStiffness => value.max(0.0).sqrt(),
            _ => value,
        }
    }

    fn step(&self) -> f64 {
        match self.kind {
            EffectKind::PressureFriction => 1e-6,
            EffectKind::BendingStiffness => 1e-7,
            EffectKind::T1Offset | EffectKind::T2Offset => 1e-6,
            EffectKind::ThermalDrift => 1e-6,
            _ => 1e-6,
        }
    }

    fn model(&self, mu: f64, theta: f64) -> Model {
        let m = Model::euler_eytelwein(mu);
        if self.kind == EffectKind::None {
            return m;
        }
        m.with_effect(Effect {
            kind: self.kind,
            value: self.value(theta),
        })
    }
}

/// A within-run fit.
#[derive(Clone, Debug)]
pub(crate) struct WithinFit {
    /// θ (internal) and its standard error.
    pub theta: f64,
    pub theta_se: f64,
    /// Cluster-robust (units as clusters) standard error of θ.
    pub theta_se_robust: f64,
    /// mu of every unit.
    pub mu: Vec<f64>,
    /// Residual sum of squares, N².
    pub rss: f64,
    /// Rows.
    pub n: usize,
}

struct Work {
    f: Vec<f64>,
    a: Vec<f64>,
    b: Vec<f64>,
}

fn predict(p: &Prepared, map: &ThetaMap, mu: &[f64], theta: f64, out: &mut [f64]) -> f64 {
    let mut rss = 0.0;
    for (u, rows) in p.units.iter().enumerate() {
        let m = map.model(mu[u], theta);
        for &i in rows {
            let f = m.predict_t2_n(p.t1[i], &p.op[i]);
            out[i] = f;
            let r = f - p.t2[i];
            rss += r * r;
        }
    }
    if rss.is_finite() {
        rss
    } else {
        f64::INFINITY
    }
}

/// Sensitivities: a = ∂f/∂mu (own unit), b = ∂f/∂θ.
fn jacobian(p: &Prepared, map: &ThetaMap, mu: &[f64], theta: f64, with_theta: bool, w: &mut Work) {
    let hb = map.step();
    // Keep the θ difference inside the bounds.
    let hb = if theta + hb > map.hi { -hb } else { hb };
    for (u, rows) in p.units.iter().enumerate() {
        let ha = 1e-6 * mu[u].abs().max(1e-3);
        let ma = map.model(mu[u] + ha, theta);
        let mb = map.model(mu[u], theta + hb);
        for &i in rows {
            let f0 = w.f[i];
            w.a[i] = (ma.predict_t2_n(p.t1[i], &p.op[i]) - f0) / ha;
            if with_theta {
                w.b[i] = (mb.predict_t2_n(p.t1[i], &p.op[i]) - f0) / hb;
            }
        }
    }
}

/// Start values of every unit's mu: the median of ln(T2/T1)/β over its rows.
pub(crate) fn start_mu(p: &Prepared) -> Vec<f64> {
    p.units
        .iter()
        .map(|rows| {
            let mut v: Vec<f64> = rows
                .iter()
                .filter(|&&i| p.t2[i] > 0.0)
                .map(|&i| (p.t2[i] / p.t1[i]).ln() / p.op[i].wrap_rad)
                .filter(|x| x.is_finite())
                .collect();
            v.sort_by(f64::total_cmp);
            let m = if v.is_empty() { 0.1 } else { v[v.len() / 2] };
            m.clamp(0.005, 2.0)
        })
        .collect()
}

/// Fit θ (if the candidate has one) and every unit's mu, starting from `theta0`, `mu0`.
pub(crate) fn fit(p: &Prepared, map: &ThetaMap, theta0: f64, mu0: &[f64]) -> WithinFit {
    let n = p.n();
    let nu = p.units.len();
    let with_theta = map.kind != EffectKind::None;
    let mut w = Work {
        f: vec![0.0; n],
        a: vec![0.0; n],
        b: vec![0.0; n],
    };
    let mut theta = theta0.clamp(map.lo, map.hi);
    let mut mu = mu0.to_vec();
    let mut rss = predict(p, map, &mu, theta, &mut w.f);
    let mut lambda = 1e-3;
    let mut trial = vec![0.0; n];
    let mut info_theta = f64::NAN;
    // Per-unit sums.
    let mut d = vec![0.0; nu];
    let mut c = vec![0.0; nu];
    let mut g = vec![0.0; nu];
    for _iter in 0..60 {
        jacobian(p, map, &mu, theta, with_theta, &mut w);
        let (mut sbb, mut gb) = (0.0, 0.0);
        for (u, rows) in p.units.iter().enumerate() {
            let (mut du, mut cu, mut gu) = (0.0, 0.0, 0.0);
            for &i in rows {
                let r = w.f[i] - p.t2[i];
                du += w.a[i] * w.a[i];
                gu += w.a[i] * r;
                if with_theta {
                    cu += w.a[i] * w.b[i];
                    sbb += w.b[i] * w.b[i];
                    gb += w.b[i] * r;
                }
            }
            d[u] = du.max(1e-300);
            c[u] = cu;
            g[u] = gu;
        }
        if with_theta {
            info_theta = sbb - (0..nu).map(|u| c[u] * c[u] / d[u]).sum::<f64>();
        }
        // Try steps with growing damping until the RSS falls.
        let mut improved = false;
        for _ in 0..30 {
            let dd: Vec<f64> = d.iter().map(|x| x * (1.0 + lambda)).collect();
            let mut dtheta = 0.0;
            if with_theta {
                let s = sbb * (1.0 + lambda) - (0..nu).map(|u| c[u] * c[u] / dd[u]).sum::<f64>();
                let rhs = -gb + (0..nu).map(|u| c[u] * g[u] / dd[u]).sum::<f64>();
                dtheta = if s > 0.0 { rhs / s } else { 0.0 };
            }
            let new_theta = (theta + dtheta).clamp(map.lo, map.hi);
            let dtheta = new_theta - theta;
            let new_mu: Vec<f64> = (0..nu)
                .map(|u| (mu[u] + (-g[u] - c[u] * dtheta) / dd[u]).max(1e-4))
                .collect();
            let new_rss = predict(p, map, &new_mu, new_theta, &mut trial);
            if new_rss < rss {
                let rel = (rss - new_rss) / rss.max(1e-300);
                theta = new_theta;
                mu = new_mu;
                rss = new_rss;
                std::mem::swap(&mut w.f, &mut trial);
                lambda = (lambda / 4.0).max(1e-9);
                improved = rel > 1e-12;
                break;
            }
            lambda *= 5.0;
            if lambda > 1e12 {
                break;
            }
        }
        if !improved {
            break;
        }
    }
    let dof = (n as f64 - nu as f64 - f64::from(u8::from(with_theta))).max(1.0);
    let sigma2 = rss / dof;
    let theta_se = if with_theta && info_theta > 0.0 {
        (sigma2 / info_theta).sqrt()
    } else {
        f64::NAN
    };
    // Cluster-robust variance of θ with the units (runs) as clusters: the profile score of
    // θ (mu of the unit projected out) summed per unit, sandwiched by the information.
    let mut theta_se_robust = f64::NAN;
    if with_theta && info_theta > 0.0 {
        jacobian(p, map, &mu, theta, true, &mut w);
        let mut meat = 0.0;
        for rows in &p.units {
            let (mut du, mut cu) = (0.0, 0.0);
            for &i in rows {
                du += w.a[i] * w.a[i];
                cu += w.a[i] * w.b[i];
            }
            let k = if du > 0.0 { cu / du } else { 0.0 };
            let s: f64 = rows
                .iter()
                .map(|&i| (w.b[i] - k * w.a[i]) * (w.f[i] - p.t2[i]))
                .sum();
            meat += s * s;
        }
        let g = nu as f64;
        let v = g / (g - 1.0).max(1.0) * meat / (info_theta * info_theta);
        theta_se_robust = v.sqrt();
    }
    WithinFit {
        theta,
        theta_se,
        theta_se_robust,
        mu,
        rss,
        n,
    }
}

/// The best of fits from several starts of θ.
pub(crate) fn fit_multistart(
    p: &Prepared,
    map: &ThetaMap,
    starts: &[f64],
    mu0: &[f64],
) -> WithinFit {
    let mut best: Option<WithinFit> = None;
    for &s in starts {
        let f = fit(p, map, s, mu0);
        if best.as_ref().is_none_or(|b| f.rss < b.rss) {
            best = Some(f);
        }
    }
    best.expect("at least one start")
}

/// Starting points of θ for each candidate (catalogue values, mapped to θ).
pub(crate) fn starts(map: &ThetaMap) -> Vec<f64> {
    let v: Vec<f64> = match map.kind {
        EffectKind::PressureFriction => vec![0.97, 0.8],
        EffectKind::BendingStiffness => vec![5e-6, 8e-5],
        EffectKind::T1Offset => vec![0.0, 0.5],
        EffectKind::T2Offset => vec![0.0],
        EffectKind::ThermalDrift => vec![0.0],
        _ => vec![map.kind.neutral_value()],
    };
    v.into_iter()
        .map(|x| map.theta(x).clamp(map.lo, map.hi))
        .collect()
}
