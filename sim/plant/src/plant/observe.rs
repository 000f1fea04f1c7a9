//! Observation: the true state of the cords and the drive, and what the plant recorded (servo
//! commands, trigger edges, watchdog gaps, sensor zeros), for tests, probes and reports.

use super::Plant;

/// A servo command as the plant received it (f32: a plant keeps [`crate::MAX_SERVO_EVENTS`]
/// of them per cord, in a few KiB).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ServoEvent {
    /// When the PWM duty was written, plant µs.
    pub t_us: u64,
    /// The pulse width that duty makes, µs (0: no pulses).
    pub pulse_us: f32,
    /// The horn angle that pulse holds on this servo, deg (its characteristic; without a
    /// pulse, where the horn was).
    pub angle_deg: f32,
}

/// The true state of one cord.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CordTruth {
    /// True tension at the servo-side sensor, N.
    pub t1_n: f64,
    /// True tension at the fixed sensor, N.
    pub t2_n: f64,
    /// Horn angle now, deg (the servo's own scale: [`crate::ServoCharacteristic`]).
    pub angle_deg: f64,
    /// Horn angle the servo is moving to (the last pulse taken at a frame), deg.
    pub target_deg: f64,
    /// Horn angle the last PWM write commands, deg.
    pub commanded_deg: f64,
    /// Pulse width of the last PWM write, µs (0: no pulses).
    pub commanded_pulse_us: f64,
    /// Amplifier control voltage this cord's rig commands (its PWM's mean), V.
    pub amp_control_v: f64,
    /// That control voltage after the RC filter, at the amplifier's input, V.
    pub amp_filtered_v: f64,
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

impl Plant {
    /// The true state of cord `i`.
    pub fn truth(&self, i: usize) -> CordTruth {
        let c = &self.cords[i];
        CordTruth {
            t1_n: c.t1,
            t2_n: c.t2,
            angle_deg: c.angle_deg,
            target_deg: c.target_deg,
            commanded_deg: c.commanded_deg,
            commanded_pulse_us: c.commanded_pulse_us,
            amp_control_v: c.amp_control_v,
            amp_filtered_v: c.amp_filtered_v,
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
