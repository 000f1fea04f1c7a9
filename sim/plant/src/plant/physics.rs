//! Advancing time: the servo takes the pulse at each PWM frame and slews against T1, the drive
//! follows its load exactly over a step, injections take effect, and the tensions of every
//! cord whose inputs changed are re-solved through the shared friction law.

use super::Plant;
use crate::injection::InjectionKind;
use capstan_physics::{math, FrictionLaw};

impl Plant {
    /// A step of `dt_us` to `t_end` would only move time on: settled (see
    /// `settled_until_us`), no frame, wander or refresh due, and the drive still (see
    /// `drive_still_dt_us`). No cord is then due a re-solve either: every step ends with none,
    /// and between steps only a new amplifier duty can ask for one, and it ends the settled
    /// spell.
    #[inline]
    pub(super) fn only_time_passes(&self, t_end: u64, dt_us: u32) -> bool {
        t_end < self.settled_until_us && self.drive_still_dt_us == dt_us
    }

    pub(super) fn step(&mut self, dt_us: u32) {
        let t_end = self.t_us + dt_us as u64;
        // Most of a run's 1 ms steps.
        if self.only_time_passes(t_end, dt_us) {
            debug_assert!(self.cords.iter().all(|c| !c.dirty));
            self.t_us = t_end;
            return;
        }
        // Settled (servos at their targets, filters at their inputs, no injection to come, no
        // heating) and no frame, wander or refresh due: only the drive may still move, and the
        // rest of a step would change nothing.
        let settled = t_end < self.settled_until_us;
        if !settled {
            self.move_inputs(t_end, dt_us);
        }
        // A drive step that changed nothing changes nothing the next time either, while the
        // load, the drive voltage and the step length stay (the drive settles to within an ulp
        // of its steady state, and stays there, a few ms after every change).
        if self.drive_still_dt_us != dt_us {
            self.move_drive(dt_us);
        }
        if !settled {
            self.heat_and_wander(t_end, dt_us);
        }
        self.t_us = t_end;
        let mut solved = false;
        for i in 0..self.cords.len() {
            if self.cords[i].dirty {
                self.solve(i);
                solved = true;
            }
        }
        if solved {
            self.demand_m = self.kinetic_demand_nm() / self.cfg.motor.gear_ratio;
            self.drive_still_dt_us = 0;
        }
        if !settled {
            let s = &self.cfg.servo;
            let still = self.injections.iter().all(|r| r.at_us.is_some())
                && self.cords.iter().all(|c| {
                    !c.heats
                        && c.target_deg == c.angle_deg
                        && c.amp_filtered_v == c.amp_control_v
                        && backdrive_deg_per_s(s, c) == 0.0
                });
            self.settled_until_us = if still { self.next_event_us() } else { 0 };
        }
    }

    /// Frames, injections, the amplifier's filter and the servos. (Out of line: the settled
    /// steps, most of them, then carry none of its registers and constants.)
    #[inline(never)]
    fn move_inputs(&mut self, t_end: u64, dt_us: u32) {
        self.take_frames(t_end);
        self.activate_injections(t_end);
        self.filter_amp(dt_us);
        self.move_servos(dt_us);
    }

    /// The next frame, wander or refresh that can change anything, µs (`u64::MAX`: none).
    ///
    /// Called with the plant still (see `step`). A frame then changes nothing unless some
    /// servo's pulse now gives another target than the one it holds: its only effects are the
    /// targets (and `falling`, only when a target changes) and moving `next_frame_us` on. A
    /// wander step changes nothing on a plant without wander (no cord has a `disturb`: a quiet
    /// plant). Such events are skipped over, settled, and their bookkeeping left behind: the
    /// next unsettled step's `take_frames` and `heat_and_wander` move `next_frame_us` and
    /// `next_wander_us` on to the same grid points as the skipped events would have, with the
    /// targets they would have left (the same pulses), and `set_servo_duty`, which can give a
    /// frame something to do, ends the settled spell and first moves `next_frame_us` on past
    /// the present (so the new pulse still waits for the next frame on the grid).
    fn next_event_us(&self) -> u64 {
        let servo = self.cfg.servo;
        let mut next = u64::MAX;
        // (A frame that takes a servo's power away, or gives it back, changes it too.)
        if self.cords.iter().any(|c| {
            !c.servo_stalled
                && (frame_target_deg(&servo, c) != c.target_deg
                    || c.powered != (c.pending_pulse_us > 0.0))
        }) {
            next = self.next_frame_us;
        }
        if self.cords.iter().any(|c| c.disturb.is_some()) {
            next = next.min(self.next_wander_us);
        }
        if self.any_time_dependent {
            next = next.min(self.next_refresh_us);
        }
        next
    }

    /// Skip `next_frame_us` past the present (the frames skipped while settled changed
    /// nothing: see `next_event_us`).
    pub(super) fn catch_up_frames(&mut self) {
        self.frames_past(self.t_us);
    }

    /// Move `next_frame_us` to the first frame of its grid after `t_us` (in one step however
    /// long the plant was settled; `frame_us` > 0 is checked when the plant is built).
    fn frames_past(&mut self, t_us: u64) {
        if self.next_frame_us <= t_us {
            let frame = self.cfg.servo.frame_us as u64;
            self.next_frame_us += ((t_us - self.next_frame_us) / frame + 1) * frame;
        }
    }

    /// The servo takes the pulse width present at each frame (none: it stops where it is).
    fn take_frames(&mut self, t_end: u64) {
        if t_end < self.next_frame_us {
            return;
        }
        let servo = self.cfg.servo;
        for c in self.cords.iter_mut() {
            if c.servo_stalled {
                continue;
            }
            let target = frame_target_deg(&servo, c);
            // Releasing (angle rising) lets the tension fall; pulling raises it.
            if target != c.target_deg {
                c.falling = target > c.target_deg;
            }
            c.target_deg = target;
            c.powered = c.pending_pulse_us > 0.0;
        }
        self.frames_past(t_end);
    }

    /// The contact's load memory, the wander of mu, and the refresh of time-dependent laws.
    #[inline(never)]
    fn heat_and_wander(&mut self, t_end: u64, dt_us: u32) {
        let dt_s = dt_us as f64 * 1e-6;
        for c in self.cords.iter_mut() {
            if c.heats {
                c.memory
                    .advance(dt_s, c.t2 - c.t1, c.setup.model.law.heat_tau_s);
            }
        }
        if t_end >= self.next_wander_us {
            let d = self.cfg.disturbances;
            let step = crate::disturb::WANDER_STEP_US;
            while self.next_wander_us <= t_end {
                for c in self.cords.iter_mut() {
                    if let Some(s) = c.disturb.as_mut() {
                        s.advance(&d, step as f64 * 1e-6);
                    }
                }
                self.next_wander_us += step;
            }
        }
        if self.any_time_dependent && t_end >= self.next_refresh_us {
            for c in self.cords.iter_mut() {
                c.dirty |= c.time_dependent;
            }
            self.next_refresh_us = t_end + self.cfg.refresh_us as u64;
        }
    }

    fn activate_injections(&mut self, t_end: u64) {
        for k in 0..self.injections.len() {
            let rep = self.injections[k];
            if rep.at_us.is_some() {
                continue;
            }
            let i = rep.injection.cord as usize;
            let Some(rise) = self.cords[i].trigger_rise_us else {
                continue;
            };
            let at = rise + rep.injection.after_trigger_us;
            if at > t_end {
                continue;
            }
            self.injections[k].at_us = Some(at);
            self.apply_injection(i, rep.injection.kind, at);
            // Already safe (e.g. injected while idle)?
            if self.is_safe(i) {
                self.injections[k].safe_at_us = Some(at);
            }
        }
    }

    /// What `kind` does to cord `i`, from `at_us`.
    fn apply_injection(&mut self, i: usize, kind: InjectionKind, at_us: u64) {
        let press_ms = self.cfg.faults.abort_press_ms as u64;
        let held = match kind {
            InjectionKind::Frozen(ch) => Some((ch, self.held_counts(i, ch))),
            _ => None,
        };
        let c = &mut self.cords[i];
        match kind {
            InjectionKind::CordBreak => c.broken = true,
            InjectionKind::SensorUnplugged(ch) => c.unplugged[ch as usize] = true,
            InjectionKind::OverForce => c.snag = true,
            InjectionKind::Abort => c.abort = Some((at_us, at_us + press_ms * 1000)),
            InjectionKind::Frozen(_) => {
                if let Some((ch, v)) = held {
                    c.frozen[ch as usize] = Some(v);
                }
            }
            InjectionKind::ServoStall => {
                c.servo_stalled = true;
                c.target_deg = c.angle_deg;
            }
        }
        c.dirty = true;
    }

    /// `kind` strikes cord `i` now, whatever its trigger did (a bench's person, a test): the
    /// same as an injection that comes due now, but not in [`Plant::injections`].
    pub fn strike(&mut self, i: usize, kind: InjectionKind) {
        self.settled_until_us = 0;
        let now = self.t_us;
        self.apply_injection(i, kind, now);
    }

    /// The RC filter in front of each rig's amplifier input follows its PWM's mean, exactly
    /// for a duty held over the step; within 1 µV it is there. A released pin (a reset) lets
    /// it fall with the slower time constant of the resistor and the pull-down.
    fn filter_amp(&mut self, dt_us: u32) {
        let m = self.cfg.motor;
        if self
            .cords
            .iter()
            .all(|c| c.amp_filtered_v == c.amp_control_v)
        {
            return;
        }
        let tau_s = m.amp_filter_tau_s;
        if tau_s > 0.0 && self.rc_decay_dt_us != dt_us {
            self.rc_decay_dt_us = dt_us;
            self.rc_decay = libm::exp(-(dt_us as f64) * 1e-6 / tau_s);
        }
        let released_tau_s = m.amp_filter_released_tau_s;
        let released_decay = if released_tau_s > 0.0 {
            libm::exp(-(dt_us as f64) * 1e-6 / released_tau_s)
        } else {
            0.0
        };
        for c in self.cords.iter_mut() {
            let target = c.amp_control_v;
            let (tau, decay) = if c.amp_released {
                (released_tau_s, released_decay)
            } else {
                (tau_s, self.rc_decay)
            };
            let v = target + (c.amp_filtered_v - target) * decay;
            c.amp_filtered_v = if tau <= 0.0 || (v - target).abs() < 1e-6 {
                target
            } else {
                v
            };
        }
        self.update_drive();
    }

    fn move_servos(&mut self, dt_us: u32) {
        let s = self.cfg.servo;
        let dt_s = dt_us as f64 * 1e-6;
        for c in self.cords.iter_mut() {
            // Unpowered: the cord turns the horn toward release (angle rising) while its torque
            // on the lever beats the gear train's hold; the servo's own target follows it.
            let backdrive = backdrive_deg_per_s(&s, c);
            if backdrive > 0.0 {
                c.angle_deg += backdrive * dt_s;
                c.target_deg = c.angle_deg;
                c.falling = true;
                c.dirty = true;
                continue;
            }
            let gap = c.target_deg - c.angle_deg;
            if gap == 0.0 {
                continue;
            }
            // Pulling (angle falling) works against T1 on the lever; releasing does not.
            let rate = if gap < 0.0 {
                let load = c.t1.max(0.0) * s.lever_m / s.stall_torque_nm;
                s.no_load_deg_per_s * (1.0 - load).max(0.0)
            } else {
                s.no_load_deg_per_s
            };
            let travel = rate * dt_s;
            if travel <= 0.0 {
                continue;
            }
            c.angle_deg = if gap.abs() <= travel {
                c.target_deg
            } else {
                c.angle_deg + travel.copysign(gap)
            };
            c.dirty = true;
        }
    }

    /// Kinetic friction load the cords ask of the capstan, N m at the capstan.
    pub(super) fn kinetic_demand_nm(&self) -> f64 {
        let snag_n = self.cfg.faults.snag_n;
        let mut sum = 0.0;
        for c in self.cords.iter() {
            if c.broken {
                continue;
            }
            let t2 = if c.snag { snag_n } else { c.t1 * c.a_kin };
            sum += (t2 - c.t1).max(0.0);
        }
        sum * self.radius_m
    }

    fn move_drive(&mut self, dt_us: u32) {
        let before = self.drive_bits();
        let m = self.cfg.motor;
        let (demand_m, stall_m) = (self.demand_m, self.stall_m);
        if self.omega > 0.0 || stall_m > demand_m {
            // Exact for a load held over the step: ω → ω_ss with the mechanical time constant.
            let w_ss = (stall_m - demand_m) * self.inv_damping;
            if self.omega != w_ss {
                if self.decay_dt_us != dt_us {
                    self.decay_dt_us = dt_us;
                    self.decay = libm::exp(
                        -self.motor_damping * dt_us as f64 * 1e-6 / m.rotor_inertia_kg_m2,
                    );
                }
                self.omega = w_ss + (self.omega - w_ss) * self.decay;
                if self.omega <= 0.0 {
                    self.omega = 0.0;
                }
            }
        }
        let transmission = if self.omega > 0.0 {
            1.0
        } else if stall_m <= 0.0 {
            0.0
        } else if demand_m <= stall_m {
            1.0
        } else {
            stall_m / demand_m
        };
        if transmission != self.transmission {
            self.transmission = transmission;
            for c in self.cords.iter_mut() {
                c.dirty = true;
            }
        }
        self.load_nm = if self.omega > 0.0 || demand_m <= stall_m.max(0.0) {
            demand_m * m.gear_ratio
        } else {
            stall_m.max(0.0) * m.gear_ratio
        };
        self.drive_still_dt_us = if self.drive_bits() == before {
            dt_us
        } else {
            0
        };
    }

    /// What a drive step may change, bit for bit.
    fn drive_bits(&self) -> [u64; 3] {
        [self.omega, self.transmission, self.load_nm].map(f64::to_bits)
    }

    /// Re-solve cord `i`'s tensions for the present lever angle, drive regime and law.
    pub(super) fn solve(&mut self, i: usize) {
        let cfg = self.cfg.cord;
        let snag_n = self.cfg.faults.snag_n;
        let rest = self.rest_deg;
        let lever = self.lever_mm_per_deg;
        let e_pre = self.e_pre_mm;
        let inv_p = self.inv_hardening;
        let s = self.transmission;
        let t_us = self.t_us;
        let drive_v = self.drive_v;
        let c = &mut self.cords[i];
        c.dirty = false;
        c.op.drive_v = drive_v;
        c.op.time_s = match c.trigger_rise_us {
            Some(r) if t_us > r => (t_us - r) as f64 * 1e-6,
            _ => 0.0,
        };
        c.op.load_memory_ns = c.memory.h_ns;
        if c.broken {
            c.t1 = 0.0;
            c.t2 = 0.0;
            return;
        }
        let e = e_pre + lever * (rest - c.angle_deg);
        if e <= 0.0 {
            c.t1 = 0.0;
            c.t2 = if c.snag { snag_n } else { 0.0 };
            return;
        }
        let mut law = c.setup.model.law;
        law.mu *= c.disturb.as_ref().map_or(1.0, |d| libm::exp(d.ln_mu));
        let op = c.op;
        let (unmodelled, falling) = (c.setup.unmodelled, c.falling);
        let kinetic = |t1: f64| -> f64 {
            if t1 <= 0.0 {
                return 1.0;
            }
            let law = FrictionLaw {
                mu: law.mu
                    * unmodelled.mu_factor(t1, falling)
                    * unmodelled.settling_factor(op.time_s),
                ..law
            };
            let a = law.t2_n(t1, &op) / t1;
            if a.is_finite() {
                a.clamp(1e-6, 1e6)
            } else {
                1e6
            }
        };
        let t1_of = |a_kin: f64| -> f64 {
            let a_eff = 1.0 + s * (a_kin - 1.0);
            // The friction crate's pow: the platform's on the host (this is the simulator's
            // hottest call), libm's on WebAssembly and bare metal.
            let den = 1.0 + cfg.far_side_ratio * math::pow(a_eff, inv_p);
            cfg.stiffness * math::pow(e / den, cfg.hardening)
        };
        // Fixed point a -> T1(a) -> a(T1); contracting for the laws of the catalogue, damped
        // after a few rounds in case a law is steep at low tension.
        let mut a = c.a_kin.max(1e-6);
        let mut t1 = t1_of(a);
        for round in 0..60 {
            let a_new = kinetic(t1);
            let converged = (a_new - a).abs() <= 1e-13 * a;
            a = if round < 8 { a_new } else { 0.5 * (a + a_new) };
            t1 = t1_of(a);
            if converged {
                break;
            }
        }
        c.a_kin = a;
        c.t1 = t1;
        c.t2 = if c.snag {
            snag_n
        } else {
            t1 * (1.0 + s * (a - 1.0))
        };
    }
}

/// How fast the cord back-drives cord `c`'s unpowered horn, deg/s (0: powered, or the gear
/// train holds it).
fn backdrive_deg_per_s(s: &crate::ServoConfig, c: &super::CordState) -> f64 {
    if c.powered {
        return 0.0;
    }
    let excess_nm = c.t1 * s.lever_m - s.unpowered_hold_nm;
    if excess_nm <= 0.0 {
        return 0.0;
    }
    (excess_nm * s.backdrive_deg_per_s_per_nm).min(s.no_load_deg_per_s)
}

/// The target a frame gives cord `c`'s servo: its pulse's angle, or short of it by the dead
/// band (`crate::servo`); no pulse: it stops where it is, unless the cord back-drives it.
fn frame_target_deg(s: &crate::ServoConfig, c: &super::CordState) -> f64 {
    if c.pending_pulse_us > 0.0 {
        s.dynamics
            .target_deg(&s.characteristic, c.pending_pulse_us, c.angle_deg)
    } else {
        c.angle_deg
    }
}
