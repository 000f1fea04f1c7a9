//! What a fit may spend. Every fit gets a work budget that grows with its data (rows and
//! parameters) but not without bound; the solver stops when it is spent and the fit says it
//! did not converge, with why. Work is counted, not timed, so a fit stops at the same point on
//! any machine and under any load: the same data give the same numbers, in a test build as in
//! a release build.
//!
//! One unit is one row's T2 prediction at given parameters; a Jacobian costs a prediction and
//! one more per free parameter for every row, and its QR factorisation m·n²/[`QR_FLOPS`] units
//! (m rows and group penalties, n parameters). On this project's 2-core machine a unit is
//! ~0.1–0.9 µs in a release build (a row with contact heating solves its step equation), so
//! [`MAX_FIT_UNITS`] is under a second.

use std::cell::Cell;

/// Units a fit may spend per row and parameter (room for ~100 solver iterations with their
/// Jacobians, far more than a fit that converges needs: the thesis's extended fit, 720 rows
/// and 14 parameters, uses ~0.07 M units of its 0.8 M).
pub const UNITS_PER_ROW_PARAM: u64 = 600;
/// The least any fit gets.
pub const MIN_FIT_UNITS: u64 = 200_000;
/// The most one fit of up to [`ROWS_AT_CAP`] rows gets, whatever its number of parameters
/// (under a second of one core at the slowest unit measured, ~0.9 µs).
pub const MAX_FIT_UNITS: u64 = 800_000;
/// Above this many rows the most a fit gets grows with them, [`UNITS_PER_ROW`] a row (as much
/// a row as [`MAX_FIT_UNITS`] gives the thesis's 720; its extended fit needs ~100).
pub const ROWS_AT_CAP: u64 = MAX_FIT_UNITS / UNITS_PER_ROW;
/// See [`ROWS_AT_CAP`].
pub const UNITS_PER_ROW: u64 = 1_000;
/// Floating-point operations of a QR factorisation per unit.
pub const QR_FLOPS: u64 = 400;

/// A fit's work budget. Not shared between threads: each fit owns its own, so where it stops
/// does not depend on what runs beside it.
#[derive(Debug)]
pub struct Budget {
    limit: u64,
    used: Cell<u64>,
}

impl Budget {
    /// A budget of `limit` units.
    pub fn new(limit: u64) -> Budget {
        Budget {
            limit,
            used: Cell::new(0),
        }
    }

    /// The most a fit on `rows` rows gets: [`MAX_FIT_UNITS`], or [`UNITS_PER_ROW`] a row for
    /// more than [`ROWS_AT_CAP`] rows.
    pub fn cap(rows: usize) -> u64 {
        MAX_FIT_UNITS.max(UNITS_PER_ROW.saturating_mul(rows as u64))
    }

    /// The budget of one fit on `rows` rows with `params` parameters (fixed and group
    /// effects): [`UNITS_PER_ROW_PARAM`] per row and parameter, at least [`MIN_FIT_UNITS`] and
    /// at most [`Budget::cap`].
    pub fn for_fit(rows: usize, params: usize) -> Budget {
        let units = UNITS_PER_ROW_PARAM.saturating_mul((rows.max(1) * params.max(1)) as u64);
        Budget::new(units.clamp(MIN_FIT_UNITS, Budget::cap(rows)))
    }

    /// A budget of at most `cap` units, for a fit that is one of many (a fold of a
    /// leave-one-out): [`Budget::for_fit`] or `cap`, whichever is less.
    pub fn for_fit_within(rows: usize, params: usize, cap: u64) -> Budget {
        let b = Budget::for_fit(rows, params);
        Budget::new(b.limit.min(cap.max(1)))
    }

    /// Spend `units`.
    pub fn charge(&self, units: u64) {
        self.used.set(self.used.get().saturating_add(units));
    }

    /// Is it spent?
    pub fn spent(&self) -> bool {
        self.used.get() >= self.limit
    }

    /// Units spent so far.
    pub fn used(&self) -> u64 {
        self.used.get()
    }

    /// Units it allows.
    pub fn limit(&self) -> u64 {
        self.limit
    }

    /// The cost of a Jacobian on `rows` rows with `free` fixed parameters, its matrix
    /// `m` × `n` factorised.
    pub fn jacobian_cost(rows: usize, free: usize, m: usize, n: usize) -> u64 {
        let eval = (rows * (free + 1)) as u64;
        let qr = (m as u64).saturating_mul((n * n) as u64) / QR_FLOPS;
        eval + qr
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn budgets_grow_with_the_data_within_bounds() {
        assert_eq!(Budget::for_fit(1, 1).limit(), MIN_FIT_UNITS);
        assert_eq!(Budget::for_fit(200, 3).limit(), 600 * 200 * 3);
        assert!(Budget::for_fit(400, 3).limit() > Budget::for_fit(200, 3).limit());
        assert_eq!(Budget::for_fit(720, 14).limit(), MAX_FIT_UNITS);
        assert_eq!(Budget::for_fit(100_000, 14).limit(), 100_000_000);
        assert_eq!(Budget::for_fit(1_000_000, 300).limit(), 1_000_000_000);
        assert_eq!(Budget::for_fit_within(720, 14, 1000).limit(), 1000);
        let b = Budget::new(10);
        b.charge(6);
        assert!(!b.spent());
        b.charge(u64::MAX);
        assert!(b.spent() && b.used() == u64::MAX);
    }
}
