//! The fitted model reduced to the law the board holds (`capstan_rig::BoardLaw`): the model at
//! the rig's operating point (its wrap, diameter and drive voltage, the first run of a fresh
//! cord, the contact's heating settled under the held load, as `capstan predict` takes it),
//! with every term the board's four numbers cannot carry checked to make no difference there.

use capstan_physics::{Model, Operating};
use capstan_rig::BoardLaw;
use std::fmt;

/// How close the board's law must follow the model's T2 reading over the rig's T1 range: 1 %
/// or 0.05 N, whichever is larger.
pub const TOLERANCE_REL: f64 = 0.01;
/// See [`TOLERANCE_REL`].
pub const TOLERANCE_N: f64 = 0.05;

/// Why a model cannot be the board's law.
#[derive(Clone, Debug, PartialEq)]
pub enum LawError {
    /// The model has no friction (mu ≤ 0) or a value that is not finite.
    NoFriction,
    /// The board's law misses the model's T2 by more than the tolerance somewhere in the T1
    /// range: at this T1 reading, the model's and the board's T2 readings (N), and why.
    Misses {
        /// T1 reading, N.
        t1_n: f64,
        /// The model's T2 reading, N.
        model_t2_n: f64,
        /// The board law's T2 reading, N.
        board_t2_n: f64,
    },
    /// A value is outside what the board takes (`capstan_rig::ForceError::Model`): the name.
    OutOfRange(&'static str, f64),
}

impl fmt::Display for LawError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LawError::NoFriction => f.write_str("the model has no friction coefficient above 0"),
            LawError::Misses {
                t1_n,
                model_t2_n,
                board_t2_n,
            } => write!(
                f,
                "the board's law (mu, settled heating, T2 offset, tension exponent) misses the \
                 model at T1 = {t1_n:.2} N: {board_t2_n:.3} N against {model_t2_n:.3} N (more \
                 than 1 % or 0.05 N): the model has terms the board cannot hold there (bending \
                 stiffness, a T1 offset, a T2 gain, a drift with time or wear)"
            ),
            LawError::OutOfRange(name, v) => {
                write!(f, "{name} = {v} is outside what the board takes")
            }
        }
    }
}

impl std::error::Error for LawError {}

/// The model's T2 reading for a T1 reading at `op`, with the contact's load memory settled
/// under it (H = τ·(T2 − T1), by fixed point).
pub fn settled_t2_n(model: &Model, t1_n: f64, op: &Operating) -> f64 {
    let mut op = *op;
    let tau = model.law.heat_tau_s;
    let mut t2 = model.predict_t2_n(t1_n, &op);
    for _ in 0..200 {
        let t1_true = model.sensors.true_t1_n(t1_n);
        let t2_true = (t2 - model.sensors.t2_offset_n) / model.sensors.t2_gain;
        op.load_memory_ns = tau * (t2_true - t1_true).max(0.0);
        let next = model.predict_t2_n(t1_n, &op);
        let done = (next - t2).abs() < 1e-12 * next.abs().max(1.0);
        // Damped: the fixed point alternates at high loads.
        t2 = 0.5 * (t2 + next);
        if done {
            break;
        }
    }
    t2
}

/// The board's law for `model` at `op` (its wrap, diameter, drive voltage; run 1, time 0),
/// checked against the model's settled T2 reading for T1 readings from 0.2 N to `t1_max_n`.
pub fn board_law(model: &Model, op: &Operating, t1_max_n: f64) -> Result<BoardLaw, LawError> {
    let law = &model.law;
    let op0 = Operating {
        run: 1.0,
        time_s: 0.0,
        load_memory_ns: 0.0,
        ..*op
    };
    let mu = law.effective_mu(&op0);
    if !(mu.is_finite() && mu > 0.0) {
        return Err(LawError::NoFriction);
    }
    let board = BoardLaw {
        mu: mu as f32,
        heat_per_n: (law.heat_per_ns * law.heat_tau_s) as f32,
        t2_offset_n: model.sensors.t2_offset_n as f32,
        exponent: law.tension_exponent as f32,
    };
    for (name, v, lo, hi) in [
        ("mu", board.mu, 0.0, 2.0),
        (
            "heating (heat_per_ns x heat_tau_s)",
            board.heat_per_n,
            0.0,
            1.0,
        ),
        ("t2_offset_n", board.t2_offset_n, -5.0, 5.0),
        ("tension exponent n", board.exponent, 0.3, 1.0),
    ] {
        if !(v.is_finite() && v >= lo && v <= hi) {
            return Err(LawError::OutOfRange(name, f64::from(v)));
        }
    }
    let beta = op.wrap_rad as f32;
    let n = 40;
    for k in 0..=n {
        let t1 = 0.2 + (t1_max_n - 0.2) * k as f64 / n as f64;
        let want = settled_t2_n(model, t1, &op0);
        let got = f64::from(board.t2_n(t1 as f32, beta));
        if (got - want).abs() > TOLERANCE_N.max(TOLERANCE_REL * want.abs()) {
            return Err(LawError::Misses {
                t1_n: t1,
                model_t2_n: want,
                board_t2_n: got,
            });
        }
    }
    Ok(board)
}

#[cfg(test)]
mod tests {
    use super::*;
    use capstan_physics::Effect;
    use capstan_physics::EffectKind;

    #[test]
    fn the_thesis_fit_reduces_exactly_and_bending_stiffness_is_refused() {
        let model = super::super::thesis_fit();
        let op = Operating::from_wrap_deg(720.0);
        let law = board_law(&model, &op, 9.0).unwrap();
        assert!((f64::from(law.mu) - model.law.mu).abs() < 1e-6);
        assert!((f64::from(law.t2_offset_n) + 0.823).abs() < 1e-3);
        let bent = model.with_effect(Effect {
            kind: EffectKind::BendingStiffness,
            value: 2e-4,
        });
        assert!(matches!(
            board_law(&bent, &op, 9.0),
            Err(LawError::Misses { .. })
        ));
    }
}
