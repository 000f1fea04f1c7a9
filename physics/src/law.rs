//! The friction law of a cord on a rotating capstan.

use crate::math::{exp, log, pow, sqrt};
use crate::{Operating, REF_DIAMETER_MM, REF_DRIVE_V, REF_TENSION_N, REF_WRAP_RAD};

/// How tension grows around the capstan, with every effect of the catalogue as a parameter.
///
/// Along the contact, dT/dθ = k·Tⁿ (Euler-Eytelwein when n = 1; Howell's power law for
/// polymer cords when n < 1) with k = mu_eff · T_ref^(1-n), T_ref = 1 N, so `mu` is the
/// friction coefficient at 1 N whatever n is. Integrated over the effective wrap:
///
/// * n = 1: T2 = T1 · exp(k β_eff)
/// * n < 1: T2 = (T1^(1-n) + (1-n) k β_eff)^(1/(1-n))
///
/// A cord with bending stiffness B (N m²) lifts off the capstan over a length √(B/T) at each
/// end, so β_eff = β − (√(B/T1) + √(B/T2))/r (r the capstan radius), never below zero.
///
/// mu_eff scales `mu` by (1 + a·t/100 s)(1 + w·(run−1))(1 + c·(d − 12.7 mm))(1 + s·(V − 10 V)):
/// a drift with time in the run, wear between runs, a diameter and a speed dependence; and by
/// exp(q·(β − 3π)) · exp(−h·H): a wrap dependence, and contact heating, where H (N s) is the
/// friction load (T2 − T1) remembered over `heat_tau_s` (see [`LoadMemory`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrictionLaw {
    /// Friction coefficient at the reference tension, conditions and time zero.
    pub mu: f64,
    /// Tension exponent n of dT/dθ = k·Tⁿ (1 = Euler-Eytelwein).
    pub tension_exponent: f64,
    /// Cord bending stiffness B, N m² (0 = perfectly flexible).
    pub bending_b_nm2: f64,
    /// Fractional change of mu per 100 s after the trigger (heating).
    pub mu_change_per_100s: f64,
    /// Fractional change of mu per repeat run (wear/polishing).
    pub mu_change_per_run: f64,
    /// Fractional change of mu per mm of capstan diameter above 12.7 mm.
    pub mu_change_per_mm: f64,
    /// Fractional change of mu per volt of drive above 10 V (speed).
    pub mu_change_per_v: f64,
    /// Logarithmic change of mu per radian of wrap beyond 3π (540°).
    pub mu_log_slope_per_rad: f64,
    /// Contact heating: mu falls by exp(−h·H) with the load memory H in N s; h in 1/(N s).
    pub heat_per_ns: f64,
    /// Time constant of the load memory, s (how long the contact remembers its friction load).
    pub heat_tau_s: f64,
}

impl FrictionLaw {
    /// Euler-Eytelwein: T2 = T1 · exp(mu β), nothing else.
    pub const fn euler_eytelwein(mu: f64) -> Self {
        FrictionLaw {
            mu,
            tension_exponent: 1.0,
            bending_b_nm2: 0.0,
            mu_change_per_100s: 0.0,
            mu_change_per_run: 0.0,
            mu_change_per_mm: 0.0,
            mu_change_per_v: 0.0,
            mu_log_slope_per_rad: 0.0,
            heat_per_ns: 0.0,
            heat_tau_s: 10.0,
        }
    }

    /// The friction coefficient in force at these operating conditions (never negative).
    pub fn effective_mu(&self, op: &Operating) -> f64 {
        let ln_factor = self.mu_log_slope_per_rad * (op.wrap_rad - REF_WRAP_RAD)
            - self.heat_per_ns * op.load_memory_ns;
        // exp(0) is exactly 1: skipping it changes no bit, and saves the most frequent call.
        let factor = if ln_factor == 0.0 {
            1.0
        } else {
            exp(ln_factor)
        };
        let mu = self.mu
            * (1.0 + self.mu_change_per_100s * op.time_s / 100.0)
            * (1.0 + self.mu_change_per_run * (op.run - 1.0))
            * (1.0 + self.mu_change_per_mm * (op.diameter_mm - REF_DIAMETER_MM))
            * (1.0 + self.mu_change_per_v * (op.drive_v - REF_DRIVE_V))
            * factor;
        mu.max(0.0)
    }

    /// The tension leaving the capstan (T2, N) for the tension entering it (T1, N).
    ///
    /// A slack or negative T1 is passed through unchanged (a slack cord carries no friction).
    pub fn t2_n(&self, t1_n: f64, op: &Operating) -> f64 {
        if t1_n.is_nan() || t1_n <= 0.0 {
            return t1_n;
        }
        let k = self.effective_mu(op);
        if self.bending_b_nm2 <= 0.0 {
            return self.integrate(t1_n, k, op.wrap_rad);
        }
        let radius_m = op.diameter_mm * 0.5e-3;
        let lift_rad = |t_n: f64| sqrt(self.bending_b_nm2 / t_n) / radius_m;
        let wrap_rad = op.wrap_rad - lift_rad(t1_n);
        // T2 = G(T2) = transmit over β − lost(T1) − lost(T2); G grows with T2, so from the
        // upper bound G(∞) Newton's method on G(y) − y descends onto the physical (largest)
        // fixed point. G'(y) = k·G^n·T_ref^(1-n) (the tension's growth rate at the exit) times
        // the lift-off's ½·√B/r·y^(-3/2).
        let n = self.tension_exponent;
        let k_n = if n == 1.0 {
            k
        } else {
            k * pow(REF_TENSION_N, 1.0 - n)
        };
        let mut t2_n = self.integrate(t1_n, k, wrap_rad);
        for _ in 0..60 {
            let lost = lift_rad(t2_n);
            let g = self.integrate(t1_n, k, wrap_rad - lost);
            let dg = if wrap_rad - lost > 0.0 {
                let g_n = if n == 1.0 { g } else { pow(g, n) };
                k_n * g_n * 0.5 * lost / t2_n
            } else {
                0.0
            };
            let next = t2_n - (g - t2_n) / (dg - 1.0);
            // Newton can overshoot below the root only if G is far from linear; fall back to
            // the plain iteration (monotone from above) then.
            let next = if next.is_finite() && next > 0.0 && next <= t2_n.max(g) {
                next
            } else {
                g
            };
            let done = (t2_n - next).abs() <= 1e-13 * t2_n;
            t2_n = next;
            if done {
                break;
            }
        }
        t2_n
    }

    /// Integrate dT/dθ = k·T_ref^(1-n)·Tⁿ from T1 over `wrap_rad` (clamped at zero).
    fn integrate(&self, t1_n: f64, k: f64, wrap_rad: f64) -> f64 {
        let wrap_rad = wrap_rad.max(0.0);
        let n = self.tension_exponent;
        let one_minus_n = 1.0 - n;
        if one_minus_n.abs() < 1e-9 {
            return t1_n * exp(k * wrap_rad);
        }
        let k_n = k * pow(REF_TENSION_N, one_minus_n);
        let base = pow(t1_n, one_minus_n) + one_minus_n * k_n * wrap_rad;
        if base <= 0.0 {
            // n > 1 can run away to infinite tension within the wrap; report it as such.
            return f64::INFINITY;
        }
        exp(log(base) / one_minus_n)
    }
}

/// The contact's memory of its friction load: dH/dt = (T2 − T1) − H/τ, so H settles at
/// τ·(T2 − T1) under a steady load and decays with τ when it goes. Integrated exactly for a
/// load held constant over each interval, so any step size gives the same answer.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LoadMemory {
    /// H, N s.
    pub h_ns: f64,
}

impl LoadMemory {
    /// Advance by `dt_s` under a friction load `load_n` = T2 − T1 (negative loads count as zero).
    pub fn advance(&mut self, dt_s: f64, load_n: f64, tau_s: f64) {
        if dt_s <= 0.0 || tau_s <= 0.0 {
            return;
        }
        let decay = exp(-dt_s / tau_s);
        self.h_ns = self.h_ns * decay + load_n.max(0.0) * tau_s * (1.0 - decay);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn op(wrap_deg: f64) -> Operating {
        Operating::from_wrap_deg(wrap_deg)
    }

    #[test]
    fn power_law_matches_numerical_integration() {
        let mut law = FrictionLaw::euler_eytelwein(0.12);
        law.tension_exponent = 0.8;
        let beta = op(630.0).wrap_rad;
        // RK4 on dT/dθ = k Tⁿ.
        let (mut t, steps) = (2.0f64, 20_000);
        let h = beta / steps as f64;
        let f = |t: f64| 0.12 * pow(t, 0.8);
        for _ in 0..steps {
            let k1 = f(t);
            let k2 = f(t + 0.5 * h * k1);
            let k3 = f(t + 0.5 * h * k2);
            let k4 = f(t + h * k3);
            t += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
        }
        let got = law.t2_n(2.0, &op(630.0));
        assert!((got / t - 1.0).abs() < 1e-9, "{got} vs {t}");
    }

    #[test]
    fn power_law_amplification_falls_with_tension() {
        let mut law = FrictionLaw::euler_eytelwein(0.12);
        law.tension_exponent = 0.85;
        let o = op(720.0);
        let amp = |t1: f64| law.t2_n(t1, &o) / t1;
        assert!(amp(0.5) > amp(5.0) && amp(5.0) > amp(20.0));
        // At the reference tension the local slope is mu, as for Euler-Eytelwein.
        let ee = FrictionLaw::euler_eytelwein(0.12);
        let d: f64 = 1e-6;
        let slope_pl = (law.t2_n(1.0, &op(d.to_degrees())) - 1.0) / d;
        let slope_ee = (ee.t2_n(1.0, &op(d.to_degrees())) - 1.0) / d;
        assert!((slope_pl - slope_ee).abs() < 1e-5);
    }

    #[test]
    fn bending_stiffness_solves_its_implicit_wrap() {
        let mut law = FrictionLaw::euler_eytelwein(0.115);
        law.bending_b_nm2 = 1e-4;
        let o = op(450.0);
        for t1 in [0.3, 1.0, 5.0, 20.0] {
            let t2 = law.t2_n(t1, &o);
            let r = o.diameter_mm * 0.5e-3;
            let lost = (sqrt(1e-4 / t1) + sqrt(1e-4 / t2)) / r;
            let want = t1 * exp(0.115 * (o.wrap_rad - lost).max(0.0));
            assert!((t2 / want - 1.0).abs() < 1e-10, "T1 {t1}: {t2} vs {want}");
        }
        // Stiffness costs most at low tension and on the small capstan.
        let ee = FrictionLaw::euler_eytelwein(0.115);
        let loss = |t1: f64, d_mm: f64| {
            let o = Operating {
                diameter_mm: d_mm,
                ..o
            };
            law.t2_n(t1, &o) / ee.t2_n(t1, &o)
        };
        assert!(loss(0.5, 12.7) < loss(5.0, 12.7));
        assert!(loss(0.5, 12.7) < loss(0.5, 25.4));
    }

    #[test]
    fn modulations_scale_mu() {
        let law = FrictionLaw {
            mu_change_per_100s: 0.1,
            mu_change_per_run: -0.02,
            mu_change_per_mm: 0.01,
            mu_change_per_v: 0.005,
            ..FrictionLaw::euler_eytelwein(0.1)
        };
        let o = Operating {
            wrap_rad: 1.0,
            diameter_mm: 25.4,
            drive_v: 20.0,
            run: 3.0,
            time_s: 50.0,
            load_memory_ns: 0.0,
        };
        let want = 0.1 * 1.05 * 0.96 * (1.0 + 0.127) * 1.05;
        assert!((law.effective_mu(&o) - want).abs() < 1e-12);
    }

    #[test]
    fn load_memory_settles_at_tau_times_load_whatever_the_step() {
        let (mut fine, mut coarse) = (LoadMemory::default(), LoadMemory::default());
        for _ in 0..10_000 {
            fine.advance(0.001, 20.0, 7.0);
        }
        coarse.advance(10.0, 20.0, 7.0);
        assert!((fine.h_ns - coarse.h_ns).abs() < 1e-9);
        assert!((coarse.h_ns - 140.0 * (1.0 - exp(-10.0 / 7.0))).abs() < 1e-9);
        // Heated contact: mu falls by exp(−h H).
        let law = FrictionLaw {
            heat_per_ns: 0.00128,
            ..FrictionLaw::euler_eytelwein(0.14)
        };
        let hot = Operating {
            load_memory_ns: 7.0 * 40.0,
            ..op(540.0)
        };
        assert!((law.effective_mu(&hot) - 0.14 * exp(-0.00128 * 280.0)).abs() < 1e-12);
        // The wrap slope is anchored at 540°.
        let law = FrictionLaw {
            mu_log_slope_per_rad: 0.015,
            ..FrictionLaw::euler_eytelwein(0.14)
        };
        assert!((law.effective_mu(&op(540.0)) - 0.14).abs() < 1e-12);
        assert!(law.effective_mu(&op(720.0)) > law.effective_mu(&op(270.0)));
    }

    #[test]
    fn slack_cord_passes_through() {
        let law = FrictionLaw::euler_eytelwein(0.1);
        assert_eq!(law.t2_n(0.0, &op(360.0)), 0.0);
        assert_eq!(law.t2_n(-0.2, &op(360.0)), -0.2);
    }
}
