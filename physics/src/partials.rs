//! First derivatives of the friction law at a solution, for fits that need a Jacobian.
//!
//! The analysis fits the law row by row thousands of times; differencing it costs one law
//! evaluation per parameter (and with bending stiffness each evaluation solves the lift-off's
//! implicit wrap). At a known solution T2 the derivatives follow in closed form, the implicit
//! wrap by the implicit-function theorem: one pass gives them all. The fits check them against
//! central differences in their tests.

use crate::math::{exp, log, pow, sqrt};
use crate::{FrictionLaw, Operating, REF_TENSION_N};

// The n → 1 limit and its series below leave out ln(T_ref) terms: they hold for T_ref = 1 N.
const _: () = assert!(REF_TENSION_N == 1.0);

/// T2's first derivatives at fixed operating conditions (load memory included).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LawPartials {
    /// ∂T2/∂T1 (true tensions).
    pub d_t1: f64,
    /// ∂T2/∂k, k the effective friction coefficient ([`FrictionLaw::effective_mu`]).
    pub d_k: f64,
    /// ∂T2/∂n, n the tension exponent.
    pub d_n: f64,
    /// ∂T2/∂√B, B the bending stiffness in N m² (finite at B = 0: the lift-off grows as √B).
    pub d_sqrt_b: f64,
}

/// The effective friction coefficient k and its first derivatives.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MuPartials {
    /// k itself (as [`FrictionLaw::effective_mu`]).
    pub k: f64,
    /// ∂k/∂mu.
    pub d_mu: f64,
    /// ∂k/∂(mu_change_per_100s).
    pub d_drift: f64,
    /// ∂k/∂(heat_per_ns), per 1/(N s).
    pub d_heat: f64,
    /// ∂k/∂H, per N s of load memory.
    pub d_memory: f64,
}

/// The partials of I(T1, k, w), T1 transmitted over the wrap w (zero where I is infinite).
struct Integral {
    d_t1: f64,
    d_k: f64,
    d_w: f64,
    d_n: f64,
}

impl FrictionLaw {
    /// The derivatives of k (its value at `op`; zero where k is clamped at zero).
    fn mu_partials(&self, k: f64, op: &Operating) -> MuPartials {
        if k <= 0.0 || self.mu <= 0.0 {
            return MuPartials::default();
        }
        let drift = 1.0 + self.mu_change_per_100s * op.time_s / 100.0;
        // k's other factors (the drift's is not zero: k > 0).
        let rest = k / (self.mu * drift);
        MuPartials {
            k,
            d_mu: k / self.mu,
            d_drift: self.mu * rest * op.time_s / 100.0,
            d_heat: -op.load_memory_ns * k,
            d_memory: -self.heat_per_ns * k,
        }
    }

    /// T2's derivatives at the solution `t2_n` of [`FrictionLaw::t2_n`] for `t1_n` (true
    /// tensions), and k's: no solve, the lift-off's implicit wrap differentiated in place.
    pub fn partials_at(&self, t1_n: f64, t2_n: f64, op: &Operating) -> (LawPartials, MuPartials) {
        let k = self.effective_mu(op);
        let mu = self.mu_partials(k, op);
        if t1_n.is_nan() || t1_n <= 0.0 || !t2_n.is_finite() || t2_n <= 0.0 {
            let slack = LawPartials {
                d_t1: 1.0,
                ..LawPartials::default()
            };
            return (slack, mu);
        }
        let radius_m = op.diameter_mm * 0.5e-3;
        let sqrt_b = sqrt(self.bending_b_nm2.max(0.0));
        // Lift-off per √B at each end, rad/√(N m²).
        let (u1, u2) = (1.0 / (radius_m * sqrt(t1_n)), 1.0 / (radius_m * sqrt(t2_n)));
        let wrap = if sqrt_b > 0.0 {
            op.wrap_rad - sqrt_b * (u1 + u2)
        } else {
            op.wrap_rad
        };
        let i = self.integrate_partials(t1_n, t2_n, k, wrap);
        // T2 = I(T1, k, β − √B·(u1 + u2)); u2 falls with T2 (∂(√B·u2)/∂T2 = −√B·u2/(2 T2)).
        let denom = 1.0 - i.d_w * sqrt_b * u2 / (2.0 * t2_n);
        let law = LawPartials {
            d_t1: (i.d_t1 + i.d_w * sqrt_b * u1 / (2.0 * t1_n)) / denom,
            d_k: i.d_k / denom,
            d_n: i.d_n / denom,
            d_sqrt_b: -i.d_w * (u1 + u2) / denom,
        };
        (law, mu)
    }

    /// The partials of [`FrictionLaw::integrate`] over `wrap_rad` (zero in the wrap where it
    /// is clamped), at its value `t2_n` (the solution: T2 = I at the wrap that transmits).
    fn integrate_partials(&self, t1_n: f64, t2_n: f64, k: f64, wrap_rad: f64) -> Integral {
        let on = wrap_rad > 0.0;
        let w = wrap_rad.max(0.0);
        let e = 1.0 - self.tension_exponent;
        let ln_t1 = log(t1_n);
        if e.abs() < 1e-9 {
            return Integral {
                d_t1: t2_n / t1_n,
                d_k: w * t2_n,
                d_w: if on { k * t2_n } else { 0.0 },
                // The limit n → 1 of the power law's ∂T2/∂n.
                d_n: t2_n * k * w * (2.0 * ln_t1 + k * w) / 2.0,
            };
        }
        let ref_e = pow(REF_TENSION_N, e);
        let k_n = k * ref_e;
        let t1_e = exp(e * ln_t1);
        // base = T1^e + e·k_n·w = T2^e.
        let base = t1_e + e * k_n * w;
        if base <= 0.0 {
            return Integral {
                d_t1: 0.0,
                d_k: 0.0,
                d_w: 0.0,
                d_n: 0.0,
            };
        }
        // ∂ ln T2/∂e, e = 1 − n. Its two terms cancel as e → 0: below 1e-5 the series about
        // e = 0 (T_ref = 1 N), to second order, is the more accurate.
        let dln_de = if e.abs() < 1e-5 {
            let (l, s) = (ln_t1, ln_t1 + k * w);
            (l * l - s * s) / 2.0 + 2.0 * e * (l * l * l / 6.0 - s * l * l / 2.0 + s * s * s / 3.0)
        } else {
            let d_base = t1_e * ln_t1 + k_n * w + e * k_n * w * log(REF_TENSION_N);
            -log(base) / (e * e) + d_base / (e * base)
        };
        Integral {
            d_t1: t2_n * t1_e / (t1_n * base),
            d_k: t2_n * w * ref_e / base,
            d_w: if on { t2_n * k_n / base } else { 0.0 },
            d_n: -t2_n * dln_de,
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::format;

    fn central(f: impl Fn(f64) -> f64, x: f64, h: f64) -> f64 {
        (f(x + h) - f(x - h)) / (2.0 * h)
    }

    fn close(a: f64, b: f64, rel: f64, what: &str) {
        let tol = rel * a.abs().max(b.abs()).max(1e-3);
        assert!((a - b).abs() <= tol, "{what}: analytic {a} vs numeric {b}");
    }

    /// Every partial against central differences of `t2_n`, over the law's range.
    #[test]
    fn partials_match_central_differences() {
        for &(n, b) in &[
            (1.0, 0.0),
            (0.85, 0.0),
            (0.999_995, 0.0),
            (1.0, 4e-5),
            (0.8, 1e-4),
        ] {
            for &(t1, deg, heat) in &[(0.4, 270.0, 0.0), (3.0, 450.0, 0.002), (20.0, 720.0, 0.0)] {
                let law = FrictionLaw {
                    tension_exponent: n,
                    bending_b_nm2: b,
                    heat_per_ns: heat,
                    mu_change_per_100s: 0.05,
                    ..FrictionLaw::euler_eytelwein(0.12)
                };
                let op = Operating {
                    time_s: 40.0,
                    load_memory_ns: 3.0,
                    ..Operating::from_wrap_deg(deg)
                };
                let t2 = law.t2_n(t1, &op);
                let (p, m) = law.partials_at(t1, t2, &op);
                let at = |l: FrictionLaw| l.t2_n(t1, &op);
                // Just off n = 1 the law itself is good to ~1e-11 (ln(base)/(1 − n)), which
                // its differences amplify.
                let rel = if n != 1.0 && (1.0 - n).abs() < 1e-4 {
                    1e-4
                } else {
                    1e-6
                };
                let case = format!("n {n} B {b} T1 {t1} at {deg}°");
                let d_t1 = central(|x| law.t2_n(x, &op), t1, 1e-4 * t1);
                close(p.d_t1, d_t1, rel, &case);
                let d_mu = central(|x| at(FrictionLaw { mu: x, ..law }), law.mu, 1e-5);
                close(p.d_k * m.d_mu, d_mu, rel, &format!("mu, {case}"));
                let d_n = central(
                    |x| {
                        at(FrictionLaw {
                            tension_exponent: x,
                            ..law
                        })
                    },
                    n,
                    1e-4,
                );
                let tol = 1e-5 * p.d_n.abs().max(d_n.abs()).max(1e-3);
                assert!((p.d_n - d_n).abs() <= tol, "n, {case}: {} vs {d_n}", p.d_n);
                let s = b.sqrt().max(1e-3);
                let d_sb = central(
                    |x| {
                        at(FrictionLaw {
                            bending_b_nm2: x * x,
                            ..law
                        })
                    },
                    s,
                    1e-3 * s,
                );
                if b > 0.0 {
                    close(p.d_sqrt_b, d_sb, rel, &format!("√B, {case}"));
                }
                let d_drift = central(
                    |x| {
                        at(FrictionLaw {
                            mu_change_per_100s: x,
                            ..law
                        })
                    },
                    0.05,
                    1e-4,
                );
                close(p.d_k * m.d_drift, d_drift, rel, &format!("drift, {case}"));
                let d_heat = central(
                    |x| {
                        at(FrictionLaw {
                            heat_per_ns: x,
                            ..law
                        })
                    },
                    heat,
                    1e-5,
                );
                close(p.d_k * m.d_heat, d_heat, rel, &format!("heat, {case}"));
                let d_h = central(
                    |x| {
                        law.t2_n(
                            t1,
                            &Operating {
                                load_memory_ns: x,
                                ..op
                            },
                        )
                    },
                    3.0,
                    1e-3,
                );
                close(p.d_k * m.d_memory, d_h, rel, &format!("memory, {case}"));
            }
        }
    }

    /// At B = 0 the lift-off's first loss is linear in √B: its slope is finite and matches a
    /// one-sided difference.
    #[test]
    fn bending_slope_at_zero_stiffness_is_the_one_sided_difference() {
        let law = FrictionLaw::euler_eytelwein(0.12);
        let op = Operating::from_wrap_deg(540.0);
        let t2 = law.t2_n(2.0, &op);
        let (p, _) = law.partials_at(2.0, t2, &op);
        let h = 1e-8;
        let stiff = FrictionLaw {
            bending_b_nm2: h * h,
            ..law
        };
        let one_sided = (stiff.t2_n(2.0, &op) - t2) / h;
        assert!(p.d_sqrt_b < 0.0);
        assert!(
            (p.d_sqrt_b / one_sided - 1.0).abs() < 1e-5,
            "{p:?} vs {one_sided}"
        );
    }

    #[test]
    fn a_slack_cord_passes_through() {
        let law = FrictionLaw::euler_eytelwein(0.12);
        let (p, _) = law.partials_at(-0.1, -0.1, &Operating::from_wrap_deg(360.0));
        assert_eq!((p.d_t1, p.d_k, p.d_n, p.d_sqrt_b), (1.0, 0.0, 0.0, 0.0));
    }
}
