//! The plant's state: servo -> lever -> cord -> capstan friction -> fixed sensor, the drive
//! motor that turns the capstan, and the force sensors on the ADC.
//!
//! * `build`: the constants checked and the plant made at rest;
//! * `physics`: advancing time — servos, drive, injections, and the tensions re-solved;
//! * `io`: what the HAL adapters call (PWM duties, pins, the ADC, the watchdog);
//! * `observe`: the true state, for tests, probes and reports.
//!
//! The plant advances lazily: whoever touches it (an adapter, a probe) first brings it to the
//! present with [`Plant::advance_to`], in steps of at most `max_step_us`. Within a step the
//! drive and the servo move with the loads of the step's start; the tensions are then re-solved
//! only for cords whose inputs changed (servo moved, drive regime changed, or a time-dependent
//! friction law was due for a refresh), so a held step costs a few multiplications per sample.

mod build;
mod io;
mod observe;
mod physics;

pub use build::PlantError;
pub use observe::{CordTruth, DriveState, ServoEvent};

use crate::config::{CordSetup, PlantConfig};
use crate::disturb::DisturbState;
use crate::injection::{Injection, InjectionReport};
use crate::rng::Rng;
use capstan_physics::{LoadMemory, Operating};
use capstan_rig::hal::Channel;
use heapless::Vec;

/// Most cords (servos) one plant can carry on its capstan.
pub const MAX_CORDS: usize = 4;
/// Servo command changes remembered per cord (a thesis run makes 14).
pub const MAX_SERVO_EVENTS: usize = 40;
/// Trigger edges remembered per cord.
pub const MAX_TRIGGER_EDGES: usize = 8;
/// Fault injections one plant can carry.
pub const MAX_INJECTIONS: usize = 8;

/// One cord's state: its servo, tensions, sensors, pins and records.
#[derive(Clone, Debug)]
struct CordState {
    setup: CordSetup,
    op: Operating,
    time_dependent: bool,
    heats: bool,
    // servo (horn angles, deg; pulses, µs; 0 = no pulse)
    pending_pulse_us: f64,
    target_deg: f64,
    angle_deg: f64,
    commanded_pulse_us: f64,
    commanded_deg: f64,
    // amplifier control: the PWM's mean (commanded) and after the RC filter, V
    amp_control_v: f64,
    amp_filtered_v: f64,
    // tensions
    t1: f64,
    t2: f64,
    a_kin: f64,
    dirty: bool,
    memory: LoadMemory,
    /// Wander of mu and zero errors (None on a quiet plant).
    disturb: Option<DisturbState>,
    /// The servo last moved to release the cord (tension falling).
    falling: bool,
    /// The servo took a pulse at its last frame (false: unpowered, back-driven by the cord).
    powered: bool,
    broken: bool,
    snag: bool,
    unplugged: [bool; 2],
    /// A channel's reading held (the pin's voltage on its 100 nF), counts at the ADC.
    frozen: [Option<f64>; 2],
    /// The servo no longer follows its pulses.
    servo_stalled: bool,
    /// The amplifier's PWM pin is not driven (a reset released it): its filter discharges
    /// through the pull-down ([`crate::MotorConfig::amp_filter_released_tau_s`]).
    amp_released: bool,
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

/// The simulated rig: one capstan and drive, 1..=[`MAX_CORDS`] cords each with its servo,
/// sensors, trigger, LED and button.
#[derive(Clone, Debug)]
pub struct Plant {
    cfg: PlantConfig,
    // derived constants
    /// Horn angle at the rest pulse, where the cord carries its preload, deg.
    rest_deg: f64,
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
    rc_decay_dt_us: u32,
    rc_decay: f64,
    // time
    origin_us: u64,
    t_us: u64,
    next_frame_us: u64,
    next_refresh_us: u64,
    next_wander_us: u64,
    any_time_dependent: bool,
    /// Until when (the next frame, wander or refresh that can change anything, µs) a step only
    /// moves the drive: the servos are at their targets, the amplifier filters at their
    /// inputs, no injection is to come and nothing heats (0: not settled; a new servo or
    /// amplifier duty or injection clears it).
    settled_until_us: u64,
    // drive
    drive_v: f64,
    omega: f64,
    transmission: f64,
    load_nm: f64,
    /// The last drive step of this length (µs) changed nothing, and neither the load nor the
    /// drive voltage has changed since (0: not so).
    drive_still_dt_us: u32,
    rng: Rng,
    cords: Vec<CordState, MAX_CORDS>,
    injections: Vec<InjectionReport, MAX_INJECTIONS>,
}

impl Plant {
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
        self.settled_until_us = 0;
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

    /// Hang `newtons` more on cord's sensor `channel` (negative: take it off): the sensor reads
    /// it on top of the cord's tension, as a known weight hung from it at the bench does. (It
    /// shifts the sensor's output at no cord tension: no state of its own, so the plant stays
    /// small enough for the QEMU build's RAM.)
    pub fn hang(&mut self, cord: usize, channel: Channel, newtons: f64) {
        let c = &mut self.cords[cord];
        let k = channel as usize;
        c.zero[k] += newtons * c.counts_per_n[k];
    }

    /// Mount cord's sensor `channel` the wrong way round: a tension lowers its reading (the
    /// same sensitivity, the other sign), as a sensor fitted or wired reversed does.
    pub fn reverse_sensor(&mut self, cord: usize, channel: Channel) {
        let c = &mut self.cords[cord];
        let k = channel as usize;
        c.counts_per_n[k] = -c.counts_per_n[k];
    }

    /// Scale cord's sensor `channel`'s sensitivity by `factor` (counts per newton): a sensor
    /// whose true sensitivity differs from its nominal one, as every real one does a little.
    /// Apply it before hanging anything (a weight already hung keeps its old reading).
    pub fn scale_sensor(&mut self, cord: usize, channel: Channel, factor: f64) {
        let c = &mut self.cords[cord];
        c.counts_per_n[channel as usize] *= factor;
    }

    /// Bring the plant to `now_us` (no-op if it is there already or past it).
    #[inline]
    pub fn advance_to(&mut self, now_us: u64) {
        // Every HAL call comes here, and all but the first of a sample find the plant there.
        if self.t_us < now_us {
            // The first usually finds one step due in which only time passes (what `step` does
            // then, without the call).
            let dt_us = now_us - self.t_us;
            if dt_us <= self.cfg.max_step_us as u64 && self.only_time_passes(now_us, dt_us as u32) {
                debug_assert!(self.cords.iter().all(|c| !c.dirty));
                self.t_us = now_us;
            } else {
                self.advance_from_past(now_us);
            }
        }
    }

    fn advance_from_past(&mut self, now_us: u64) {
        while self.t_us < now_us {
            let dt = (now_us - self.t_us).min(self.cfg.max_step_us as u64);
            self.step(dt as u32);
        }
    }

    /// Is cord `i`'s rig commanding the safe state: the servo's pulse at rest (within the
    /// servo's dead band of [`crate::ServoConfig::rest_pulse_us`]) and amplifier duty 0?
    pub fn is_safe(&self, i: usize) -> bool {
        let c = &self.cords[i];
        let s = &self.cfg.servo;
        (c.commanded_pulse_us - s.rest_pulse_us).abs() <= s.characteristic.dead_band_us
            && c.amp_control_v == 0.0
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
}
