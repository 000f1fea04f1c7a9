//! The small hardware traits of ours, for what embedded-hal 1.0 has no trait for.

/// The two force channels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub enum Channel {
    /// T1: the low-side tension, the cord end pulled by the servo.
    T1 = 0,
    /// T2: the high-side tension, the cord end on the fixed sensor.
    T2 = 1,
}

impl Channel {
    /// Both channels, T1 first.
    pub const BOTH: [Channel; 2] = [Channel::T1, Channel::T2];
}

/// Full scale of the 12-bit ADC, counts.
pub const ADC_MAX_COUNTS: u16 = 4095;

/// A conversion that did not produce a value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub struct AdcError;

/// A 12-bit ADC with the two force sensors on it (raw counts, 0..=4095).
pub trait ForceAdc {
    /// Convert one channel now.
    fn read_counts(&mut self, channel: Channel) -> Result<u16, AdcError>;
}

/// Something that resets the chip unless fed in time (a no-op where there is none).
pub trait Watchdog {
    /// Called once per sample period by the runner.
    fn feed(&mut self);
}

/// No watchdog.
impl Watchdog for () {
    fn feed(&mut self) {}
}

impl<T: ForceAdc + ?Sized> ForceAdc for &mut T {
    fn read_counts(&mut self, channel: Channel) -> Result<u16, AdcError> {
        (**self).read_counts(channel)
    }
}

impl<T: Watchdog + ?Sized> Watchdog for &mut T {
    fn feed(&mut self) {
        (**self).feed()
    }
}
