//! The model's scalars a fit may move, one row each ([`Scalar`]): its name (on JSON, in
//! reports, in an entry's `population.scalar`), how to read and set it in a [`Model`], how it
//! enters a prediction, its natural transform and a typical size. A scalar lives here beside
//! its law, so the fitter lists none by hand: a new law's scalar is one more row.

use crate::entry::Transform;
use crate::Model;

/// How a scalar enters a prediction (it decides how the fitter takes its sensitivity).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Enters {
    /// Inside the friction law's T2 (by central differences of the law).
    Law,
    /// The load memory's time constant (through the memory recursion).
    MemoryTime,
    /// Shifts the true T1.
    T1Offset,
    /// Adds to the measured T2.
    T2Offset,
    /// Multiplies the measured T2.
    T2Gain,
}

/// One scalar of [`Model`].
#[derive(Clone, Copy, Debug)]
pub struct Scalar {
    /// Its name.
    pub name: &'static str,
    /// Its value in a model.
    pub get: fn(&Model) -> f64,
    /// Set its value in a model.
    pub set: fn(&mut Model, f64),
    /// How it enters a prediction.
    pub enters: Enters,
    /// The transform a fit moves it on by default (`Log` for the positive ones).
    pub transform: Transform,
    /// A typical magnitude, to size finite-difference steps.
    pub scale: f64,
}

/// A scalar of the friction law, unbounded, of typical size 0.01.
const fn law(name: &'static str, get: fn(&Model) -> f64, set: fn(&mut Model, f64)) -> Scalar {
    Scalar {
        name,
        get,
        set,
        enters: Enters::Law,
        transform: Transform::Identity,
        scale: 0.01,
    }
}

/// Every scalar, in the fitter's order.
pub const SCALARS: [Scalar; 13] = [
    Scalar {
        transform: Transform::Log,
        scale: 0.1,
        ..law("mu", |m| m.law.mu, |m, v| m.law.mu = v)
    },
    Scalar {
        transform: Transform::Logistic { lo: 0.3, hi: 1.7 },
        scale: 1.0,
        ..law(
            "n",
            |m| m.law.tension_exponent,
            |m, v| m.law.tension_exponent = v,
        )
    },
    Scalar {
        transform: Transform::Log,
        scale: 1e-5,
        ..law(
            "b_nm2",
            |m| m.law.bending_b_nm2,
            |m, v| m.law.bending_b_nm2 = v,
        )
    },
    law(
        "mu_change_per_100s",
        |m| m.law.mu_change_per_100s,
        |m, v| m.law.mu_change_per_100s = v,
    ),
    law(
        "mu_change_per_run",
        |m| m.law.mu_change_per_run,
        |m, v| m.law.mu_change_per_run = v,
    ),
    Scalar {
        scale: 1e-3,
        ..law(
            "mu_change_per_mm",
            |m| m.law.mu_change_per_mm,
            |m, v| m.law.mu_change_per_mm = v,
        )
    },
    law(
        "mu_change_per_v",
        |m| m.law.mu_change_per_v,
        |m, v| m.law.mu_change_per_v = v,
    ),
    law(
        "mu_log_slope_per_rad",
        |m| m.law.mu_log_slope_per_rad,
        |m, v| m.law.mu_log_slope_per_rad = v,
    ),
    Scalar {
        transform: Transform::Log,
        scale: 1e-3,
        ..law(
            "heat_per_ns",
            |m| m.law.heat_per_ns,
            |m, v| m.law.heat_per_ns = v,
        )
    },
    Scalar {
        enters: Enters::MemoryTime,
        transform: Transform::Log,
        ..law(
            "heat_tau_s",
            |m| m.law.heat_tau_s,
            |m, v| m.law.heat_tau_s = v,
        )
    },
    Scalar {
        enters: Enters::T1Offset,
        ..law(
            "t1_offset_n",
            |m| m.sensors.t1_offset_n,
            |m, v| m.sensors.t1_offset_n = v,
        )
    },
    Scalar {
        enters: Enters::T2Offset,
        ..law(
            "t2_offset_n",
            |m| m.sensors.t2_offset_n,
            |m, v| m.sensors.t2_offset_n = v,
        )
    },
    Scalar {
        enters: Enters::T2Gain,
        transform: Transform::Log,
        ..law(
            "t2_gain",
            |m| m.sensors.t2_gain,
            |m, v| m.sensors.t2_gain = v,
        )
    },
];

/// The position of the scalar `name` in [`SCALARS`] (a compile-time error in a `const` when
/// there is none).
pub const fn index_of(name: &str) -> usize {
    let mut i = 0;
    while i < SCALARS.len() {
        if eq(SCALARS[i].name.as_bytes(), name.as_bytes()) {
            return i;
        }
        i += 1;
    }
    panic!("no such model scalar");
}

const fn eq(a: &[u8], b: &[u8]) -> bool {
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_scalar_reads_back_what_is_set_and_names_are_unique() {
        for (i, s) in SCALARS.iter().enumerate() {
            let mut m = Model::euler_eytelwein(0.1);
            (s.set)(&mut m, 0.4321);
            assert_eq!((s.get)(&m), 0.4321, "{}", s.name);
            assert_eq!(index_of(s.name), i);
        }
    }

    #[test]
    fn every_entry_moves_a_scalar_of_the_table() {
        for e in crate::ENTRIES.iter().skip(1) {
            let _ = index_of(e.population.scalar);
        }
    }
}
