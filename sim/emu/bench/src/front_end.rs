//! The board's analog front end for a force sensor, as the user guide's hardware chapter wires it: the sensor's
//! 0-5 V output through a divider (10 kΩ from the sensor to the pin, 18 kΩ from the pin to
//! AGND) into the RP2040's 12-bit ADC, whose reference is ADC_VREF (3.3 V).
//!
//! The plant specifies its sensors at the ADC, in counts (its nominal transfer is the
//! firmware's default calibration, 400 counts at 0 N and 0.015 N per count; see
//! `capstan_plant::SensorConfig`), because host-sim's simulated ADC returns counts. Here the
//! emulated RP2040 has an ADC of its own, so the plant's reading is turned back into what the
//! sensor puts out ([`FrontEnd::sensor_v`]), and that voltage goes through the divider
//! ([`FrontEnd::pin_v`]) and the ADC's quantisation ([`FrontEnd::code`]) like on the board.

use capstan_rig::hal::ADC_MAX_COUNTS;

/// Divider and ADC reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrontEnd {
    /// Resistor from the sensor's output to the ADC pin, Ω.
    pub r_top_ohm: f64,
    /// Resistor from the ADC pin to AGND, Ω.
    pub r_bottom_ohm: f64,
    /// The ADC's reference (full scale), V.
    pub vref_v: f64,
}

impl FrontEnd {
    /// The hardware chapter's wiring: 10 kΩ / 18 kΩ, 3.3 V reference (5 V at the sensor → 3.21 V, about
    /// 3990 counts).
    pub const BOARD: FrontEnd = FrontEnd {
        r_top_ohm: 10_000.0,
        r_bottom_ohm: 18_000.0,
        vref_v: 3.3,
    };

    /// Pin voltage per sensor voltage.
    pub fn ratio(&self) -> f64 {
        self.r_bottom_ohm / (self.r_top_ohm + self.r_bottom_ohm)
    }

    /// One ADC count, V.
    pub fn lsb_v(&self) -> f64 {
        self.vref_v / (ADC_MAX_COUNTS as f64 + 1.0)
    }

    /// The sensor's output voltage for a plant reading in counts at the ADC.
    pub fn sensor_v(&self, plant_counts: f64) -> f64 {
        plant_counts * self.lsb_v() / self.ratio()
    }

    /// The voltage at the ADC pin for a sensor output, V.
    pub fn pin_v(&self, sensor_v: f64) -> f64 {
        sensor_v * self.ratio()
    }

    /// The conversion result for a pin voltage: rounded to the nearest count (half up) and
    /// clamped to 0..=4095, the convention of the plant's own ADC (`Plant::read_counts`).
    pub fn code(&self, pin_v: f64) -> u16 {
        quantise(pin_v / self.lsb_v())
    }
}

/// A value in counts to a 12-bit code, exactly as `capstan_plant::Plant::read_counts` does.
pub fn quantise(counts: f64) -> u16 {
    let x = counts + 0.5;
    if x < 1.0 || x.is_nan() {
        0
    } else if x >= ADC_MAX_COUNTS as f64 {
        ADC_MAX_COUNTS
    } else {
        x as u16
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn five_volts_at_the_sensor_is_3_21_v_and_3990_counts() {
        let fe = FrontEnd::BOARD;
        let pin = fe.pin_v(5.0);
        assert!((pin - 3.214).abs() < 1e-3, "{pin}");
        assert_eq!(fe.code(pin), 3990);
        assert_eq!(fe.code(0.0), 0);
        assert_eq!(fe.code(-0.2), 0);
        assert_eq!(fe.code(3.4), 4095);
    }

    #[test]
    fn the_divider_and_adc_give_the_plants_own_counts() {
        // Through sensor volts, the divider and the ADC, a plant reading comes out as the very
        // code the plant's own ADC would give: host-sim and the emulated board see the same
        // counts. Checked over the whole range at a step that is not a fraction of a count.
        let fe = FrontEnd::BOARD;
        let mut x = -20.0f64;
        let mut n = 0u32;
        while x < 4_200.0 {
            let through = fe.code(fe.pin_v(fe.sensor_v(x)));
            assert_eq!(through, quantise(x), "{x}");
            x += 0.013_731_9;
            n += 1;
        }
        assert!(n > 300_000);
    }
}
