//! What a real rig adds that no model fits: the scatter inside a run ([`Disturbances`]) and
//! physics outside the effect catalogue ([`Unmodelled`]).
//!
//! The shared friction law (`capstan_friction::Model`) is what the analysis fits; these live
//! only in the plant, so data made with them test whether the analysis notices structure it
//! has no name for, and whether its evidence holds when the noise is as large and as
//! correlated as the thesis rig's.
//!
//! * **Slow wander of mu**: ln mu follows an Ornstein-Uhlenbeck process within a run
//!   (stationary SD `mu_wander_sd`, correlation time `mu_wander_tau_s`), restarted from its
//!   stationary law at every run: the contact's state drifts between steps, so consecutive
//!   pairs of a run share their error (serial correlation).
//! * **Zero error after the tare**: each sensor's zero moves by a random amount (SD
//!   `zero_error_sd_n`) once the drive runs (bridge warm-up, amplifier ground shift): a run's
//!   own offset on both channels, which its tare cannot remove.
//!
//! Unmodelled physics, per cord:
//! * `hysteresis`: mu is larger by this fraction while the tension is falling (the servo last
//!   moved to release the cord): the contact remembers the direction it was loaded from.
//! * `t2_nonlinearity`: the T2 sensor's calibration curve is S-shaped: it reads
//!   T2 + q·c(T2), c a cubic that is zero at 0, R/2 and R (R = [`NONLINEARITY_REF_N`]) and ±1
//!   at its extremes (R/2·(1 ∓ 1/√3)): q is the largest error, N. A bowed (quadratic) error is not used: at the thesis rig's
//!   noise it is indistinguishable from contact heating, whose effect grows with the load in
//!   the same one-signed way (docs/README-diagnose.md).
//! * `regime_change`: mu changes by this fraction over a narrow band of true T1 around
//!   [`REGIME_T1_N`] (a logistic step [`REGIME_WIDTH_N`] wide): the cord flattens into a
//!   different contact at a tension, a kink no power law follows.

use crate::rng::Rng;

/// Span of the T2 sensor's S-shaped calibration error, N.
pub const NONLINEARITY_REF_N: f64 = 40.0;
/// Centre of the friction regime change, true T1 in N.
pub const REGIME_T1_N: f64 = 4.0;
/// Width of the regime change (logistic scale), N.
pub const REGIME_WIDTH_N: f64 = 0.5;
/// How often the wander of mu is advanced, µs.
pub const WANDER_STEP_US: u64 = 50_000;

/// Scatter a real rig adds inside a run (all zero: the quiet simulator).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Disturbances {
    /// Stationary SD of the wander of ln mu within a run (fraction of mu).
    pub mu_wander_sd: f64,
    /// Correlation time of that wander, s.
    pub mu_wander_tau_s: f64,
    /// SD of each sensor's zero error once the drive runs, N.
    pub zero_error_sd_n: f64,
}

impl Disturbances {
    /// None: the window means carry only the sensors' white noise.
    pub const QUIET: Disturbances = Disturbances {
        mu_wander_sd: 0.0,
        mu_wander_tau_s: 30.0,
        zero_error_sd_n: 0.0,
    };

    /// Is anything switched on?
    pub fn any(&self) -> bool {
        self.mu_wander_sd > 0.0 || self.zero_error_sd_n > 0.0
    }
}

impl Default for Disturbances {
    fn default() -> Self {
        Self::QUIET
    }
}

/// Physics outside the effect catalogue (all zero: none).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Unmodelled {
    /// Fractional increase of mu while the tension is falling.
    pub hysteresis: f64,
    /// T2 sensor's S-shaped calibration error: its largest deviation, N (module docs).
    pub t2_nonlinearity: f64,
    /// Fractional change of mu above the regime tension ([`REGIME_T1_N`]).
    pub regime_change: f64,
}

impl Unmodelled {
    /// Names and meanings, for command lines and reports.
    pub const NAMES: [&'static str; 3] = ["hysteresis", "t2_nonlinearity", "regime_change"];

    /// Set the one called `name` to `value`; `false` if there is no such name.
    pub fn set(&mut self, name: &str, value: f64) -> bool {
        match name {
            "hysteresis" => self.hysteresis = value,
            "t2_nonlinearity" => self.t2_nonlinearity = value,
            "regime_change" => self.regime_change = value,
            _ => return false,
        }
        true
    }

    /// Is anything switched on?
    pub fn any(&self) -> bool {
        self.hysteresis != 0.0 || self.t2_nonlinearity != 0.0 || self.regime_change != 0.0
    }

    /// Factor on mu at true tension `t1_n` while the tension is `falling`.
    pub fn mu_factor(&self, t1_n: f64, falling: bool) -> f64 {
        let mut f = 1.0;
        if falling {
            f *= 1.0 + self.hysteresis;
        }
        if self.regime_change != 0.0 {
            let s = 1.0 / (1.0 + libm::exp(-(t1_n - REGIME_T1_N) / REGIME_WIDTH_N));
            f *= 1.0 + self.regime_change * s;
        }
        f
    }

    /// The T2 sensor's reading of a tension, N.
    pub fn t2_reading_n(&self, t2_n: f64) -> f64 {
        if self.t2_nonlinearity == 0.0 {
            // What the sum below gives (T2 is finite, and never −0): without its square root
            // and two divisions, for every conversion of the T2 channel.
            return t2_n;
        }
        let a = 0.5 * NONLINEARITY_REF_N;
        // T(T − a)(T − 2a) peaks at ±2a³/(3√3).
        let peak = 2.0 * a * a * a / (3.0 * libm::sqrt(3.0));
        t2_n + self.t2_nonlinearity * t2_n * (t2_n - a) * (t2_n - 2.0 * a) / peak
    }
}

/// One cord's disturbance state: its wander of ln mu and its zero errors.
#[derive(Clone, Debug)]
pub(crate) struct DisturbState {
    rng: Rng,
    /// ln mu offset now.
    pub ln_mu: f64,
    /// Zero errors of the T1 and T2 readings while the drive runs, N.
    pub zero_error_n: [f64; 2],
}

impl DisturbState {
    /// A cord's state for a run: wander drawn from its stationary law, zero errors drawn.
    pub fn new(d: &Disturbances, seed: u64) -> Self {
        let mut rng = Rng::new(seed);
        let ln_mu = d.mu_wander_sd * rng.normal();
        let zero_error_n = [
            d.zero_error_sd_n * rng.normal(),
            d.zero_error_sd_n * rng.normal(),
        ];
        DisturbState {
            rng,
            ln_mu,
            zero_error_n,
        }
    }

    /// Advance the wander by `dt_s` (exact Ornstein-Uhlenbeck transition).
    pub fn advance(&mut self, d: &Disturbances, dt_s: f64) {
        if d.mu_wander_sd <= 0.0 || d.mu_wander_tau_s <= 0.0 {
            return;
        }
        let a = libm::exp(-dt_s / d.mu_wander_tau_s);
        self.ln_mu = a * self.ln_mu + d.mu_wander_sd * libm::sqrt(1.0 - a * a) * self.rng.normal();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wander_keeps_its_stationary_spread_and_memory() {
        let d = Disturbances {
            mu_wander_sd: 0.03,
            mu_wander_tau_s: 20.0,
            zero_error_sd_n: 0.0,
        };
        let mut s = DisturbState::new(&d, 7);
        let (mut sum2, mut lag, mut prev, n) = (0.0, 0.0, s.ln_mu, 200_000);
        for _ in 0..n {
            s.advance(&d, 10.0);
            sum2 += s.ln_mu * s.ln_mu;
            lag += s.ln_mu * prev;
            prev = s.ln_mu;
        }
        let sd = libm::sqrt(sum2 / n as f64);
        let rho = lag / sum2;
        assert!((sd / 0.03 - 1.0).abs() < 0.03, "{sd}");
        // Lag 10 s with τ = 20 s: exp(−0.5) = 0.607.
        assert!((rho - libm::exp(-0.5)).abs() < 0.02, "{rho}");
    }

    #[test]
    fn unmodelled_factors() {
        let u = Unmodelled {
            hysteresis: 0.1,
            t2_nonlinearity: -0.05,
            regime_change: -0.2,
        };
        assert!((u.mu_factor(0.5, true) / u.mu_factor(0.5, false) - 1.1).abs() < 1e-12);
        assert!((u.mu_factor(REGIME_T1_N, false) - 0.9).abs() < 1e-12);
        assert!((u.mu_factor(20.0, false) - 0.8).abs() < 1e-6);
        // Exact at 0, 20 and 40 N; its largest error is q, at 20(1 ∓ 1/√3) N.
        for t in [0.0, 20.0, 40.0] {
            assert!((u.t2_reading_n(t) - t).abs() < 1e-12);
        }
        let t_peak = 20.0 * (1.0 - 1.0 / libm::sqrt(3.0));
        assert!((u.t2_reading_n(t_peak) - t_peak - (-0.05)).abs() < 1e-12);
        assert!((u.t2_reading_n(40.0 - t_peak) - (40.0 - t_peak) - 0.05).abs() < 1e-12);
        let mut v = Unmodelled::default();
        assert!(!v.any() && v.set("hysteresis", 0.2) && v.any() && !v.set("x", 1.0));
    }
}
