//! The servo's position control beyond its slew: the dead band it moves with.
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

use crate::config::ServoCharacteristic;

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
