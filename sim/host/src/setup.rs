//! Setting up a run on one cord, shared by campaigns and the two-control rig: the ranges of a
//! capstan diameter, a wrap and a drive voltage, the cord's protocol and the plant's constants.

use capstan_plant::PlantConfig;
use capstan_rig::safety::SafetyLimits;
use capstan_rig::{Calibration, Protocol, StepOrder};
use std::fmt;

/// A set-up value out of its range: which, the value, and what is allowed.
#[derive(Clone, Debug, PartialEq)]
pub struct OutOfRange {
    /// What the value is (with its unit).
    pub what: &'static str,
    /// The value.
    pub value: f64,
    /// What is allowed.
    pub allowed: String,
}

impl fmt::Display for OutOfRange {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} = {}: {}", self.what, self.value, self.allowed)
    }
}

fn in_range(
    ok: bool,
    what: &'static str,
    value: f64,
    allowed: impl Into<String>,
) -> Result<(), OutOfRange> {
    if ok {
        Ok(())
    } else {
        Err(OutOfRange {
            what,
            value,
            allowed: allowed.into(),
        })
    }
}

/// A capstan diameter: 0 to 1000 mm.
pub fn check_diameter(d: f64) -> Result<(), OutOfRange> {
    let ok = d.is_finite() && d > 0.0 && d <= 1000.0;
    in_range(ok, "capstan diameter (mm)", d, "must be in (0, 1000]")
}

/// A wrap: 0 to 3600°.
pub fn check_wrap(w: f64) -> Result<(), OutOfRange> {
    let ok = w.is_finite() && w > 0.0 && w <= 3600.0;
    in_range(ok, "wrap (deg)", w, "must be in (0, 3600]")
}

/// A drive voltage: 0 to the amplifier's full control voltage × its gain (13.2 V with the
/// default calibration), judged as the firmware judges the control voltage it is commanded
/// ([`cord_protocol`]'s, in `f32`): 13.2 V itself is a drive the rig runs (in `f64`, 3.3 V of
/// `f32` × 4 is 13.1999998 V, and 13.2 V was refused).
pub fn check_drive_v(v: f64, calibration: &Calibration) -> Result<(), OutOfRange> {
    let control_v = (v / calibration.amp.amp_gain as f64) as f32;
    let ok = v.is_finite() && v >= 0.0 && control_v <= calibration.amp.full_scale_v;
    let (full, gain) = (calibration.amp.full_scale_v, calibration.amp.amp_gain);
    let top = full as f64 * gain as f64;
    let allowed =
        format!("must be 0 to {top:.1} V ({full} V of control × the amplifier's gain of {gain})");
    in_range(ok, "drive voltage (V)", v, allowed)
}

/// The protocol of a run on one cord: `base` with the step order and the cord's diameter and
/// wrap, and the drive voltage commanded as drive / the amplifier's gain of control voltage.
pub fn cord_protocol(
    base: &Protocol,
    calibration: &Calibration,
    order: StepOrder,
    diameter_mm: f64,
    wrap_deg: f64,
    drive_v: f64,
) -> Protocol {
    Protocol {
        order,
        amp_control_v: (drive_v / calibration.amp.amp_gain as f64) as f32,
        capstan_diameter_mm: diameter_mm as f32,
        wrap_deg: wrap_deg as f32,
        ..*base
    }
}

/// The firmware's limits for a plant with or without sensor noise: a noiseless plant (an
/// idealisation no real channel is) is not a frozen sensor, so the firmware's check for a
/// channel without any noise is off for it (`SafetyLimits::stuck_samples`). Every other check
/// is as the board's.
pub fn cord_limits(base: &SafetyLimits, plant: &PlantConfig) -> SafetyLimits {
    let noiseless = plant.sensor.noise_sd_n == 0.0 && plant.adc.noise_sd_counts == 0.0;
    SafetyLimits {
        stuck_samples: if noiseless { 0 } else { base.stuck_samples },
        ..*base
    }
}

/// The sensitivities the simulated person types into the firmware: the calibration as given,
/// counted as typed (the simulation knows its sensors; a board's built-in placeholder never
/// runs).
pub fn typed_calibration() -> Calibration {
    Calibration::default().typed()
}

/// The rig's constants on a capstan of `diameter_mm`, with or without sensor noise.
pub fn cord_plant(base: &PlantConfig, diameter_mm: f64, sensor_noise: bool) -> PlantConfig {
    let mut plant = *base;
    plant.capstan_diameter_mm = diameter_mm;
    if !sensor_noise {
        plant.sensor.noise_sd_n = 0.0;
    }
    plant
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The default rig's top drive, 13.2 V, is accepted (the firmware runs it); a hundredth
    /// of a volt more, a negative drive or NaN are not.
    #[test]
    fn the_top_drive_is_the_firmwares() {
        let cal = Calibration::default();
        assert!(check_drive_v(13.2, &cal).is_ok());
        assert!(check_drive_v(0.0, &cal).is_ok());
        for v in [13.21, 13.3, 24.0, -0.1, f64::NAN, f64::INFINITY] {
            assert!(check_drive_v(v, &cal).is_err(), "{v}");
        }
        let p = cord_protocol(
            &Protocol::default(),
            &cal,
            StepOrder::Monotone,
            12.7,
            360.0,
            13.2,
        );
        assert!(p.amp_control_v <= cal.amp.full_scale_v);
    }

    /// The refusal states the range of the rig it judged, from its calibration: the default
    /// rig's 13.2 V, and 6.6 V for an amplifier of gain 2.
    #[test]
    fn the_refusal_names_the_calibrated_range() {
        let mut cal = Calibration::default();
        let e = check_drive_v(20.0, &cal).unwrap_err().to_string();
        assert!(
            e.contains("0 to 13.2 V (3.3 V of control × the amplifier's gain of 4)"),
            "{e}"
        );
        cal.amp.amp_gain = 2.0;
        assert!(check_drive_v(6.6, &cal).is_ok());
        let e = check_drive_v(7.0, &cal).unwrap_err().to_string();
        assert!(
            e.contains("0 to 6.6 V (3.3 V of control × the amplifier's gain of 2)"),
            "{e}"
        );
    }
}
