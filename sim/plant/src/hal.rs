//! The simulated HAL: the very traits the board implements (embedded-hal 1.0 `SetDutyCycle`,
//! `OutputPin`, `InputPin`, and the rig core's `ForceAdc` and `Watchdog`), over a shared
//! `&RefCell<Plant>`. Every call reads the time ([`Clock`]: `embassy_time::Instant::now()`,
//! unless the harness hands a cheaper read of the same clock) and first brings the plant to that
//! instant, so the plant sees only what a real rig would: duty cycles and pin levels out of the
//! firmware, ADC counts and the button level into it.

use crate::plant::Plant;
use capstan_rig::hal::{AdcError, Channel, ForceAdc, Watchdog};
use capstan_rig::{ForceOutputs, RigIo};
use core::cell::RefCell;
use core::convert::Infallible;
use embedded_hal::digital::{ErrorType as PinErrorType, InputPin, OutputPin};
use embedded_hal::pwm::{ErrorType as PwmErrorType, SetDutyCycle};

/// `max_duty_cycle()` of the simulated servo PWM: the RP2040's 50 Hz frame in counts of
/// 0.32 µs (125 MHz / 40), `top + 1` = 62 500, the full scale the board's driver reports (its
/// output is high for `compare` counts of every `top + 1`): a duty count is the board's 0.32 µs.
pub const SERVO_MAX_DUTY: u16 = 62_500;
/// `max_duty_cycle()` of the simulated amplifier PWM: 1 mV of control voltage per count.
pub const AMP_MAX_DUTY: u16 = 3_300;

/// Where the adapters read the time, µs on `embassy_time::Instant`'s clock.
pub trait Clock: Copy {
    /// Now, µs.
    fn now_us(&self) -> u64;
}

/// `embassy_time::Instant::now()`: the board's timer, or a host's driver (host-sim's virtual
/// time, which also hands its own, inlined read of the same clock: the adapters read it ~5
/// times per simulated sample).
#[derive(Clone, Copy, Debug, Default)]
pub struct EmbassyClock;

impl Clock for EmbassyClock {
    #[inline]
    fn now_us(&self) -> u64 {
        embassy_time::Instant::now().as_micros()
    }
}

/// A handle on one cord of a shared plant: what every adapter holds.
#[derive(Clone, Copy)]
pub struct CordRef<'a, C = EmbassyClock> {
    plant: &'a RefCell<Plant>,
    cord: usize,
    clock: C,
}

impl<'a> CordRef<'a> {
    /// Cord `cord` (0-based) of `plant`. Panics if the plant has no such cord.
    pub fn new(plant: &'a RefCell<Plant>, cord: usize) -> Self {
        Self::with_clock(plant, cord, EmbassyClock)
    }
}

impl<'a, C: Clock> CordRef<'a, C> {
    /// Cord `cord` (0-based) of `plant`, on `clock`. Panics if the plant has no such cord.
    pub fn with_clock(plant: &'a RefCell<Plant>, cord: usize, clock: C) -> Self {
        assert!(cord < plant.borrow().cord_count(), "no cord {cord}");
        CordRef { plant, cord, clock }
    }

    #[inline]
    fn with<R>(&self, f: impl FnOnce(&mut Plant, usize) -> R) -> R {
        let mut p = self.plant.borrow_mut();
        p.advance_to(self.clock.now_us());
        f(&mut p, self.cord)
    }
}

macro_rules! adapter {
    ($(#[$doc:meta])* $name:ident) => {
        $(#[$doc])*
        pub struct $name<'a, C = EmbassyClock>(pub CordRef<'a, C>);
    };
}

adapter!(
    /// Servo PWM (50 Hz, [`SERVO_MAX_DUTY`]).
    ServoPwm
);
adapter!(
    /// Amplifier control PWM into the RC filter ([`AMP_MAX_DUTY`] = 3.3 V).
    AmpPwm
);
adapter!(
    /// Logger trigger line.
    TriggerPin
);
adapter!(
    /// Status LED.
    LedPin
);
adapter!(
    /// Start/abort button, active low: `is_low()` while pressed.
    ButtonPin
);
adapter!(
    /// The 12-bit ADC with both force sensors.
    SimAdc
);
adapter!(
    /// Watchdog (the plant records the longest gap between feeds).
    SimWatchdog
);

impl<C: Clock> PwmErrorType for ServoPwm<'_, C> {
    type Error = Infallible;
}

impl<C: Clock> SetDutyCycle for ServoPwm<'_, C> {
    fn max_duty_cycle(&self) -> u16 {
        SERVO_MAX_DUTY
    }

    fn set_duty_cycle(&mut self, duty: u16) -> Result<(), Infallible> {
        self.0
            .with(|p, i| p.set_servo_duty(i, duty, SERVO_MAX_DUTY));
        Ok(())
    }
}

impl<C: Clock> PwmErrorType for AmpPwm<'_, C> {
    type Error = Infallible;
}

impl<C: Clock> SetDutyCycle for AmpPwm<'_, C> {
    fn max_duty_cycle(&self) -> u16 {
        AMP_MAX_DUTY
    }

    fn set_duty_cycle(&mut self, duty: u16) -> Result<(), Infallible> {
        self.0.with(|p, i| p.set_amp_duty(i, duty, AMP_MAX_DUTY));
        Ok(())
    }
}

impl<C: Clock> PinErrorType for TriggerPin<'_, C> {
    type Error = Infallible;
}

impl<C: Clock> OutputPin for TriggerPin<'_, C> {
    fn set_low(&mut self) -> Result<(), Infallible> {
        self.0.with(|p, i| p.set_trigger(i, false));
        Ok(())
    }

    fn set_high(&mut self) -> Result<(), Infallible> {
        self.0.with(|p, i| p.set_trigger(i, true));
        Ok(())
    }
}

impl<C: Clock> PinErrorType for LedPin<'_, C> {
    type Error = Infallible;
}

impl<C: Clock> OutputPin for LedPin<'_, C> {
    fn set_low(&mut self) -> Result<(), Infallible> {
        self.0.with(|p, i| p.set_led(i, false));
        Ok(())
    }

    fn set_high(&mut self) -> Result<(), Infallible> {
        self.0.with(|p, i| p.set_led(i, true));
        Ok(())
    }
}

impl<C: Clock> PinErrorType for ButtonPin<'_, C> {
    type Error = Infallible;
}

impl<C: Clock> InputPin for ButtonPin<'_, C> {
    fn is_high(&mut self) -> Result<bool, Infallible> {
        Ok(!self.0.with(|p, i| p.button_pressed(i)))
    }

    #[inline]
    fn is_low(&mut self) -> Result<bool, Infallible> {
        Ok(self.0.with(|p, i| p.button_pressed(i)))
    }
}

impl<C: Clock> ForceAdc for SimAdc<'_, C> {
    fn read_counts(&mut self, channel: Channel) -> Result<u16, AdcError> {
        self.0.with(|p, i| p.read_counts(i, channel))
    }

    /// Both conversions on one access to the plant (one borrow, one `advance_to`): the same
    /// conversions in the same order as two `read_counts` calls, at the same instant.
    #[inline]
    fn read_both(&mut self) -> [Result<u16, AdcError>; 2] {
        self.0.with(|p, i| p.read_both(i))
    }
}

impl<C: Clock> Watchdog for SimWatchdog<'_, C> {
    #[inline]
    fn feed(&mut self) {
        self.0.with(|p, i| p.feed_watchdog(i));
    }
}

/// The outputs of cord `cord`'s rig as the firmware's last-resort path reaches them on the
/// board: straight to the pins, past the runner and its drivers. [`capstan_rig::force_safe`] on
/// this is what the RP2040's panic and HardFault handlers do on its registers (host-sim's
/// `panic` module runs it when the firmware panics).
pub struct ForcedOutputs<'a, C = EmbassyClock>(pub CordRef<'a, C>);

impl<C: Clock> ForceOutputs for ForcedOutputs<'_, C> {
    fn force_amp_off(&mut self) {
        self.0.with(|p, i| p.set_amp_duty(i, 0, AMP_MAX_DUTY));
    }

    fn force_servo_duty(&mut self, duty: u16) {
        self.0
            .with(|p, i| p.set_servo_duty(i, duty, SERVO_MAX_DUTY));
    }

    fn force_trigger_low(&mut self) {
        self.0.with(|p, i| p.set_trigger(i, false));
    }
}

/// The rig's hardware for cord `cord` of a simulated plant.
pub type SimRigIo<'a, C = EmbassyClock> = RigIo<
    ServoPwm<'a, C>,
    AmpPwm<'a, C>,
    TriggerPin<'a, C>,
    LedPin<'a, C>,
    ButtonPin<'a, C>,
    SimAdc<'a, C>,
    SimWatchdog<'a, C>,
>;

/// Everything `capstan_rig::run_once` needs for cord `cord` (0-based) of `plant`.
pub fn rig_io(plant: &RefCell<Plant>, cord: usize) -> SimRigIo<'_> {
    rig_io_on(plant, cord, EmbassyClock)
}

/// [`rig_io`], the adapters reading the time from `clock`.
pub fn rig_io_on<C: Clock>(plant: &RefCell<Plant>, cord: usize, clock: C) -> SimRigIo<'_, C> {
    let c = CordRef::with_clock(plant, cord, clock);
    RigIo {
        servo: ServoPwm(c),
        amp: AmpPwm(c),
        trigger: TriggerPin(c),
        led: LedPin(c),
        button: ButtonPin(c),
        adc: SimAdc(c),
        watchdog: SimWatchdog(c),
    }
}
