//! A force run's samples: both forces averaged over each control period, the target of the
//! segment being held, and the control law once a period. What `rig/run.rs` calls in force
//! mode, with the step the run holds and the time into it.

use super::control::{self, Input, Params, State, CONTROL_HZ};
use crate::protocol::Protocol;
use crate::safety::SafetyLimits;

/// The controller never asks for more than this fraction of the over-force limit.
pub const DEMAND_OF_LIMIT: f32 = 0.9;

/// One force run's controller and its averaging.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ForceRun {
    params: Params,
    state: State,
    sum: [f32; 2],
    count: u32,
    /// Samples per control period, and how many are left of this one.
    every: u32,
    left: u32,
    /// The segment the last period was in.
    segment: u32,
    /// The target now (for the log), N.
    target_n: f32,
}

impl ForceRun {
    /// A run of `p` (in force mode) under `limits`, the servo at rest.
    pub fn new(p: &Protocol, limits: &SafetyLimits) -> ForceRun {
        let every = (p.sample_hz / CONTROL_HZ).max(1);
        let dt_s = every as f32 / p.sample_hz as f32;
        let f = &p.force;
        let shape_decay = if f.shape_ms == 0 {
            0.0
        } else {
            libm::expf(-dt_s * 1000.0 / f.shape_ms as f32)
        };
        let params = Params {
            law: f.law,
            beta_rad: p.wrap_deg * (core::f32::consts::PI / 180.0),
            kp: f.kp,
            ki: f.ki,
            t1_gain: f.t1_gain,
            rate_deg_s: f.rate_deg_s,
            shape_decay,
            rest_deg: p.rest_deg,
            travel_deg: p.final_deg,
            max_demand_n: DEMAND_OF_LIMIT * limits.over_force_n,
            dt_s,
        };
        ForceRun {
            params,
            state: State::at_rest(p.rest_deg),
            sum: [0.0; 2],
            count: 0,
            every,
            left: every,
            segment: 0,
            target_n: 0.0,
        }
    }

    /// One sample `in_ms` into segment `segment` with the forces read (NaN where a conversion
    /// failed): the servo command.
    pub fn sample(&mut self, p: &Protocol, segment: u32, in_ms: u32, force_n: [f32; 2]) -> f32 {
        self.target_n = p.force.target_n(segment, in_ms, p.dwell_ms);
        if force_n[0].is_finite() && force_n[1].is_finite() {
            self.sum[0] += force_n[0];
            self.sum[1] += force_n[1];
            self.count += 1;
        }
        self.left -= 1;
        if self.left > 0 {
            return self.state.servo_deg;
        }
        self.left = self.every;
        let n = self.count as f32;
        let inp = Input {
            target_n: self.target_n,
            new_segment: segment != self.segment,
            t1_n: if self.count > 0 {
                self.sum[0] / n
            } else {
                f32::NAN
            },
            t2_n: if self.count > 0 {
                self.sum[1] / n
            } else {
                f32::NAN
            },
        };
        self.segment = segment;
        (self.sum, self.count) = ([0.0; 2], 0);
        self.state = control::step(&self.state, &self.params, &inp).0;
        self.state.servo_deg
    }

    /// The T2 target of the last sample (0: none), N.
    pub fn target_n(&self) -> f32 {
        self.target_n
    }
}
