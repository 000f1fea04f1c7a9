//! The pin map of the Raspberry Pi Pico board, defined once: the board binary takes these
//! pins (and checks at boot that its typed peripherals are them), its panic path writes their
//! registers by number, and the emulated board's harness (`sim/emu/harness.mjs`, through the job
//! file `tests/emu_rp2040` writes from [`PINS`]) and bench listen and drive the same ones.
//!
//! | signal                          | GPIO | peripheral        | Pico pin |
//! |---------------------------------|------|-------------------|----------|
//! | servo signal, 50 Hz PWM         | GP16 | PWM slice 0, A    | 21       |
//! | amplifier control, PWM into RC  | GP18 | PWM slice 1, A    | 24       |
//! | logger trigger (high = trigger) | GP20 | SIO output        | 26       |
//! | start/abort button (to GND)     | GP21 | SIO input pull-up | 27       |
//! | status LED (onboard)            | GP25 | SIO output        | —        |
//! | T1 force sensor (servo side)    | GP26 | ADC0              | 31       |
//! | T2 force sensor (fixed side)    | GP27 | ADC1              | 32       |
//! | SMPS mode (inside the Pico)     | GP23 | SIO output, high  | —        |

/// The rig's pins, by GPIO number.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PinMap {
    /// Servo signal, 50 Hz PWM (channel A of its slice).
    pub servo: u8,
    /// Amplifier control, PWM into the RC filter (channel A of its slice).
    pub amp: u8,
    /// Logger trigger line (high = trigger).
    pub trigger: u8,
    /// Start/abort button to ground (pull-up: pressed = low).
    pub button: u8,
    /// Status LED (the Pico's onboard one).
    pub led: u8,
    /// T1 force sensor (servo side), an ADC input.
    pub t1: u8,
    /// T2 force sensor (fixed side), an ADC input.
    pub t2: u8,
    /// The Pico's SMPS power-save pin (driven high: PWM mode, a quieter ADC reference).
    pub smps_mode: u8,
}

/// The pins of the plain Pico (not a Pico W, whose GP23-25 and GP29 belong to its radio).
pub const PINS: PinMap = PinMap {
    servo: 16,
    amp: 18,
    trigger: 20,
    button: 21,
    led: 25,
    t1: 26,
    t2: 27,
    smps_mode: 23,
};

impl PinMap {
    /// Every pin with its name (the field's), for a map written as data (JSON for the harness).
    pub const fn named(&self) -> [(&'static str, u8); 8] {
        [
            ("servo", self.servo),
            ("amp", self.amp),
            ("trigger", self.trigger),
            ("button", self.button),
            ("led", self.led),
            ("t1", self.t1),
            ("t2", self.t2),
            ("smps_mode", self.smps_mode),
        ]
    }
}

/// The RP2040's PWM slice of a GPIO (GP0/1 slice 0, ..., GP16/17 slice 0 again).
pub const fn pwm_slice(gpio: u8) -> u8 {
    (gpio >> 1) & 7
}

/// The RP2040's ADC input of a GPIO (GP26 is ADC0 ... GP29 ADC3), `None` for another pin.
pub const fn adc_channel(gpio: u8) -> Option<u8> {
    match gpio {
        26..=29 => Some(gpio - 26),
        _ => None,
    }
}

// The two PWMs run at different frequencies (50 Hz, 30.5 kHz): a slice has one counter, so
// they must be on different slices. The sensors must be ADC inputs.
const _: () = {
    assert!(pwm_slice(PINS.servo) != pwm_slice(PINS.amp));
    assert!(
        PINS.servo.is_multiple_of(2) && PINS.amp.is_multiple_of(2),
        "channel A of their slices"
    );
    assert!(adc_channel(PINS.t1).is_some() && adc_channel(PINS.t2).is_some());
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slices_and_adc_inputs_are_the_boards() {
        assert_eq!(pwm_slice(PINS.servo), 0);
        assert_eq!(pwm_slice(PINS.amp), 1);
        assert_eq!(adc_channel(PINS.t1), Some(0));
        assert_eq!(adc_channel(PINS.t2), Some(1));
        let named = PINS.named();
        for (i, (name, gpio)) in named.iter().enumerate() {
            assert!(named[..i].iter().all(|(n, g)| n != name && g != gpio));
        }
    }
}
