//! The servo: its pulse-to-angle characteristic, and its position control beyond its slew (the dead band it moves with).
//!
//! A hobby servo compares the pulse's position with its potentiometer and drives its motor
//! only while they differ by more than half its dead band (the HS-322HD: 5 µs, 0.25° of horn
//! each side): it stops as soon as the horn is inside the band, short of the pulse's position
//! by up to half the band, and a new pulse closer than that to where the horn stands moves
//! nothing. For the thesis's protocol (5.2° steps, the level's mean over 7 s) this is a small
//! constant offset in each level's angle, which the cord's fit (`CordConfig`) absorbed when it
//! was made without it: so it is off by default, and the campaigns' tensions stay as fitted.
//! For force control it is what a controller must live with (a feedback that moves the pulse
//! by less than a band gets no motion: the horn hunts), so the force-control rigs switch it on
//! ([`ServoDynamics::HS_322HD`]).

/// What a servo does with a pulse: its own transfer from pulse width to horn angle, linear
/// about its neutral pulse and limited to its travel. This is the servo's, not the firmware's:
/// the firmware maps the protocol's angles to pulses with its own calibration
/// (`capstan_rig::ServoMap`, the Arduino Servo convention by default), so a firmware map that
/// disagrees with the servo moves the lever by other amounts than the protocol means, here as
/// on the rig.
///
/// Default ([`ServoCharacteristic::HS_322HD`]): the HiTec HS-322HD data sheet as the thesis's
/// appendix quotes it in its m-file ("Control System: +Pulse Width Control 1500usec Neutral",
/// "Operating Angle: 40 Deg. one side pulse traveling 400usec", "Direction: Clockwise/Pulse
/// Traveling 1500 to 1900usec", "Dead Band Width: 5usec"; HiTec's HS-311/HS-322 spec sheet has
/// the same figures): 40° per 400 µs, 0.1° of horn per µs about 1500 µs. Angles are on the
/// usual 0-180° scale with the neutral at 90°: the thesis's write(125) (1833 µs) puts the horn
/// at 123.3°, write(65) (1214 µs) at 61.4°, so the protocol's 60° span is 61.9° of horn. The
/// travel is limited to that scale, 600-2400 µs (HiTec's standard-size servos sweep about 180°
/// over 600-2400 µs: consistent with 0.1°/µs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ServoCharacteristic {
    /// Pulse of the centre of travel, µs.
    pub neutral_pulse_us: f64,
    /// Horn travel per µs of pulse, deg/µs (a longer pulse turns clockwise: angle up, which
    /// releases the cord). Negative: the servo is mounted the other way round, so a longer
    /// pulse pulls (the firmware's rest, its longest pulse, is then the tension end).
    pub deg_per_us: f64,
    /// Horn angle at the neutral pulse, deg.
    pub neutral_deg: f64,
    /// End of travel at short pulses, deg.
    pub min_deg: f64,
    /// End of travel at long pulses, deg.
    pub max_deg: f64,
    /// Dead band, µs: pulses closer than this are the same position to the servo.
    pub dead_band_us: f64,
}

impl ServoCharacteristic {
    /// The HiTec HS-322HD (see the type's documentation for the source of each figure).
    pub const HS_322HD: ServoCharacteristic = ServoCharacteristic {
        neutral_pulse_us: 1_500.0,
        deg_per_us: 40.0 / 400.0,
        neutral_deg: 90.0,
        min_deg: 0.0,
        max_deg: 180.0,
        dead_band_us: 5.0,
    };

    /// The horn angle a pulse of `pulse_us` holds, deg, within the travel.
    pub fn angle_deg(&self, pulse_us: f64) -> f64 {
        let a = self.neutral_deg + (pulse_us - self.neutral_pulse_us) * self.deg_per_us;
        a.clamp(self.min_deg, self.max_deg)
    }

    /// The pulse that holds the horn at `angle_deg`, µs (inverse of [`Self::angle_deg`]).
    pub fn pulse_us(&self, angle_deg: f64) -> f64 {
        self.neutral_pulse_us + (angle_deg - self.neutral_deg) / self.deg_per_us
    }
}

impl Default for ServoCharacteristic {
    fn default() -> Self {
        ServoCharacteristic::HS_322HD
    }
}

/// How the servo's position control moves the horn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ServoDynamics {
    /// The horn stops half the characteristic's `dead_band_us` short of the pulse's position,
    /// and does not move for a pulse within that of where it stands. Off: it goes exactly to
    /// the pulse's position (the plant before issue 43).
    pub dead_band_motion: bool,
}

impl ServoDynamics {
    /// The horn goes exactly where the pulse says.
    pub const EXACT: ServoDynamics = ServoDynamics {
        dead_band_motion: false,
    };
    /// The HS-322HD as its data sheet has it: a 5 µs dead band in its motion too.
    pub const HS_322HD: ServoDynamics = ServoDynamics {
        dead_band_motion: true,
    };

    /// Where a frame's pulse of `pulse_us` sends a horn standing at `angle_deg`, deg.
    pub fn target_deg(&self, ch: &ServoCharacteristic, pulse_us: f64, angle_deg: f64) -> f64 {
        let aim = ch.angle_deg(pulse_us);
        if !self.dead_band_motion {
            return aim;
        }
        let half_deg = 0.5 * ch.dead_band_us * ch.deg_per_us.abs();
        let gap = aim - angle_deg;
        if gap.abs() <= half_deg {
            angle_deg
        } else {
            aim - half_deg.copysign(gap)
        }
    }
}

impl Default for ServoDynamics {
    fn default() -> Self {
        ServoDynamics::EXACT
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_horn_stops_half_a_band_short_and_ignores_a_smaller_move() {
        let ch = ServoCharacteristic::HS_322HD;
        let d = ServoDynamics::HS_322HD;
        // 1600 µs is 100°; from 90° the horn stops at 99.75°.
        assert!((d.target_deg(&ch, 1_600.0, 90.0) - 99.75).abs() < 1e-9);
        assert!((d.target_deg(&ch, 1_400.0, 90.0) - 80.25).abs() < 1e-9);
        // 2 µs (0.2°) from where it stands: no motion.
        assert_eq!(d.target_deg(&ch, 1_502.0, 90.0), 90.0);
        assert_eq!(ServoDynamics::EXACT.target_deg(&ch, 1_502.0, 90.0), 90.2);
    }
}
