//! What the HAL adapters call, after bringing the plant to the present with
//! [`Plant::advance_to`]: PWM duties, pin levels, ADC conversions and watchdog feeds.

use super::{angle_deg, Plant, ServoEvent};
use firmware::hal::{AdcError, Channel, ADC_MAX_COUNTS};

impl Plant {
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
}
