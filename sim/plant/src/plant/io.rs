//! What the HAL adapters call, after bringing the plant to the present with
//! [`Plant::advance_to`]: PWM duties, pin levels, ADC conversions and watchdog feeds.

use super::{Plant, ServoEvent};
use crate::rng::Rng;
use capstan_rig::hal::{AdcError, Channel, ADC_MAX_COUNTS};

impl Plant {
    /// The servo PWM of cord `i` is set to `duty` of `max_duty` (50 Hz frame; duty 0: no
    /// pulses). The servo takes it at its next frame, through its own characteristic.
    pub fn set_servo_duty(&mut self, i: usize, duty: u16, max_duty: u16) {
        let frame = self.cfg.servo.frame_us as f64;
        let pulse = if max_duty == 0 {
            0.0
        } else {
            duty as f64 / max_duty as f64 * frame
        };
        let now = self.t_us;
        let characteristic = self.cfg.servo.characteristic;
        // The next frame may have something to do now: the settled spell, which may have
        // skipped frames, ends, and the frame grid is brought past the present first.
        self.catch_up_frames();
        self.settled_until_us = 0;
        let c = &mut self.cords[i];
        // No pulse: the servo is unpowered and its horn stays where it is.
        let angle = if pulse > 0.0 {
            characteristic.angle_deg(pulse)
        } else {
            c.angle_deg
        };
        c.pending_pulse_us = pulse;
        if pulse != c.commanded_pulse_us || c.servo_events.is_empty() {
            c.commanded_pulse_us = pulse;
            c.commanded_deg = angle;
            let ev = ServoEvent {
                t_us: now,
                pulse_us: pulse as f32,
                angle_deg: angle as f32,
            };
            if c.servo_events.push(ev).is_err() {
                c.servo_events_dropped += 1;
            }
        }
        self.note_safe(i);
    }

    /// The amplifier control PWM of cord `i`'s rig is set to `duty` of `max_duty`. Its mean
    /// reaches the amplifier through the RC filter (`motor.amp_filter_tau_s`, advanced with
    /// time); the power amplifier follows the highest filtered control voltage of all rigs
    /// (their control lines are diode-OR'd: any running rig keeps the capstan turning).
    pub fn set_amp_duty(&mut self, i: usize, duty: u16, max_duty: u16) {
        let m = self.cfg.motor;
        let v = if max_duty == 0 {
            0.0
        } else {
            duty as f64 / max_duty as f64 * m.amp_full_scale_v
        };
        self.cords[i].amp_released = false;
        self.cords[i].amp_control_v = v;
        self.settled_until_us = 0;
        if m.amp_filter_tau_s <= 0.0 {
            self.cords[i].amp_filtered_v = v;
            self.update_drive();
        }
        self.note_safe(i);
    }

    /// Cord `i`'s amplifier PWM pin is released (a reset: every pin an input): the control
    /// input falls through the filter's resistor and the pull-down
    /// (`motor.amp_filter_released_tau_s`) until the pin is driven again.
    pub fn release_amp(&mut self, i: usize) {
        self.cords[i].amp_control_v = 0.0;
        self.cords[i].amp_released = true;
        self.settled_until_us = 0;
        if self.cfg.motor.amp_filter_released_tau_s <= 0.0 {
            self.cords[i].amp_filtered_v = 0.0;
            self.update_drive();
        }
        self.note_safe(i);
    }

    /// The drive voltage from the filtered control voltages; every cord is re-solved when it
    /// changes.
    pub(super) fn update_drive(&mut self) {
        let m = self.cfg.motor;
        let control = self
            .cords
            .iter()
            .map(|c| c.amp_filtered_v)
            .fold(0.0, f64::max);
        let drive = (control * m.amp_gain).min(m.amp_supply_v);
        if drive != self.drive_v {
            self.drive_v = drive;
            self.stall_m = m.kt_nm_per_a * drive / m.resistance_ohm - m.coulomb_nm;
            self.drive_still_dt_us = 0;
            for c in self.cords.iter_mut() {
                c.dirty = true;
            }
        }
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
    // (This and `feed_watchdog`, with their adapters, are inlined into host-sim's sample
    // loop: each is read or called every simulated sample.)
    #[inline]
    pub fn button_pressed(&self, i: usize) -> bool {
        let c = &self.cords[i];
        let t = self.t_us;
        let inside = |w: Option<(u64, u64)>| w.is_some_and(|(a, b)| t >= a && t < b);
        inside(c.press) || inside(c.abort)
    }

    /// Convert one force channel of cord `i` now.
    pub fn read_counts(&mut self, i: usize, ch: Channel) -> Result<u16, AdcError> {
        self.convert(i, ch)
    }

    /// Convert both force channels of cord `i` now, T1 then T2: the same two conversions as
    /// two [`Plant::read_counts`] calls. (One call per simulated sample.)
    // What two `convert` calls compute, in the same order and to the bit, with what they share
    // worked out once: the cord and the drive state are looked up once, the noise-free values
    // of both channels come first (they do not depend on the generator), and the generator's
    // state is copied into locals for the two draws (kept in registers between them, written
    // back once). The draws are the same, in the same order (T1's, then T2's), and an unplugged
    // channel still draws nothing. With an ADC of its own noise, or a frozen channel, the two
    // conversions are made one after the other (each draws its sensor's noise, then the ADC's).
    #[inline]
    pub fn read_both(&mut self, i: usize) -> [Result<u16, AdcError>; 2] {
        let adc = self.cfg.adc;
        let c = &self.cords[i];
        if adc.noise_sd_counts > 0.0 || c.frozen[0].is_some() || c.frozen[1].is_some() {
            return [self.convert(i, Channel::T1), self.convert(i, Channel::T2)];
        }
        let drive_on = self.drive_v > 0.0;
        let plugged = [!c.unplugged[0], !c.unplugged[1]];
        let mut counts = [0.0; 2];
        if plugged[0] {
            counts[0] = Self::noiseless_counts(c, Channel::T1, drive_on);
        }
        if plugged[1] {
            counts[1] = Self::noiseless_counts(c, Channel::T2, drive_on);
        }
        let sd = self.noise_sd_counts;
        if sd > 0.0 {
            let mut state = self.rng.state();
            for k in 0..2 {
                if plugged[k] {
                    counts[k] += sd * Rng::normal_in(&mut state);
                }
            }
            self.rng = Rng::from_state(state);
        }
        let sat = self.cfg.sensor.saturation_counts;
        let sensor = |k: usize| {
            if plugged[k] {
                saturate(counts[k], sat)
            } else {
                0.0
            }
        };
        [
            Ok(quantise(sensor(0) + adc.offset_counts)),
            Ok(quantise(sensor(1) + adc.offset_counts)),
        ]
    }

    /// [`Plant::read_counts`].
    #[inline(always)]
    fn convert(&mut self, i: usize, ch: Channel) -> Result<u16, AdcError> {
        Ok(quantise(self.analog(i, ch)))
    }

    /// The analog value one conversion of cord `i`'s force channel sees now, in ADC counts
    /// before quantisation (the sensor's output through its divider, its noise, then the
    /// ADC's offset and noise: one draw of each per call, as [`Plant::read_counts`], which
    /// rounds and clamps this). An unplugged sensor reads the ADC's offset and noise only, a
    /// frozen one the value it froze at and the ADC's. For a harness with an ADC of its own
    /// (the emulated RP2040's, which has neither): `volts at the pin = counts × V_ref / 4096`.
    #[inline]
    pub fn read_analog(&mut self, i: usize, ch: Channel) -> f64 {
        self.analog(i, ch)
    }

    /// [`Plant::read_analog`].
    #[inline(always)]
    fn analog(&mut self, i: usize, ch: Channel) -> f64 {
        let drive_on = self.drive_v > 0.0;
        let c = &self.cords[i];
        let k = ch as usize;
        let sensor = if c.unplugged[k] {
            0.0
        } else if let Some(held) = c.frozen[k] {
            held
        } else {
            let mut counts = Self::noiseless_counts(c, ch, drive_on);
            if self.noise_sd_counts > 0.0 {
                counts += self.noise_sd_counts * self.rng.normal();
            }
            saturate(counts, self.cfg.sensor.saturation_counts)
        };
        let adc = self.cfg.adc;
        let mut v = sensor + adc.offset_counts;
        if adc.noise_sd_counts > 0.0 {
            v += adc.noise_sd_counts * self.rng.normal();
        }
        v
    }

    /// What cord `i`'s channel `ch` puts out now without noise, saturated, counts (what a
    /// frozen channel holds).
    pub(super) fn held_counts(&self, i: usize, ch: Channel) -> f64 {
        let c = &self.cords[i];
        let v = Self::noiseless_counts(c, ch, self.drive_v > 0.0);
        saturate(v, self.cfg.sensor.saturation_counts)
    }

    /// What a plugged channel of cord `c` reads before the noise, in ADC counts.
    #[inline(always)]
    fn noiseless_counts(c: &super::CordState, ch: Channel, drive_on: bool) -> f64 {
        let k = ch as usize;
        let art = c.setup.model.sensors;
        // The catalogue artefacts ride on the drive (see the crate docs): the tare, done with
        // the capstan stopped, neither removes the offsets nor sees the gain. (T2's calibration
        // curve, a function of T2 alone, only for T2.)
        let mut reading = match ch {
            Channel::T1 if drive_on => {
                c.setup.unmodelled.t1_reading_n(c.t1)
                    + art.t1_offset_n
                    + c.setup.unmodelled.t1_offset_n(c.op.diameter_mm)
            }
            Channel::T1 => c.setup.unmodelled.t1_reading_n(c.t1),
            Channel::T2 => {
                let t2 = c.setup.unmodelled.t2_reading_n(c.t2);
                if drive_on {
                    art.t2_gain * t2
                        + art.t2_offset_n
                        + c.setup.unmodelled.t2_offset_n(c.op.wrap_rad)
                } else {
                    t2
                }
            }
        };
        if let (true, Some(d)) = (drive_on, c.disturb.as_ref()) {
            reading += d.zero_error_n[k];
        }
        c.zero[k] + reading * c.counts_per_n[k]
    }

    /// Cord `i`'s watchdog is fed.
    #[inline]
    pub fn feed_watchdog(&mut self, i: usize) {
        let now = self.t_us;
        let c = &mut self.cords[i];
        if let Some(last) = c.last_feed_us {
            c.max_feed_gap_us = c.max_feed_gap_us.max(now - last);
        }
        c.last_feed_us = Some(now);
    }
}

/// A sensor's output cannot rise above its saturation (a reading in counts at the ADC).
#[inline(always)]
fn saturate(counts: f64, saturation_counts: f64) -> f64 {
    if counts > saturation_counts {
        saturation_counts
    } else {
        counts
    }
}

/// One conversion's analog value, ADC counts, as the ADC gives it: rounded half up and clamped
/// to its range (a NaN reads 0, as `NaN as u16` did).
#[inline(always)]
fn quantise(counts: f64) -> u16 {
    let x = counts + 0.5;
    if x >= 1.0 {
        if x >= ADC_MAX_COUNTS as f64 {
            ADC_MAX_COUNTS
        } else {
            // (`as` truncates: the floor, as x ≥ 1.)
            x as u16
        }
    } else {
        0
    }
}
