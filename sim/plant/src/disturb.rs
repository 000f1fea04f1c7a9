//! What a real rig adds that no model fits: the scatter inside a run ([`Disturbances`]) and
//! physics outside the effect catalogue ([`Unmodelled`]).
//!
//! The shared friction law (`capstan_physics::Model`) is what the analysis fits; these live
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
//!
//! Five more for `capstan discover`'s validation (docs/README-discover.md): four that its
//! library can express, one it cannot.
//! * `t2_lowforce`: the T2 hook seats at low force: T2 reads T2 + q·(1 − e^{−T2/1 N}), N.
//! * `t1_tare_diameter`: the T1 tare differs between capstan sessions: while the drive runs T1
//!   reads T1 − q·(D − D_ref)/D_ref ([`TARE_REF_DIAMETER_MM`]), N.
//! * `t2_offset_wrap`: the T2 sensor is re-mounted for every wrap and its zero moves: while
//!   the drive runs T2 reads T2 + q·(β − β_ref)/2π ([`capstan_physics::REF_WRAP_RAD`]), N per
//!   turn.
//! * `settling`: the contact settles after the trigger: mu·(1 − c·e^{−t/10 s}).
//! * `t2_range_step` (not expressible): the T2 amplifier switches range at
//!   [`RANGE_STEP_T2_N`]: T2 reads q more above it (a logistic step 0.3 N wide), N.
//!
//! Three more (issue 41), which its library can express:
//! * `t2_quadratic`, `t1_quadratic`: a load cell's calibration is bowed: it reads
//!   T + q·(T/[`QUADRATIC_REF_N`])², q the error at that force, N (T2's, or T1's).
//! * `mu_bump`: mu is larger (or smaller) by this fraction over a band of true T1 around
//!   [`BUMP_T1_N`]: a Gaussian in ln T1 of SD [`BUMP_WIDTH_LN`] (a contact regime between the
//!   cord's conforming at low tension and its softening at high tension).

use crate::rng::Rng;

/// Span of the T2 sensor's S-shaped calibration error, N.
pub const NONLINEARITY_REF_N: f64 = 40.0;
/// Centre of the friction regime change, true T1 in N.
pub const REGIME_T1_N: f64 = 4.0;
/// Width of the regime change (logistic scale), N.
pub const REGIME_WIDTH_N: f64 = 0.5;
/// Reference diameter of `t1_tare_diameter` (the middle of the thesis's two capstans), mm.
pub const TARE_REF_DIAMETER_MM: f64 = 19.05;
/// Time constant of `settling`, s.
pub const SETTLING_TAU_S: f64 = 10.0;
/// Where the T2 amplifier of `t2_range_step` switches range, N.
pub const RANGE_STEP_T2_N: f64 = 15.0;
/// Force at which `t2_quadratic`'s error is its size, N.
pub const QUADRATIC_REF_N: f64 = 20.0;
/// Centre of `mu_bump`, true T1 in N.
pub const BUMP_T1_N: f64 = 6.0;
/// Width of `mu_bump`: SD in ln T1.
pub const BUMP_WIDTH_LN: f64 = 0.5;
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
    /// T2 hook seating at low force: its full size, N.
    pub t2_lowforce: f64,
    /// T1 tare per capstan: N per relative diameter from [`TARE_REF_DIAMETER_MM`].
    pub t1_tare_diameter: f64,
    /// T2 zero per wrap: N per turn from the reference wrap.
    pub t2_offset_wrap: f64,
    /// Settling of mu after the trigger: its fraction at t = 0.
    pub settling: f64,
    /// T2 amplifier range switch at [`RANGE_STEP_T2_N`]: the step, N.
    pub t2_range_step: f64,
    /// Bowed T2 calibration: its error at [`QUADRATIC_REF_N`], N.
    pub t2_quadratic: f64,
    /// Bowed T1 calibration: its error at [`QUADRATIC_REF_N`], N.
    pub t1_quadratic: f64,
    /// Bump of mu around [`BUMP_T1_N`]: its fraction at the centre.
    pub mu_bump: f64,
}

impl Unmodelled {
    /// Names and meanings, for command lines and reports.
    /// (The diagnose suite's outside cases draw from these three.)
    pub const NAMES: [&'static str; 3] = ["hysteresis", "t2_nonlinearity", "regime_change"];
    /// Every kind, for command lines (`capstan simulate --unmodelled`) and `capstan discover`'s
    /// validation.
    pub const ALL_NAMES: [&'static str; 11] = [
        "hysteresis",
        "t2_nonlinearity",
        "regime_change",
        "t2_lowforce",
        "t1_tare_diameter",
        "t2_offset_wrap",
        "settling",
        "t2_range_step",
        "t2_quadratic",
        "mu_bump",
        "t1_quadratic",
    ];

    /// Set the one called `name` to `value`; `false` if there is no such name.
    pub fn set(&mut self, name: &str, value: f64) -> bool {
        match name {
            "hysteresis" => self.hysteresis = value,
            "t2_nonlinearity" => self.t2_nonlinearity = value,
            "regime_change" => self.regime_change = value,
            "t2_lowforce" => self.t2_lowforce = value,
            "t1_tare_diameter" => self.t1_tare_diameter = value,
            "t2_offset_wrap" => self.t2_offset_wrap = value,
            "settling" => self.settling = value,
            "t2_range_step" => self.t2_range_step = value,
            "t2_quadratic" => self.t2_quadratic = value,
            "mu_bump" => self.mu_bump = value,
            "t1_quadratic" => self.t1_quadratic = value,
            _ => return false,
        }
        true
    }

    /// Is anything switched on?
    pub fn any(&self) -> bool {
        self.values().iter().any(|v| *v != 0.0)
    }

    /// Every value, in [`Unmodelled::ALL_NAMES`] order.
    pub fn values(&self) -> [f64; 11] {
        [
            self.hysteresis,
            self.t2_nonlinearity,
            self.regime_change,
            self.t2_lowforce,
            self.t1_tare_diameter,
            self.t2_offset_wrap,
            self.settling,
            self.t2_range_step,
            self.t2_quadratic,
            self.mu_bump,
            self.t1_quadratic,
        ]
    }

    /// Factor on mu from `settling`, `time_s` after the trigger.
    pub fn settling_factor(&self, time_s: f64) -> f64 {
        if self.settling == 0.0 {
            return 1.0;
        }
        1.0 - self.settling * libm::exp(-time_s.max(0.0) / SETTLING_TAU_S)
    }

    /// What the T1 reading adds while the drive runs, on a capstan of `diameter_mm`, N.
    pub fn t1_offset_n(&self, diameter_mm: f64) -> f64 {
        -self.t1_tare_diameter * (diameter_mm - TARE_REF_DIAMETER_MM) / TARE_REF_DIAMETER_MM
    }

    /// What the T2 reading adds while the drive runs, at a wrap of `wrap_rad`, N.
    pub fn t2_offset_n(&self, wrap_rad: f64) -> f64 {
        self.t2_offset_wrap * (wrap_rad - capstan_physics::REF_WRAP_RAD)
            / (2.0 * core::f64::consts::PI)
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
        if self.mu_bump != 0.0 && t1_n > 0.0 {
            let z = libm::log(t1_n / BUMP_T1_N) / BUMP_WIDTH_LN;
            f *= 1.0 + self.mu_bump * libm::exp(-0.5 * z * z);
        }
        f
    }

    /// The T1 sensor's reading of a tension (its calibration curve), N.
    pub fn t1_reading_n(&self, t1_n: f64) -> f64 {
        if self.t1_quadratic == 0.0 {
            return t1_n;
        }
        let r = t1_n / QUADRATIC_REF_N;
        t1_n + self.t1_quadratic * r * r
    }

    /// The T2 sensor's reading of a tension, N.
    pub fn t2_reading_n(&self, t2_n: f64) -> f64 {
        let mut extra = 0.0;
        if self.t2_lowforce != 0.0 {
            extra += self.t2_lowforce * (1.0 - libm::exp(-t2_n.max(0.0)));
        }
        if self.t2_range_step != 0.0 {
            extra += self.t2_range_step / (1.0 + libm::exp(-(t2_n - RANGE_STEP_T2_N) / 0.3));
        }
        if self.t2_quadratic != 0.0 {
            let r = t2_n / QUADRATIC_REF_N;
            extra += self.t2_quadratic * r * r;
        }
        extra + self.t2_nonlinear_reading_n(t2_n)
    }

    fn t2_nonlinear_reading_n(&self, t2_n: f64) -> f64 {
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
            ..Unmodelled::default()
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
        for name in Unmodelled::ALL_NAMES {
            let mut w = Unmodelled::default();
            assert!(w.set(name, 0.5) && w.any(), "{name}");
        }
    }

    #[test]
    fn the_discover_kinds_act_where_their_docs_say() {
        let u = Unmodelled {
            t2_lowforce: 0.8,
            t2_range_step: 0.6,
            settling: 0.1,
            t1_tare_diameter: 0.3,
            t2_offset_wrap: -0.4,
            ..Unmodelled::default()
        };
        // Low-force seating: 0 at 0 N, its full size well above 1 N; the range step above 15 N.
        assert!(u.t2_reading_n(0.0).abs() < 1e-12);
        assert!((u.t2_reading_n(10.0) - 10.0 - 0.8).abs() < 1e-3);
        assert!((u.t2_reading_n(30.0) - 30.0 - 1.4).abs() < 1e-3);
        assert!((u.settling_factor(0.0) - 0.9).abs() < 1e-12);
        assert!((u.settling_factor(100.0) - 1.0).abs() < 1e-4);
        assert!(u.t1_offset_n(TARE_REF_DIAMETER_MM).abs() < 1e-12);
        assert!((u.t1_offset_n(12.7) - 0.1).abs() < 1e-12);
        let three_turns = 3.0 * core::f64::consts::PI;
        assert!(u.t2_offset_n(three_turns).abs() < 1e-12);
        assert!((u.t2_offset_n(three_turns + 2.0 * core::f64::consts::PI) + 0.4).abs() < 1e-12);
        // The bowed T2 cell: q at the reference force, a quarter of it at half.
        let q = Unmodelled {
            t2_quadratic: 0.4,
            mu_bump: 0.2,
            ..Unmodelled::default()
        };
        assert!((q.t2_reading_n(QUADRATIC_REF_N) - QUADRATIC_REF_N - 0.4).abs() < 1e-12);
        assert!((q.t2_reading_n(10.0) - 10.0 - 0.1).abs() < 1e-12);
        let q1 = Unmodelled {
            t1_quadratic: -0.4,
            ..Unmodelled::default()
        };
        assert!((q1.t1_reading_n(10.0) - 10.0 + 0.1).abs() < 1e-12);
        assert_eq!(q1.t2_reading_n(10.0), 10.0);
        // The bump: its full size at the centre, e^{-1/2} of it one width away, none far off.
        assert!((q.mu_factor(BUMP_T1_N, false) - 1.2).abs() < 1e-12);
        let one_sd = BUMP_T1_N * libm::exp(BUMP_WIDTH_LN);
        assert!((q.mu_factor(one_sd, false) - 1.0 - 0.2 * libm::exp(-0.5)).abs() < 1e-12);
        assert!((q.mu_factor(0.3, false) - 1.0).abs() < 1e-3);
    }
}
