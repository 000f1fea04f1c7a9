//! The small hardware traits of ours, for what embedded-hal 1.0 has no trait for.

/// The two force channels (their wire codes and names are the schema's).
pub use capstan_wire::Channel;

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

    /// Convert both channels now, T1 then T2 (what the runner reads every sample). The same
    /// two conversions as two [`ForceAdc::read_counts`] calls, in that order; an ADC that can
    /// do both in one go (the host simulator's, one access to its plant) says so here.
    #[inline]
    fn read_both(&mut self) -> [Result<u16, AdcError>; 2] {
        [self.read_counts(Channel::T1), self.read_counts(Channel::T2)]
    }
}

/// Something that resets the chip unless fed in time (a no-op where there is none).
pub trait Watchdog {
    /// Called once per sample period by the runner.
    fn feed(&mut self);

    /// Feed it once with room for an operation that holds the loop for up to `ms` (a flash
    /// write); the next [`Watchdog::feed`] restores the usual timeout.
    fn allow_ms(&mut self, ms: u32) {
        let _ = ms;
        self.feed();
    }
}

/// No watchdog.
impl Watchdog for () {
    fn feed(&mut self) {}
}

/// Where host commands arrive: a byte stream, read without waiting (the RTT down channel on
/// the board).
pub trait Console {
    /// The next byte the host sent, if one is there.
    fn read_byte(&mut self) -> Option<u8>;
}

/// No host.
impl Console for () {
    fn read_byte(&mut self) -> Option<u8> {
        None
    }
}

impl<T: ForceAdc + ?Sized> ForceAdc for &mut T {
    fn read_counts(&mut self, channel: Channel) -> Result<u16, AdcError> {
        (**self).read_counts(channel)
    }
    fn read_both(&mut self) -> [Result<u16, AdcError>; 2] {
        (**self).read_both()
    }
}

impl<T: Watchdog + ?Sized> Watchdog for &mut T {
    fn feed(&mut self) {
        (**self).feed()
    }
    fn allow_ms(&mut self, ms: u32) {
        (**self).allow_ms(ms)
    }
}
