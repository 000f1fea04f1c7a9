//! Making a plant: every constant checked against its physical range, then the plant at rest
//! (servo at its rest angle, capstan stopped, cords at their preload, sensor zeros drawn).

use super::{CordState, Plant, MAX_CORDS, MAX_INJECTIONS};
use crate::config::{CordConfig, CordSetup, MotorConfig, PlantConfig, SensorConfig, ServoConfig};
use crate::disturb::{DisturbState, Disturbances};
use crate::rng::{derive_seed, Rng};
use capstan_physics::{LoadMemory, Operating};
use heapless::Vec;

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

fn check(ok: bool, name: &'static str) -> Result<(), PlantError> {
    if ok {
        Ok(())
    } else {
        Err(PlantError::BadConstant(name))
    }
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
        check_constants(&cfg)?;
        cords.iter().try_for_each(check_cord)?;

        let (s, c, m, n) = (cfg.servo, cfg.cord, cfg.motor, cfg.sensor);
        let mut rng = Rng::new(seed);
        let inv_hardening = 1.0 / c.hardening;
        let e_pre_mm =
            (1.0 + c.far_side_ratio) * libm::pow(c.preload_n / c.stiffness, inv_hardening);
        let rest_deg = s.characteristic.angle_deg(s.rest_pulse_us);
        let mut states: Vec<CordState, MAX_CORDS> = Vec::new();
        for (k, cs) in cords.iter().enumerate() {
            // The sensor zeros of each cord in turn, from the plant's one stream.
            let zero = [(); 2].map(|()| n.zero_counts + n.zero_spread_counts * rng.normal());
            let st = CordState::at_rest(&cfg, cs, zero, rest_deg, origin_us);
            let st = CordState {
                // Its own stream, so a quiet plant draws exactly the numbers it always drew.
                disturb: cfg.disturbances.any().then(|| {
                    DisturbState::new(
                        &cfg.disturbances,
                        derive_seed(seed, &[0xD157_0000, k as u64]),
                    )
                }),
                ..st
            };
            let _ = states.push(st);
        }
        let any_time_dependent = states.iter().any(|c| c.time_dependent);
        let damping = m.kt_nm_per_a * m.kt_nm_per_a / m.resistance_ohm + m.viscous_nms;
        let mut plant = Plant {
            cfg,
            rest_deg,
            lever_mm_per_deg: s.lever_m * 1e3 * core::f64::consts::PI / 180.0,
            e_pre_mm,
            inv_hardening,
            radius_m: cfg.capstan_diameter_mm * 0.5e-3,
            noise_sd_counts: n.noise_sd_n / n.n_per_count,
            motor_damping: damping,
            inv_damping: 1.0 / damping,
            stall_m: -m.coulomb_nm,
            demand_m: 0.0,
            decay_dt_us: 0,
            decay: 1.0,
            rc_decay_dt_us: 0,
            rc_decay: 1.0,
            origin_us,
            t_us: origin_us,
            next_frame_us: origin_us + s.frame_us as u64,
            next_refresh_us: origin_us,
            next_wander_us: origin_us + crate::disturb::WANDER_STEP_US,
            any_time_dependent,
            settled_until_us: 0,
            drive_v: 0.0,
            omega: 0.0,
            transmission: 0.0,
            load_nm: 0.0,
            drive_still_dt_us: 0,
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
}

impl CordState {
    /// A cord at rest under `cfg`: servo at its rest angle, cord at its preload, the sensors
    /// with these zeros, no disturbance (the caller draws it).
    fn at_rest(
        cfg: &PlantConfig,
        cs: &CordSetup,
        zero: [f64; 2],
        rest_deg: f64,
        origin_us: u64,
    ) -> CordState {
        let (s, c, n) = (cfg.servo, cfg.cord, cfg.sensor);
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
        let cpn = n.gain / n.n_per_count;
        let wanders = cfg.disturbances.mu_wander_sd > 0.0;
        CordState {
            setup: *cs,
            op,
            time_dependent: heats || law.mu_change_per_100s != 0.0 || wanders,
            heats,
            pending_pulse_us: s.rest_pulse_us,
            target_deg: rest_deg,
            angle_deg: rest_deg,
            commanded_pulse_us: s.rest_pulse_us,
            commanded_deg: rest_deg,
            amp_control_v: 0.0,
            amp_filtered_v: 0.0,
            t1: c.preload_n,
            t2: c.preload_n,
            a_kin: 1.0,
            dirty: true,
            memory: LoadMemory::default(),
            disturb: None,
            falling: false,
            powered: true,
            broken: false,
            snag: false,
            unplugged: [false; 2],
            frozen: [None; 2],
            servo_stalled: false,
            amp_released: false,
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
        }
    }
}

/// Every constant of the configuration within its physical range.
fn check_constants(cfg: &PlantConfig) -> Result<(), PlantError> {
    check(positive(cfg.capstan_diameter_mm), "capstan_diameter_mm")?;
    check_servo(&cfg.servo)?;
    check_cord_and_motor(&cfg.cord, &cfg.motor)?;
    check_sensor(&cfg.sensor)?;
    let a = cfg.adc;
    check(
        a.offset_counts.is_finite() && (0.0..=100.0).contains(&a.offset_counts),
        "adc.offset_counts",
    )?;
    check(
        a.noise_sd_counts.is_finite() && (0.0..=50.0).contains(&a.noise_sd_counts),
        "adc.noise_sd_counts",
    )?;
    check(cfg.max_step_us > 0, "max_step_us")?;
    check(cfg.refresh_us > 0, "refresh_us")?;
    check_disturbances(&cfg.disturbances)
}

fn check_servo(s: &ServoConfig) -> Result<(), PlantError> {
    check(positive(s.lever_m), "servo.lever_m")?;
    check(positive(s.no_load_deg_per_s), "servo.no_load_deg_per_s")?;
    check(positive(s.stall_torque_nm), "servo.stall_torque_nm")?;
    check(s.frame_us > 0, "servo.frame_us")?;
    let sc = s.characteristic;
    check(
        sc.neutral_pulse_us.is_finite(),
        "servo.characteristic.neutral_pulse_us",
    )?;
    check(
        sc.deg_per_us.is_finite() && sc.deg_per_us != 0.0,
        "servo.characteristic.deg_per_us",
    )?;
    check(
        sc.min_deg.is_finite()
            && sc.max_deg.is_finite()
            && sc.min_deg < sc.max_deg
            && (sc.min_deg..=sc.max_deg).contains(&sc.neutral_deg),
        "servo.characteristic travel (min_deg <= neutral_deg <= max_deg)",
    )?;
    check(
        sc.dead_band_us.is_finite() && sc.dead_band_us >= 0.0,
        "servo.characteristic.dead_band_us",
    )?;
    check(
        positive(s.rest_pulse_us) && s.rest_pulse_us < s.frame_us as f64,
        "servo.rest_pulse_us",
    )?;
    check(
        s.unpowered_hold_nm.is_finite() && s.unpowered_hold_nm >= 0.0,
        "servo.unpowered_hold_nm",
    )?;
    check(
        s.backdrive_deg_per_s_per_nm.is_finite() && s.backdrive_deg_per_s_per_nm >= 0.0,
        "servo.backdrive_deg_per_s_per_nm",
    )?;
    Ok(())
}

fn check_cord_and_motor(c: &CordConfig, m: &MotorConfig) -> Result<(), PlantError> {
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
    check(
        m.amp_filter_tau_s.is_finite() && m.amp_filter_tau_s >= 0.0,
        "motor.amp_filter_tau_s",
    )?;
    check(
        m.amp_filter_released_tau_s.is_finite() && m.amp_filter_released_tau_s >= 0.0,
        "motor.amp_filter_released_tau_s",
    )?;
    Ok(())
}

fn check_sensor(n: &SensorConfig) -> Result<(), PlantError> {
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
    check(n.saturation_counts > 0.0, "sensor.saturation_counts")?;
    Ok(())
}

fn check_disturbances(d: &Disturbances) -> Result<(), PlantError> {
    check(
        d.mu_wander_sd.is_finite() && (0.0..=0.5).contains(&d.mu_wander_sd),
        "disturbances.mu_wander_sd",
    )?;
    check(positive(d.mu_wander_tau_s), "disturbances.mu_wander_tau_s")?;
    check(
        d.zero_error_sd_n.is_finite() && (0.0..=5.0).contains(&d.zero_error_sd_n),
        "disturbances.zero_error_sd_n",
    )?;
    Ok(())
}

/// One cord's set-up (wrap, run, unmodelled physics) within its range.
fn check_cord(cs: &CordSetup) -> Result<(), PlantError> {
    check(
        cs.wrap_deg.is_finite() && cs.wrap_deg >= 0.0,
        "cord wrap_deg",
    )?;
    check(cs.run >= 1, "cord run")?;
    let u = cs.unmodelled;
    check(
        u.hysteresis.is_finite() && u.hysteresis > -0.9 && u.hysteresis < 2.0,
        "cord unmodelled.hysteresis",
    )?;
    check(
        u.t2_nonlinearity.is_finite() && u.t2_nonlinearity.abs() < 10.0,
        "cord unmodelled.t2_nonlinearity",
    )?;
    check(
        u.regime_change.is_finite() && u.regime_change > -0.9 && u.regime_change < 2.0,
        "cord unmodelled.regime_change",
    )?;
    check(
        u.settling.is_finite() && u.settling > -0.9 && u.settling < 0.9,
        "cord unmodelled.settling",
    )?;
    check(
        u.mu_bump.is_finite() && u.mu_bump > -0.9 && u.mu_bump < 2.0,
        "cord unmodelled.mu_bump",
    )?;
    for (v, what) in [
        (u.t2_lowforce, "cord unmodelled.t2_lowforce"),
        (u.t1_tare_diameter, "cord unmodelled.t1_tare_diameter"),
        (u.t2_offset_wrap, "cord unmodelled.t2_offset_wrap"),
        (u.t2_range_step, "cord unmodelled.t2_range_step"),
        (u.t2_quadratic, "cord unmodelled.t2_quadratic"),
        (u.t1_quadratic, "cord unmodelled.t1_quadratic"),
    ] {
        check(v.is_finite() && v.abs() < 10.0, what)?;
    }
    Ok(())
}
