//! The plant's state and physics: servo -> lever -> cord -> capstan friction -> fixed sensor,
//! the drive motor that turns the capstan, and the force sensors on the ADC.
//!
//! The plant advances lazily: whoever touches it (an adapter, a probe) first brings it to the
//! present with [`Plant::advance_to`], in steps of at most `max_step_us`. Within a step the
//! drive and the servo move with the loads of the step's start; the tensions are then re-solved
//! only for cords whose inputs changed (servo moved, drive regime changed, or a time-dependent
//! friction law was due for a refresh), so a held step costs a few multiplications per sample.

use crate::config::{CordSetup, PlantConfig};
use crate::rng::Rng;
use capstan_friction::{LoadMemory, Operating};
use firmware::hal::{AdcError, Channel, ADC_MAX_COUNTS};
use firmware::{FaultKind, ServoMap};
use heapless::Vec;

/// Most cords (servos) one plant can carry on its capstan.
pub const MAX_CORDS: usize = 4;
/// Servo command changes remembered per cord (a thesis run makes 14).
pub const MAX_SERVO_EVENTS: usize = 40;
/// Trigger edges remembered per cord.
pub const MAX_TRIGGER_EDGES: usize = 8;
/// Fault injections one plant can carry.
pub const MAX_INJECTIONS: usize = 8;

/// A physical fault the plant can be made to suffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InjectionKind {
    /// The cord parts at the fixed sensor's hook. Both tensions collapse (a free end carries
    /// nothing, and the capstan feeds the loose cord towards the servo).
    CordBreak,
    /// A sensor's connector comes out: its ADC input is pulled to 0 counts.
    SensorUnplugged(Channel),
    /// The cord snags between capstan and fixed sensor: T2 jumps to `FaultConfig::snag_n`.
    OverForce,
    /// The operator presses the start/abort button during the run.
    Abort,
}

impl InjectionKind {
    /// The fault the firmware should raise for it.
    pub const fn fault(self) -> FaultKind {
        match self {
            InjectionKind::CordBreak => FaultKind::CordBreak,
            InjectionKind::SensorUnplugged(_) => FaultKind::SensorRail,
            InjectionKind::OverForce => FaultKind::OverForce,
            InjectionKind::Abort => FaultKind::Abort,
        }
    }

    /// The firmware's name of that fault (`cord_break`, `sensor_unplugged`, `over_force`,
    /// `abort`).
    pub const fn name(self) -> &'static str {
        self.fault().name()
    }

    /// Parse a fault name; `sensor_unplugged` unplugs T2 (the fixed sensor), and
    /// `sensor_unplugged_t1` / `sensor_unplugged_t2` choose.
    pub fn from_name(name: &str) -> Option<InjectionKind> {
        match name {
            "cord_break" => Some(InjectionKind::CordBreak),
            "sensor_unplugged" | "sensor_unplugged_t2" => {
                Some(InjectionKind::SensorUnplugged(Channel::T2))
            }
            "sensor_unplugged_t1" => Some(InjectionKind::SensorUnplugged(Channel::T1)),
            "over_force" => Some(InjectionKind::OverForce),
            "abort" => Some(InjectionKind::Abort),
            _ => None,
        }
    }

    /// The names [`InjectionKind::from_name`] knows.
    pub const NAMES: [&'static str; 4] = ["cord_break", "sensor_unplugged", "over_force", "abort"];
}

/// A fault to inject: what, on which cord, and when (µs after that cord's trigger rose; the
/// logger's timebase, the same as the pairs' `time_s`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Injection {
    /// What happens.
    pub kind: InjectionKind,
    /// Which cord (0-based).
    pub cord: u8,
    /// When, µs after the cord's trigger rising edge.
    pub after_trigger_us: u64,
}

/// What became of an injection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InjectionReport {
    /// The injection.
    pub injection: Injection,
    /// When it took effect, plant µs (`None`: the trigger never rose or time never got there).
    pub at_us: Option<u64>,
    /// First moment after it at which the plant saw that cord's servo commanded to rest and
    /// its amplifier at 0 V, plant µs.
    pub safe_at_us: Option<u64>,
}

impl InjectionReport {
    /// Time from the injection to the safe state, µs.
    pub fn safe_after_us(&self) -> Option<u64> {
        Some(self.safe_at_us? - self.at_us?)
    }
}

/// A servo command as the plant received it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ServoEvent {
    /// When the PWM duty was written, plant µs.
    pub t_us: u64,
    /// The angle that pulse width commands, deg.
    pub angle_deg: f64,
}

/// The true state of one cord.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CordTruth {
    /// True tension at the servo-side sensor, N.
    pub t1_n: f64,
    /// True tension at the fixed sensor, N.
    pub t2_n: f64,
    /// Servo angle now, deg.
    pub angle_deg: f64,
    /// Angle the servo is moving to (the last pulse taken at a frame), deg.
    pub target_deg: f64,
    /// Angle the last PWM write commands, deg.
    pub commanded_deg: f64,
    /// Amplifier control voltage this cord's rig commands, V.
    pub amp_control_v: f64,
    /// The friction law's T2/T1 at this T1 with the capstan slipping.
    pub kinetic_amplification: f64,
    /// The friction law's effective mu now.
    pub mu: f64,
    /// The cord is broken.
    pub broken: bool,
}

/// The true state of the drive.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DriveState {
    /// Motor terminal voltage, V.
    pub drive_v: f64,
    /// Motor shaft speed, rad/s.
    pub motor_rad_s: f64,
    /// Capstan speed, rpm.
    pub capstan_rpm: f64,
    /// Winding current, A.
    pub current_a: f64,
    /// Electrical power into the motor, W.
    pub power_w: f64,
    /// Friction torque the capstan transmits to all cords, N m (at the capstan).
    pub load_nm: f64,
    /// Fraction of the kinetic friction torque the drive delivers: 1 while the capstan turns,
    /// below 1 when it is stalled (then T2 − T1 is what the stalled motor can push).
    pub transmission: f64,
}

#[derive(Clone, Debug)]
struct CordState {
    setup: CordSetup,
    op: Operating,
    time_dependent: bool,
    heats: bool,
    // servo
    pending_pulse_us: f64,
    target_deg: f64,
    angle_deg: f64,
    commanded_deg: f64,
    amp_control_v: f64,
    // tensions
    t1: f64,
    t2: f64,
    a_kin: f64,
    dirty: bool,
    memory: LoadMemory,
    broken: bool,
    snag: bool,
    unplugged: [bool; 2],
    // sensors
    zero: [f64; 2],
    counts_per_n: [f64; 2],
    // pins
    trigger: bool,
    trigger_rise_us: Option<u64>,
    trigger_edges: Vec<(u64, bool), MAX_TRIGGER_EDGES>,
    led: bool,
    press: Option<(u64, u64)>,
    abort: Option<(u64, u64)>,
    servo_events: Vec<ServoEvent, MAX_SERVO_EVENTS>,
    servo_events_dropped: u32,
    last_feed_us: Option<u64>,
    max_feed_gap_us: u64,
    safe_since_us: Option<u64>,
}

/// Why a plant cannot be made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlantError {
    /// No cord, or more than [`MAX_CORDS`].
    CordCount,
    /// A constant is out of its physical range; the name of the field.
    BadConstant(&'static str),
    /// More than [`MAX_INJECTIONS`] injections, or one on a cord that does not exist.
    BadInjection,
}

impl core::fmt::Display for PlantError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            PlantError::CordCount => write!(f, "a plant carries 1 to {MAX_CORDS} cords"),
            PlantError::BadConstant(name) => write!(f, "plant constant `{name}` is out of range"),
            PlantError::BadInjection => write!(
                f,
                "at most {MAX_INJECTIONS} fault injections, each on an existing cord"
            ),
        }
    }
}

/// The simulated rig: one capstan and drive, 1..=[`MAX_CORDS`] cords each with its servo,
/// sensors, trigger, LED and button.
#[derive(Clone, Debug)]
pub struct Plant {
    cfg: PlantConfig,
    // derived constants
    lever_mm_per_deg: f64,
    e_pre_mm: f64,
    inv_hardening: f64,
    radius_m: f64,
    noise_sd_counts: f64,
    motor_damping: f64,
    inv_damping: f64,
    /// Motor torque at standstill minus Coulomb friction at the present drive voltage, N m.
    stall_m: f64,
    /// Kinetic friction load of all cords at the motor shaft, N m (updated with the tensions).
    demand_m: f64,
    decay_dt_us: u32,
    decay: f64,
    // time
    origin_us: u64,
    t_us: u64,
    next_frame_us: u64,
    next_refresh_us: u64,
    any_time_dependent: bool,
    // drive
    drive_v: f64,
    omega: f64,
    transmission: f64,
    load_nm: f64,
    rng: Rng,
    cords: Vec<CordState, MAX_CORDS>,
    injections: Vec<InjectionReport, MAX_INJECTIONS>,
}

fn check(ok: bool, name: &'static str) -> Result<(), PlantError> {
    if ok {
        Ok(())
    } else {
        Err(PlantError::BadConstant(name))
    }
}

/// The servo's pulse for an angle, µs (the firmware's map, in f64).
fn pulse_us(map: &ServoMap, angle_deg: f64) -> f64 {
    let (lo, hi) = (map.pulse_at_min_us as f64, map.pulse_at_max_us as f64);
    lo + (hi - lo) * angle_deg.clamp(0.0, map.max_deg as f64) / map.max_deg as f64
}

/// The angle a pulse commands, deg, within the servo's travel.
fn angle_deg(map: &ServoMap, pulse_us: f64) -> f64 {
    let (lo, hi) = (map.pulse_at_min_us as f64, map.pulse_at_max_us as f64);
    ((pulse_us - lo) / (hi - lo) * map.max_deg as f64).clamp(0.0, map.max_deg as f64)
}

fn positive(x: f64) -> bool {
    x.is_finite() && x > 0.0
}

impl Plant {
    /// A plant at rest (servo at its rest angle, capstan stopped, cords at their preload),
    /// whose clock starts at `Instant::now()`.
    pub fn new(cfg: PlantConfig, cords: &[CordSetup], seed: u64) -> Result<Plant, PlantError> {
        Plant::new_at(cfg, cords, seed, embassy_time::Instant::now().as_micros())
    }

    /// As [`Plant::new`], with the clock starting at `origin_us`.
    pub fn new_at(
        cfg: PlantConfig,
        cords: &[CordSetup],
        seed: u64,
        origin_us: u64,
    ) -> Result<Plant, PlantError> {
        if cords.is_empty() || cords.len() > MAX_CORDS {
            return Err(PlantError::CordCount);
        }
        let (s, c, m, n) = (cfg.servo, cfg.cord, cfg.motor, cfg.sensor);
        check(positive(cfg.capstan_diameter_mm), "capstan_diameter_mm")?;
        check(positive(s.lever_m), "servo.lever_m")?;
        check(positive(s.no_load_deg_per_s), "servo.no_load_deg_per_s")?;
        check(positive(s.stall_torque_nm), "servo.stall_torque_nm")?;
        check(s.frame_us > 0, "servo.frame_us")?;
        check(
            s.rest_deg.is_finite() && (0.0..=180.0).contains(&s.rest_deg),
            "servo.rest_deg",
        )?;
        check(positive(c.preload_n), "cord.preload_n")?;
        check(positive(c.stiffness), "cord.stiffness")?;
        check(positive(c.hardening), "cord.hardening")?;
        check(
            c.far_side_ratio.is_finite() && c.far_side_ratio >= 0.0,
            "cord.far_side_ratio",
        )?;
        check(positive(m.kt_nm_per_a), "motor.kt_nm_per_a")?;
        check(positive(m.resistance_ohm), "motor.resistance_ohm")?;
        check(positive(m.gear_ratio), "motor.gear_ratio")?;
        check(positive(m.rotor_inertia_kg_m2), "motor.rotor_inertia_kg_m2")?;
        check(
            m.viscous_nms.is_finite() && m.viscous_nms >= 0.0,
            "motor.viscous_nms",
        )?;
        check(
            m.coulomb_nm.is_finite() && m.coulomb_nm >= 0.0,
            "motor.coulomb_nm",
        )?;
        check(positive(m.amp_full_scale_v), "motor.amp_full_scale_v")?;
        check(
            m.amp_gain.is_finite() && m.amp_gain >= 0.0,
            "motor.amp_gain",
        )?;
        check(
            m.amp_supply_v.is_finite() && m.amp_supply_v >= 0.0,
            "motor.amp_supply_v",
        )?;
        check(positive(n.n_per_count), "sensor.n_per_count")?;
        check(positive(n.gain), "sensor.gain")?;
        check(n.zero_counts.is_finite(), "sensor.zero_counts")?;
        check(
            n.zero_spread_counts.is_finite() && n.zero_spread_counts >= 0.0,
            "sensor.zero_spread_counts",
        )?;
        check(
            n.noise_sd_n.is_finite() && n.noise_sd_n >= 0.0,
            "sensor.noise_sd_n",
        )?;
        check(cfg.max_step_us > 0, "max_step_us")?;
        check(cfg.refresh_us > 0, "refresh_us")?;
        for cs in cords {
            check(
                cs.wrap_deg.is_finite() && cs.wrap_deg >= 0.0,
                "cord wrap_deg",
            )?;
            check(cs.run >= 1, "cord run")?;
        }

        let mut rng = Rng::new(seed);
        let inv_hardening = 1.0 / c.hardening;
        let e_pre_mm =
            (1.0 + c.far_side_ratio) * libm::pow(c.preload_n / c.stiffness, inv_hardening);
        let rest_pulse = pulse_us(&s.map, s.rest_deg);
        let mut states: Vec<CordState, MAX_CORDS> = Vec::new();
        for cs in cords {
            let op = Operating {
                wrap_rad: cs.wrap_deg.to_radians(),
                diameter_mm: cfg.capstan_diameter_mm,
                drive_v: 0.0,
                run: cs.run as f64,
                time_s: 0.0,
                ..Operating::from_wrap_deg(cs.wrap_deg)
            };
            let law = &cs.model.law;
            let heats = law.heat_per_ns != 0.0;
            let mut zero = [0.0; 2];
            for z in zero.iter_mut() {
                *z = n.zero_counts + n.zero_spread_counts * rng.normal();
            }
            let cpn = n.gain / n.n_per_count;
            let st = CordState {
                setup: *cs,
                op,
                time_dependent: heats || law.mu_change_per_100s != 0.0,
                heats,
                pending_pulse_us: rest_pulse,
                target_deg: s.rest_deg,
                angle_deg: s.rest_deg,
                commanded_deg: s.rest_deg,
                amp_control_v: 0.0,
                t1: c.preload_n,
                t2: c.preload_n,
                a_kin: 1.0,
                dirty: true,
                memory: LoadMemory::default(),
                broken: false,
                snag: false,
                unplugged: [false; 2],
                zero,
                counts_per_n: [cpn, cpn],
                trigger: false,
                trigger_rise_us: None,
                trigger_edges: Vec::new(),
                led: false,
                press: cs
                    .press_at_us
                    .map(|at| (origin_us + at, origin_us + at + cs.press_us)),
                abort: None,
                servo_events: Vec::new(),
                servo_events_dropped: 0,
                last_feed_us: None,
                max_feed_gap_us: 0,
                safe_since_us: Some(origin_us),
            };
            let _ = states.push(st);
        }
        let any_time_dependent = states.iter().any(|c| c.time_dependent);
        let mut plant = Plant {
            cfg,
            lever_mm_per_deg: s.lever_m * 1e3 * core::f64::consts::PI / 180.0,
            e_pre_mm,
            inv_hardening,
            radius_m: cfg.capstan_diameter_mm * 0.5e-3,
            noise_sd_counts: n.noise_sd_n / n.n_per_count,
            motor_damping: m.kt_nm_per_a * m.kt_nm_per_a / m.resistance_ohm + m.viscous_nms,
            inv_damping: 1.0 / (m.kt_nm_per_a * m.kt_nm_per_a / m.resistance_ohm + m.viscous_nms),
            stall_m: -m.coulomb_nm,
            demand_m: 0.0,
            decay_dt_us: 0,
            decay: 1.0,
            origin_us,
            t_us: origin_us,
            next_frame_us: origin_us + s.frame_us as u64,
            next_refresh_us: origin_us,
            any_time_dependent,
            drive_v: 0.0,
            omega: 0.0,
            transmission: 0.0,
            load_nm: 0.0,
            rng,
            cords: states,
            injections: Vec::new(),
        };
        for i in 0..plant.cords.len() {
            plant.solve(i);
        }
        plant.demand_m = plant.kinetic_demand_nm() / m.gear_ratio;
        Ok(plant)
    }

    /// The constants.
    pub fn config(&self) -> &PlantConfig {
        &self.cfg
    }

    /// Number of cords.
    pub fn cord_count(&self) -> usize {
        self.cords.len()
    }

    /// The cord's setup.
    pub fn cord_setup(&self, cord: usize) -> &CordSetup {
        &self.cords[cord].setup
    }

    /// The plant's present, µs (same clock as `embassy_time::Instant`).
    pub fn now_us(&self) -> u64 {
        self.t_us
    }

    /// When the plant was made, µs.
    pub fn origin_us(&self) -> u64 {
        self.origin_us
    }

    /// Schedule a fault. Refused when the table is full or the cord does not exist.
    pub fn inject(&mut self, injection: Injection) -> Result<(), PlantError> {
        if injection.cord as usize >= self.cords.len() {
            return Err(PlantError::BadInjection);
        }
        self.injections
            .push(InjectionReport {
                injection,
                at_us: None,
                safe_at_us: None,
            })
            .map_err(|_| PlantError::BadInjection)
    }

    /// What became of every injection so far.
    pub fn injections(&self) -> &[InjectionReport] {
        &self.injections
    }

    /// Press cord's button from `at_us` (plant µs, absolute) for `for_us`.
    pub fn press(&mut self, cord: usize, at_us: u64, for_us: u64) {
        self.cords[cord].press = Some((at_us, at_us + for_us));
    }

    /// Bring the plant to `now_us` (no-op if it is there already or past it).
    pub fn advance_to(&mut self, now_us: u64) {
        while self.t_us < now_us {
            let dt = (now_us - self.t_us).min(self.cfg.max_step_us as u64);
            self.step(dt as u32);
        }
    }

    fn step(&mut self, dt_us: u32) {
        let t_end = self.t_us + dt_us as u64;
        let frame = self.cfg.servo.frame_us as u64;
        // The servo takes the pulse width present at each frame.
        if t_end >= self.next_frame_us {
            let map = self.cfg.servo.map;
            for c in self.cords.iter_mut() {
                c.target_deg = angle_deg(&map, c.pending_pulse_us);
            }
            while self.next_frame_us <= t_end {
                self.next_frame_us += frame;
            }
        }
        self.activate_injections(t_end);
        self.move_servos(dt_us);
        self.move_drive(dt_us);
        let dt_s = dt_us as f64 * 1e-6;
        for c in self.cords.iter_mut() {
            if c.heats {
                c.memory
                    .advance(dt_s, c.t2 - c.t1, c.setup.model.law.heat_tau_s);
            }
        }
        if self.any_time_dependent && t_end >= self.next_refresh_us {
            for c in self.cords.iter_mut() {
                c.dirty |= c.time_dependent;
            }
            self.next_refresh_us = t_end + self.cfg.refresh_us as u64;
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
            let press_ms = self.cfg.faults.abort_press_ms as u64;
            let c = &mut self.cords[i];
            match rep.injection.kind {
                InjectionKind::CordBreak => c.broken = true,
                InjectionKind::SensorUnplugged(ch) => c.unplugged[ch as usize] = true,
                InjectionKind::OverForce => c.snag = true,
                InjectionKind::Abort => c.abort = Some((at, at + press_ms * 1000)),
            }
            c.dirty = true;
            // Already safe (e.g. injected while idle)?
            if self.is_safe(i) {
                self.injections[k].safe_at_us = Some(at);
            }
        }
    }

    fn move_servos(&mut self, dt_us: u32) {
        let s = self.cfg.servo;
        let dt_s = dt_us as f64 * 1e-6;
        for c in self.cords.iter_mut() {
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
    fn kinetic_demand_nm(&self) -> f64 {
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
    }

    /// Re-solve cord `i`'s tensions for the present lever angle, drive regime and law.
    fn solve(&mut self, i: usize) {
        let cfg = self.cfg.cord;
        let snag_n = self.cfg.faults.snag_n;
        let rest = self.cfg.servo.rest_deg;
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
        let law = c.setup.model.law;
        let op = c.op;
        let kinetic = |t1: f64| -> f64 {
            if t1 <= 0.0 {
                return 1.0;
            }
            let a = law.t2_n(t1, &op) / t1;
            if a.is_finite() {
                a.clamp(1e-6, 1e6)
            } else {
                1e6
            }
        };
        let t1_of = |a_kin: f64| -> f64 {
            let a_eff = 1.0 + s * (a_kin - 1.0);
            let den = 1.0 + cfg.far_side_ratio * libm::pow(a_eff, inv_p);
            cfg.stiffness * libm::pow(e / den, cfg.hardening)
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

    /// Is cord `i`'s rig commanding the safe state (servo at rest, amplifier 0 V)?
    pub fn is_safe(&self, i: usize) -> bool {
        let c = &self.cords[i];
        (c.commanded_deg - self.cfg.servo.rest_deg).abs() < 0.5 && c.amp_control_v == 0.0
    }

    fn note_safe(&mut self, i: usize) {
        let now = self.t_us;
        if !self.is_safe(i) {
            self.cords[i].safe_since_us = None;
            return;
        }
        if self.cords[i].safe_since_us.is_none() {
            self.cords[i].safe_since_us = Some(now);
        }
        for r in self.injections.iter_mut() {
            if r.injection.cord as usize == i && r.at_us.is_some() && r.safe_at_us.is_none() {
                r.safe_at_us = Some(now);
            }
        }
    }

    // ----- what the adapters call (after `advance_to(now)`) -----

    /// The servo PWM of cord `i` is set to `duty` of `max_duty` (50 Hz frame).
    pub fn set_servo_duty(&mut self, i: usize, duty: u16, max_duty: u16) {
        let frame = self.cfg.servo.frame_us as f64;
        let pulse = if max_duty == 0 {
            0.0
        } else {
            duty as f64 / max_duty as f64 * frame
        };
        let angle = angle_deg(&self.cfg.servo.map, pulse);
        let now = self.t_us;
        let c = &mut self.cords[i];
        c.pending_pulse_us = pulse;
        if angle != c.commanded_deg || c.servo_events.is_empty() {
            c.commanded_deg = angle;
            let ev = ServoEvent {
                t_us: now,
                angle_deg: angle,
            };
            if c.servo_events.push(ev).is_err() {
                c.servo_events_dropped += 1;
            }
        }
        self.note_safe(i);
    }

    /// The amplifier control PWM of cord `i`'s rig is set to `duty` of `max_duty`. The power
    /// amplifier follows the highest control voltage of all rigs (their control lines are
    /// diode-OR'd: any running rig keeps the capstan turning).
    pub fn set_amp_duty(&mut self, i: usize, duty: u16, max_duty: u16) {
        let m = self.cfg.motor;
        let v = if max_duty == 0 {
            0.0
        } else {
            duty as f64 / max_duty as f64 * m.amp_full_scale_v
        };
        self.cords[i].amp_control_v = v;
        let control = self
            .cords
            .iter()
            .map(|c| c.amp_control_v)
            .fold(0.0, f64::max);
        let drive = (control * m.amp_gain).min(m.amp_supply_v);
        if drive != self.drive_v {
            self.drive_v = drive;
            self.stall_m = m.kt_nm_per_a * drive / m.resistance_ohm - m.coulomb_nm;
            for c in self.cords.iter_mut() {
                c.dirty = true;
            }
        }
        self.note_safe(i);
    }

    /// Cord `i`'s trigger line is driven `high` or low.
    pub fn set_trigger(&mut self, i: usize, high: bool) {
        let now = self.t_us;
        let c = &mut self.cords[i];
        if high == c.trigger {
            return;
        }
        c.trigger = high;
        if high && c.trigger_rise_us.is_none() {
            c.trigger_rise_us = Some(now);
        }
        let _ = c.trigger_edges.push((now, high));
    }

    /// Cord `i`'s LED is driven.
    pub fn set_led(&mut self, i: usize, on: bool) {
        self.cords[i].led = on;
    }

    /// Is cord `i`'s button held down now?
    pub fn button_pressed(&self, i: usize) -> bool {
        let c = &self.cords[i];
        let t = self.t_us;
        let inside = |w: Option<(u64, u64)>| w.is_some_and(|(a, b)| t >= a && t < b);
        inside(c.press) || inside(c.abort)
    }

    /// Convert one force channel of cord `i` now.
    pub fn read_counts(&mut self, i: usize, ch: Channel) -> Result<u16, AdcError> {
        let k = ch as usize;
        let drive_on = self.drive_v > 0.0;
        let c = &self.cords[i];
        if c.unplugged[k] {
            return Ok(0);
        }
        let art = c.setup.model.sensors;
        // The catalogue artefacts ride on the drive (see the crate docs): the tare, done with
        // the capstan stopped, neither removes the offsets nor sees the gain.
        let reading = match ch {
            Channel::T1 if drive_on => c.t1 + art.t1_offset_n,
            Channel::T2 if drive_on => art.t2_gain * c.t2 + art.t2_offset_n,
            Channel::T1 => c.t1,
            Channel::T2 => c.t2,
        };
        let mut counts = c.zero[k] + reading * c.counts_per_n[k];
        if self.noise_sd_counts > 0.0 {
            counts += self.noise_sd_counts * self.rng.normal();
        }
        // Round half up and clamp to the ADC's range (`as` truncates: floor, as x ≥ 1).
        let x = counts + 0.5;
        Ok(if x < 1.0 {
            0
        } else if x >= ADC_MAX_COUNTS as f64 {
            ADC_MAX_COUNTS
        } else {
            x as u16
        })
    }

    /// Cord `i`'s watchdog is fed.
    pub fn feed_watchdog(&mut self, i: usize) {
        let now = self.t_us;
        let c = &mut self.cords[i];
        if let Some(last) = c.last_feed_us {
            c.max_feed_gap_us = c.max_feed_gap_us.max(now - last);
        }
        c.last_feed_us = Some(now);
    }

    // ----- observation (tests, probes, reports) -----

    /// The true state of cord `i`.
    pub fn truth(&self, i: usize) -> CordTruth {
        let c = &self.cords[i];
        CordTruth {
            t1_n: c.t1,
            t2_n: c.t2,
            angle_deg: c.angle_deg,
            target_deg: c.target_deg,
            commanded_deg: c.commanded_deg,
            amp_control_v: c.amp_control_v,
            kinetic_amplification: c.a_kin,
            mu: c.setup.model.law.effective_mu(&c.op),
            broken: c.broken,
        }
    }

    /// The true state of the drive.
    pub fn drive(&self) -> DriveState {
        let m = self.cfg.motor;
        let current = (self.drive_v - m.kt_nm_per_a * self.omega) / m.resistance_ohm;
        DriveState {
            drive_v: self.drive_v,
            motor_rad_s: self.omega,
            capstan_rpm: self.omega / m.gear_ratio * 60.0 / (2.0 * core::f64::consts::PI),
            current_a: current,
            power_w: self.drive_v * current,
            load_nm: self.load_nm,
            transmission: self.transmission,
        }
    }

    /// Servo commands cord `i` received (time, angle), oldest first, and how many did not fit.
    pub fn servo_events(&self, i: usize) -> (&[ServoEvent], u32) {
        let c = &self.cords[i];
        (&c.servo_events, c.servo_events_dropped)
    }

    /// Trigger edges of cord `i` (time, level).
    pub fn trigger_edges(&self, i: usize) -> &[(u64, bool)] {
        &self.cords[i].trigger_edges
    }

    /// First trigger rising edge of cord `i`, plant µs.
    pub fn trigger_rise_us(&self, i: usize) -> Option<u64> {
        self.cords[i].trigger_rise_us
    }

    /// Cord `i`'s LED.
    pub fn led(&self, i: usize) -> bool {
        self.cords[i].led
    }

    /// Since when cord `i`'s rig has been commanding the safe state (servo at rest, amplifier
    /// 0 V), plant µs; `None` while it is not.
    pub fn safe_since_us(&self, i: usize) -> Option<u64> {
        self.cords[i].safe_since_us
    }

    /// Longest gap between two watchdog feeds of cord `i`, µs.
    pub fn max_feed_gap_us(&self, i: usize) -> u64 {
        self.cords[i].max_feed_gap_us
    }

    /// The zero (counts at 0 N) this plant drew for cord `i`'s two sensors.
    pub fn sensor_zero_counts(&self, i: usize) -> [f64; 2] {
        self.cords[i].zero
    }
}
