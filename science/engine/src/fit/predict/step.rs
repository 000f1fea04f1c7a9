//! One step of a run: the contact's load memory over the step (bit for bit
//! `LoadMemory::advance`, with its partials) and the implicit step equation
//! T2 = t2_n(T1, H(T2)) solved for T2.

use capstan_physics::{FrictionLaw, LoadMemory, Operating};

/// [`LoadMemory::advance`] with its decay factor remembered for the last interval (a run's
/// steps share their timing): the same numbers, one exponential per distinct interval.
pub(super) struct Decay {
    tau: f64,
    dt: f64,
    a: f64,
}

impl Decay {
    pub(super) fn new(tau: f64) -> Decay {
        Decay {
            tau,
            dt: f64::NAN,
            a: 1.0,
        }
    }

    /// exp(−dt/τ), exactly as `LoadMemory::advance` computes it.
    pub(super) fn factor(&mut self, dt: f64) -> f64 {
        if dt != self.dt {
            let mut m = LoadMemory { h_ns: 1.0 };
            m.advance(dt, 0.0, self.tau);
            self.dt = dt;
            self.a = m.h_ns;
        }
        self.a
    }

    /// The memory after `dt` under `load`, bit for bit `LoadMemory::advance`.
    pub(super) fn after(&mut self, h: f64, dt: f64, load: f64) -> f64 {
        if dt <= 0.0 || self.tau <= 0.0 {
            return h;
        }
        let a = self.factor(dt);
        h * a + load.max(0.0) * self.tau * (1.0 - a)
    }
}

/// Memory after `dt` of constant `load`, and its partials (dH_new/dH_old, /dload, /dτ).
pub(super) fn memory_step(h: f64, dt: f64, load: f64, tau: f64) -> (f64, f64, f64, f64) {
    let mut m = LoadMemory { h_ns: h };
    m.advance(dt, load, tau);
    if dt <= 0.0 || tau <= 0.0 {
        return (m.h_ns, 1.0, 0.0, 0.0);
    }
    let a = (-dt / tau).exp();
    let l = load.max(0.0);
    let da_dtau = a * dt / (tau * tau);
    let d_tau = h * da_dtau + l * ((1.0 - a) - tau * da_dtau);
    let d_load = if load > 0.0 { tau * (1.0 - a) } else { 0.0 };
    (m.h_ns, a, d_load, d_tau)
}

/// The law's T2 at `x` with the contact remembering `h`.
pub(super) fn t2_at(law: &FrictionLaw, x: f64, op: &Operating, h: f64) -> f64 {
    let op = Operating {
        load_memory_ns: h,
        ..*op
    };
    law.t2_n(x, &op)
}

/// [`solve_step`]'s T2 by Newton's method from a nearby solution `y0` (falls back to the
/// bracketed search if Newton does not settle at once); `a` is the memory's decay over `dt_c`.
pub(super) fn solve_step_from(
    law: &FrictionLaw,
    x: f64,
    op: &Operating,
    (h_acc, dt_c, a): (f64, f64, f64),
    (y0, s0): (f64, f64),
) -> (f64, f64) {
    let tau = law.heat_tau_s;
    // The memory after dt_c, linear in the load: H(y) = h_acc·a + τ(1 − a)·max(y − x, 0),
    // a = exp(−dt_c/τ).
    let h_of = |y: f64| {
        if dt_c > 0.0 && tau > 0.0 {
            h_acc * a + (y - x).max(0.0) * tau * (1.0 - a)
        } else {
            h_acc
        }
    };
    let f = |y: f64| t2_at(law, x, op, h_of(y)) - y;
    if law.heat_per_ns != 0.0 && x > 0.0 && y0.is_finite() && y0 > x {
        let mut y = y0;
        let mut known = s0;
        for _ in 0..4 {
            let fy = f(y);
            if fy.abs() <= 1e-12 * y {
                return (y, known);
            }
            let given = known.is_finite() && known < 0.0;
            let slope = if given {
                known
            } else {
                let d = 1e-7 * y;
                (f(y + d) - fy) / d
            };
            let next = y - fy / slope;
            if !(slope < 0.0 && next.is_finite() && next > x) {
                break;
            }
            // From within 1e-5 of the root one Newton step on this point's slope lands within
            // ~1e-10 (the step equation is smooth, its slope changes by less than that
            // fraction): no need to evaluate it again. A slope given from nearby parameters
            // (off by up to a few per cent) only from within 1e-9.
            if fy.abs() <= if given { 1e-9 } else { 1e-5 } * y {
                return (next, slope);
            }
            y = next;
            known = f64::NAN;
        }
    }
    (solve_step(law, x, op, h_acc, dt_c).0, f64::NAN)
}

/// Solve y = t2_n(x, H(y)) with H(y) = memory after `dt_c` from `h_acc` under load y − x.
pub(super) fn solve_step(
    law: &FrictionLaw,
    x: f64,
    op: &Operating,
    h_acc: f64,
    dt_c: f64,
) -> (f64, f64) {
    let tau = law.heat_tau_s;
    let h_of = |y: f64| memory_step(h_acc, dt_c, y - x, tau).0;
    let rhs = |y: f64| t2_at(law, x, op, h_of(y));
    let y0 = rhs(x);
    if law.heat_per_ns == 0.0 || x <= 0.0 || !y0.is_finite() {
        return (y0, h_of(y0));
    }
    let f = |y: f64| rhs(y) - y;
    let (mut a, mut fa) = (x, y0 - x);
    if fa <= 0.0 {
        return (y0, h_of(y0));
    }
    let (mut b, mut fb) = (y0, f(y0));
    let mut tries = 0;
    while fb > 0.0 {
        // Heating that raises mu (h < 0) feeds back positively: look further up.
        a = b;
        fa = fb;
        b *= 2.0;
        fb = f(b);
        tries += 1;
        if tries > 60 || !fb.is_finite() {
            return (f64::INFINITY, f64::INFINITY);
        }
    }
    // Illinois regula falsi on the bracket [a, b] (f(a) > 0 >= f(b)).
    let mut side = 0i8;
    let mut y = b;
    for _ in 0..200 {
        y = (a * fb - b * fa) / (fb - fa);
        let fy = f(y);
        if fy == 0.0 || (b - a).abs() <= 1e-13 * b.abs().max(1e-9) {
            break;
        }
        if fy > 0.0 {
            a = y;
            fa = fy;
            if side == 1 {
                fb *= 0.5;
            }
            side = 1;
        } else {
            b = y;
            fb = fy;
            if side == -1 {
                fa *= 0.5;
            }
            side = -1;
        }
        if fy.abs() <= 1e-14 * y.abs() {
            break;
        }
    }
    (y, h_of(y))
}
