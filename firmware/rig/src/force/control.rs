//! The control law of force control, pure: `step(state, params, input) -> (state, output)`, once
//! per control period ([`CONTROL_HZ`]), on the measurements averaged over the period.
//!
//! ```text
//! target ─► shaped reference r (a jump eased over force_shape_ms, bumpless)
//!   e = r − T2            (T2 measured)
//!   u = r·(1 + I) + kp·e  (demand: the target corrected by the feedback; 0 ≤ u ≤ 90 % of the
//!                          over-force limit)
//!   dI/dt = ki·e / r      (the integral as a gain on the target: a cord whose mu differs from
//!                          the model's is off by a factor, the same at every level; frozen while
//!                          the demand, the servo's speed or its travel is at a limit: anti-windup)
//!   T1* = law⁻¹(u)        (feedforward through the fitted capstan law)
//!   dθ/dt = −t1_gain·(T1* − T1), |dθ/dt| ≤ force_rate_deg_s, final_deg ≤ θ ≤ rest_deg
//! ```
//!
//! The last line is the T1 loop: the servo is a position device, the angle its integrator
//! (more tension is a smaller angle: rest is the end that releases). kp = ki = 0 is open loop
//! in T2: T2 is then only what the law makes of the T1 the loop holds.

use super::law::BoardLaw;

/// Control periods per second.
pub const CONTROL_HZ: u32 = 100;

/// The integral's range: the demand may be corrected by a factor 0.5 to 2.
const INTEGRAL_MIN: f32 = -0.5;
const INTEGRAL_MAX: f32 = 1.0;

/// What the law needs that does not change during a run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// The fitted law.
    pub law: BoardLaw,
    /// Wrap, rad.
    pub beta_rad: f32,
    /// Proportional gain on the T2 error, N/N.
    pub kp: f32,
    /// Integral gain, 1/s.
    pub ki: f32,
    /// The T1 loop's gain, deg/s per N.
    pub t1_gain: f32,
    /// Fastest servo command, deg/s.
    pub rate_deg_s: f32,
    /// What is left of a target's jump after one period (exp(−dt/τ); 0: no shaping).
    pub shape_decay: f32,
    /// Rest: the servo's release end, deg.
    pub rest_deg: f32,
    /// The servo's tension end, deg (the protocol's final angle).
    pub travel_deg: f32,
    /// Largest demand, N.
    pub max_demand_n: f32,
    /// Control period, s.
    pub dt_s: f32,
}

/// The controller's memory.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct State {
    /// Servo command, deg.
    pub servo_deg: f32,
    /// The integral: the demand's correction as a fraction of the reference.
    pub integral: f32,
    /// What the shaped reference still differs from the target, N.
    pub shape_n: f32,
    /// The last target (0: rest), N.
    pub target_n: f32,
}

impl State {
    /// At rest, nothing learned.
    pub const fn at_rest(rest_deg: f32) -> State {
        State {
            servo_deg: rest_deg,
            integral: 0.0,
            shape_n: 0.0,
            target_n: 0.0,
        }
    }
}

/// One control period's measurements and target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Input {
    /// The T2 target (0: none, go to rest), N.
    pub target_n: f32,
    /// A new segment began: a jump of the target from the last is shaped (a continuous one
    /// adds nothing).
    pub new_segment: bool,
    /// T1, mean over the period, N.
    pub t1_n: f32,
    /// T2, mean over the period, N.
    pub t2_n: f32,
}

/// What the law commands.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Output {
    /// Servo angle, deg.
    pub servo_deg: f32,
    /// The shaped reference, N.
    pub reference_n: f32,
    /// The demand after feedback, N.
    pub demand_n: f32,
    /// The T1 the law needs for the demand, N.
    pub t1_ref_n: f32,
}

#[allow(clippy::manual_clamp)] // f32::clamp's assertion links float formatting on the board.
fn clamp(v: f32, lo: f32, hi: f32) -> f32 {
    if v < lo {
        lo
    } else if v > hi {
        hi
    } else {
        v
    }
}

/// One control period.
pub fn step(s: &State, p: &Params, inp: &Input) -> (State, Output) {
    let mut next = *s;
    if inp.target_n.is_nan() || inp.target_n <= 0.0 {
        // No target: back to rest at the servo's speed; what was learned is kept.
        let to_rest = clamp(p.rest_deg - s.servo_deg, 0.0, p.rate_deg_s * p.dt_s);
        next.servo_deg = s.servo_deg + to_rest;
        next.target_n = 0.0;
        next.shape_n = 0.0;
        let out = Output {
            servo_deg: next.servo_deg,
            reference_n: 0.0,
            demand_n: 0.0,
            t1_ref_n: 0.0,
        };
        return (next, out);
    }
    if inp.new_segment {
        // Bumpless: the reference starts where the last one was (from rest: at the measured T2).
        let from = if s.target_n > 0.0 {
            s.target_n + s.shape_n
        } else {
            inp.t2_n
        };
        next.shape_n = if p.shape_decay > 0.0 && from.is_finite() {
            from - inp.target_n
        } else {
            0.0
        };
    }
    next.target_n = inp.target_n;
    let r = inp.target_n + next.shape_n;
    next.shape_n *= p.shape_decay;
    let e = r - inp.t2_n;
    let e = if e.is_finite() { e } else { 0.0 };
    let raw_demand = r * (1.0 + s.integral) + p.kp * e;
    let demand = clamp(raw_demand, 0.0, p.max_demand_n);
    let t1_ref = p.law.t1_for(demand, p.beta_rad);
    let t1_err = if inp.t1_n.is_finite() {
        t1_ref - inp.t1_n
    } else {
        0.0
    };
    let speed = -p.t1_gain * t1_err;
    let limit = p.rate_deg_s;
    let servo = clamp(
        s.servo_deg + clamp(speed, -limit, limit) * p.dt_s,
        p.travel_deg,
        p.rest_deg,
    );
    next.servo_deg = servo;
    // Anti-windup: integrate only while nothing is at a limit in the direction the error asks
    // for (more T2: a larger demand, a smaller angle).
    let demand_stuck = (raw_demand >= p.max_demand_n && e > 0.0) || (raw_demand <= 0.0 && e < 0.0);
    let servo_stuck = speed.abs() > limit
        || (servo <= p.travel_deg && e > 0.0)
        || (servo >= p.rest_deg && e < 0.0);
    if !(demand_stuck || servo_stuck) {
        let di = p.ki * p.dt_s * e / r.max(super::MIN_TARGET_N);
        next.integral = clamp(s.integral + di, INTEGRAL_MIN, INTEGRAL_MAX);
    }
    let out = Output {
        servo_deg: servo,
        reference_n: r,
        demand_n: demand,
        t1_ref_n: t1_ref,
    };
    (next, out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> Params {
        Params {
            law: BoardLaw::euler_eytelwein(0.115),
            beta_rad: 4.0 * core::f32::consts::PI,
            kp: 0.3,
            ki: 3.0,
            t1_gain: 120.0,
            rate_deg_s: 250.0,
            shape_decay: 0.0,
            rest_deg: 125.0,
            travel_deg: 65.0,
            max_demand_n: 40.5,
            dt_s: 0.01,
        }
    }

    /// A static rig: T1 = stiffness·(rest − θ), T2 = amplification·T1.
    fn close_loop(p: &Params, amplification: f32, target: f32, periods: u32) -> (State, f32) {
        let mut s = State::at_rest(p.rest_deg);
        let mut t2 = 0.0;
        for i in 0..periods {
            let t1 = 0.15 * (p.rest_deg - s.servo_deg);
            t2 = amplification * t1;
            let inp = Input {
                target_n: target,
                new_segment: i == 0,
                t1_n: t1,
                t2_n: t2,
            };
            s = step(&s, p, &inp).0;
        }
        (s, t2)
    }

    #[test]
    fn feedback_holds_the_target_on_a_cord_the_law_gets_wrong() {
        let p = params();
        let a = libm::expf(0.115 * p.beta_rad);
        // mu 20 % high: the law's T1 gives a third more T2; the integral takes it out.
        let strong = libm::expf(0.138 * p.beta_rad);
        let (s, t2) = close_loop(&p, strong, 20.0, 1_000);
        assert!((t2 - 20.0).abs() < 0.02, "{t2}");
        assert!(
            (s.integral - (a / strong - 1.0)).abs() < 0.01,
            "{}",
            s.integral
        );
        // Open loop on the same cord: off by the factor.
        let open = Params {
            kp: 0.0,
            ki: 0.0,
            ..p
        };
        let (_, t2) = close_loop(&open, strong, 20.0, 1_000);
        assert!((t2 / 20.0 - strong / a).abs() < 0.01, "{t2}");
    }

    #[test]
    fn the_servo_respects_its_speed_and_travel() {
        let p = params();
        let mut s = State::at_rest(p.rest_deg);
        for i in 0..50 {
            // A rig that never answers: the servo runs to its tension end at its speed.
            let inp = Input {
                target_n: 30.0,
                new_segment: i == 0,
                t1_n: 0.1,
                t2_n: 0.4,
            };
            let (n, out) = step(&s, &p, &inp);
            assert!(s.servo_deg - n.servo_deg <= p.rate_deg_s * p.dt_s + 1e-4);
            assert!(out.servo_deg >= p.travel_deg);
            // Wound up against the travel, the integral does not grow.
            assert!(n.integral <= s.integral + 1e-6 || s.servo_deg > p.travel_deg);
            s = n;
        }
        assert_eq!(s.servo_deg, p.travel_deg);
        assert_eq!(s.integral, 0.0, "frozen while the servo is at a limit");
        // No target: back toward rest at the servo's speed.
        let inp = Input {
            target_n: 0.0,
            new_segment: true,
            t1_n: 5.0,
            t2_n: 20.0,
        };
        let (n, _) = step(&s, &p, &inp);
        assert_eq!(n.servo_deg, p.travel_deg + p.rate_deg_s * p.dt_s);
    }

    #[test]
    fn a_jump_is_shaped_from_the_measured_tension() {
        let p = Params {
            shape_decay: libm::expf(-0.01 / 0.3),
            ..params()
        };
        let s = State::at_rest(p.rest_deg);
        let inp = Input {
            target_n: 10.0,
            new_segment: true,
            t1_n: 0.1,
            t2_n: 0.4,
        };
        let (_, out) = step(&s, &p, &inp);
        assert!((out.reference_n - 0.4).abs() < 1e-5, "{}", out.reference_n);
    }
}
