//! A stand-in plant until `capstan-plant` lands: the servo angle sets T1 through a first-order
//! lag, T2 = T1·e^(0.115·wrap), both quantised by a 12-bit ADC; the button is pressed from
//! 20 ms to 120 ms after the plant is made. Same adapters shape as the real plant.

use core::cell::RefCell;
use embassy_time::Instant;
use embedded_hal::digital::{ErrorType as PinErrorType, InputPin, OutputPin};
use embedded_hal::pwm::{ErrorType as PwmErrorType, SetDutyCycle};
use firmware::hal::{AdcError, Channel, ForceAdc, Watchdog};

/// The simulated rig.
pub struct Plant {
    start_us: u64,
    last_us: u64,
    servo_duty: u16,
    t1_n: f64,
    seed: u64,
}

impl Plant {
    /// A plant at rest, its clock starting now.
    pub fn new(seed: u64) -> Self {
        let now = Instant::now().as_micros();
        Plant {
            start_us: now,
            last_us: now,
            servo_duty: 0,
            t1_n: 0.1,
            seed,
        }
    }

    fn advance(&mut self) {
        let now = Instant::now().as_micros();
        let dt = (now - self.last_us) as f64 * 1e-6;
        self.last_us = now;
        let pulse_us = self.servo_duty as f64 / MAX_DUTY as f64 * 20_000.0;
        let angle = (pulse_us - 1000.0) / 1000.0 * 180.0;
        let target = 0.1 + ((125.0 - angle).max(0.0)) * 0.4;
        let k = libm::exp(-dt / 0.05);
        self.t1_n = target + (self.t1_n - target) * k;
    }

    fn noise(&mut self) -> f64 {
        self.seed ^= self.seed << 13;
        self.seed ^= self.seed >> 7;
        self.seed ^= self.seed << 17;
        (self.seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }
}

const MAX_DUTY: u16 = 20_000;

/// Servo PWM.
pub struct Servo<'a>(pub &'a RefCell<Plant>);
/// Amplifier PWM (ignored).
pub struct Amp;
/// Any output pin (ignored).
pub struct Pin;
/// The button.
pub struct Button<'a>(pub &'a RefCell<Plant>);
/// The ADC.
pub struct Adc<'a>(pub &'a RefCell<Plant>);

impl PwmErrorType for Servo<'_> {
    type Error = core::convert::Infallible;
}
impl SetDutyCycle for Servo<'_> {
    fn max_duty_cycle(&self) -> u16 {
        MAX_DUTY
    }
    fn set_duty_cycle(&mut self, duty: u16) -> Result<(), Self::Error> {
        let mut p = self.0.borrow_mut();
        p.advance();
        p.servo_duty = duty;
        Ok(())
    }
}
impl PwmErrorType for Amp {
    type Error = core::convert::Infallible;
}
impl SetDutyCycle for Amp {
    fn max_duty_cycle(&self) -> u16 {
        MAX_DUTY
    }
    fn set_duty_cycle(&mut self, _duty: u16) -> Result<(), Self::Error> {
        Ok(())
    }
}
impl PinErrorType for Pin {
    type Error = core::convert::Infallible;
}
impl OutputPin for Pin {
    fn set_low(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
}
impl PinErrorType for Button<'_> {
    type Error = core::convert::Infallible;
}
impl InputPin for Button<'_> {
    fn is_high(&mut self) -> Result<bool, Self::Error> {
        self.is_low().map(|low| !low)
    }
    fn is_low(&mut self) -> Result<bool, Self::Error> {
        let p = self.0.borrow();
        let t = Instant::now().as_micros() - p.start_us;
        Ok((20_000..120_000).contains(&t))
    }
}
impl ForceAdc for Adc<'_> {
    fn read_counts(&mut self, channel: Channel) -> Result<u16, AdcError> {
        let mut p = self.0.borrow_mut();
        p.advance();
        let t = match channel {
            Channel::T1 => p.t1_n,
            Channel::T2 => p.t1_n * libm::exp(0.115 * core::f64::consts::TAU),
        };
        let counts = t / 0.015 + 400.0 + p.noise() * 4.0;
        Ok(libm::round(counts).clamp(0.0, 4095.0) as u16)
    }
}
/// No watchdog.
pub struct Dog;
impl Watchdog for Dog {
    fn feed(&mut self) {}
}
