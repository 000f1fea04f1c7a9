//! The fitted capstan law as the board holds it: four numbers the host reduces the fitted model
//! to at the rig's diameter and drive voltage (`capstan rig load-model`), in f32.
//!
//! Along the contact dT/dθ = k·Tⁿ (n = 1: Euler-Eytelwein), k = mu_eff, and mu_eff = mu ·
//! exp(−h·(T2 − T1)): contact heating settled under the held load (the fitted model's
//! `heat_per_ns` times its memory's `heat_tau_s`). The T2 sensor reads `t2_offset_n` more while
//! the capstan turns (the tare, with the capstan stopped, cannot remove it), so the law maps a
//! T1 reading to a T2 reading, as the controller sees both.

use libm::{expf, powf};

/// The law: mu, heating, the T2 sensor's offset and the tension exponent.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub struct BoardLaw {
    /// mu at the rig's diameter and drive (0: no model).
    pub mu: f32,
    /// Contact heating, 1/N: mu falls by exp(−this·(T2 − T1)).
    pub heat_per_n: f32,
    /// What the T2 sensor adds while the capstan turns, N.
    pub t2_offset_n: f32,
    /// Tension exponent n of dT/dθ = k·Tⁿ (1: Euler-Eytelwein).
    pub exponent: f32,
}

/// Rounds of the fixed point on the heated mu (it contracts by ~0.1 a round on the thesis rig).
const ROUNDS: u32 = 6;

impl BoardLaw {
    /// No model.
    pub const NONE: BoardLaw = BoardLaw {
        mu: 0.0,
        heat_per_n: 0.0,
        t2_offset_n: 0.0,
        exponent: 1.0,
    };

    /// Euler-Eytelwein with one mu.
    pub const fn euler_eytelwein(mu: f32) -> BoardLaw {
        BoardLaw {
            mu,
            ..BoardLaw::NONE
        }
    }

    pub(super) fn validate(&self) -> Result<(), super::ForceError> {
        let ok = super::within(self.mu, 0.0, 2.0)
            && super::within(self.heat_per_n, 0.0, 1.0)
            && super::within(self.t2_offset_n, -5.0, 5.0)
            && super::within(self.exponent, 0.3, 1.0);
        ok.then_some(()).ok_or(super::ForceError::Model)
    }

    /// T2 leaving the contact for T1 entering it at heated coefficient `k`, over `beta_rad`.
    fn transmit(&self, t1: f32, k: f32, beta_rad: f32) -> f32 {
        let n = self.exponent;
        if n >= 1.0 {
            return t1 * expf(k * beta_rad);
        }
        let m = 1.0 - n;
        powf(powf(t1, m) + m * k * beta_rad, 1.0 / m)
    }

    /// T1 entering the contact for T2 leaving it at heated coefficient `k` (inverse of
    /// `transmit`; 0 where no T1 can give so little T2).
    fn receive(&self, t2: f32, k: f32, beta_rad: f32) -> f32 {
        let n = self.exponent;
        if n >= 1.0 {
            return t2 * expf(-k * beta_rad);
        }
        let m = 1.0 - n;
        let base = powf(t2, m) - m * k * beta_rad;
        if base <= 0.0 {
            0.0
        } else {
            powf(base, 1.0 / m)
        }
    }

    fn heated(&self, load_n: f32) -> f32 {
        if self.heat_per_n == 0.0 {
            self.mu
        } else {
            self.mu * expf(-self.heat_per_n * load_n.max(0.0))
        }
    }

    /// The T2 reading for a T1 reading (settled heating), N.
    pub fn t2_n(&self, t1_n: f32, beta_rad: f32) -> f32 {
        if t1_n.is_nan() || t1_n <= 0.0 {
            return t1_n.max(0.0) + self.t2_offset_n;
        }
        let mut t2 = self.transmit(t1_n, self.mu, beta_rad);
        // (This fixed point contracts by ~0.3 a round at 30 N: more rounds, off the hot path.)
        for _ in 0..3 * ROUNDS {
            t2 = self.transmit(t1_n, self.heated(t2 - t1_n), beta_rad);
        }
        t2 + self.t2_offset_n
    }

    /// The T1 reading the law needs for a T2 reading of `t2_n` (settled heating), N: the
    /// feedforward. At most `t2_n` less the offset (a capstan never loses tension), never below 0.
    pub fn t1_for(&self, t2_n: f32, beta_rad: f32) -> f32 {
        let t2 = t2_n - self.t2_offset_n;
        if t2.is_nan() || t2 <= 0.0 {
            return 0.0;
        }
        let mut t1 = self.receive(t2, self.mu, beta_rad);
        for _ in 0..ROUNDS {
            t1 = self.receive(t2, self.heated(t2 - t1), beta_rad);
        }
        t1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const BETA_720: f32 = 4.0 * core::f32::consts::PI;

    #[test]
    fn euler_eytelwein_inverts_exactly() {
        let law = BoardLaw::euler_eytelwein(0.115);
        let a = expf(0.115 * BETA_720);
        for t2 in [2.0f32, 5.0, 30.0] {
            let t1 = law.t1_for(t2, BETA_720);
            assert!((t1 * a / t2 - 1.0).abs() < 1e-5, "{t2}: {t1}");
            assert!((law.t2_n(t1, BETA_720) / t2 - 1.0).abs() < 1e-5);
        }
    }

    #[test]
    fn the_thesis_fit_round_trips_and_heating_costs_amplification() {
        // The extended model `capstan analyze` fits to the thesis data: mu 0.145, heating
        // 0.0332 /(N s) over a 0.25 s memory, T2 offset -0.82 N.
        let law = BoardLaw {
            mu: 0.145,
            heat_per_n: 0.0332 * 0.25,
            t2_offset_n: -0.82,
            exponent: 1.0,
        };
        for t2 in [5.0f32, 10.0, 20.0, 30.0] {
            let t1 = law.t1_for(t2, BETA_720);
            assert!((law.t2_n(t1, BETA_720) - t2).abs() < 1e-3, "{t2}: {t1}");
        }
        // Heated harder, 30 N needs relatively more T1 than 5 N does.
        let gain = |t2: f32| (t2 - law.t2_offset_n) / law.t1_for(t2, BETA_720);
        assert!(gain(30.0) < gain(5.0) * 0.9, "{} {}", gain(30.0), gain(5.0));
    }

    #[test]
    fn a_power_law_inverts_and_tiny_targets_need_no_t1() {
        let law = BoardLaw {
            exponent: 0.8,
            ..BoardLaw::euler_eytelwein(0.12)
        };
        let t1 = law.t1_for(12.0, BETA_720);
        assert!((law.t2_n(t1, BETA_720) - 12.0).abs() < 1e-3, "{t1}");
        assert_eq!(law.t1_for(-1.0, BETA_720), 0.0);
        let offset = BoardLaw {
            t2_offset_n: 1.0,
            ..law
        };
        assert_eq!(offset.t1_for(0.5, BETA_720), 0.0);
    }
}
