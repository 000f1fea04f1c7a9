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
///
/// The board implements it on the RP2040's ADC, the simulated plant on its sensor model. A
/// test bench with fixed readings, turned into newtons by the default calibration:
///
/// ```
/// use capstan_rig::hal::{AdcError, Channel, ForceAdc};
/// use capstan_rig::Calibration;
///
/// /// Two sensors holding still, and the conversions asked of them.
/// struct Still {
///     counts: [u16; 2],
///     asked: Vec<Channel>,
/// }
///
/// impl ForceAdc for Still {
///     fn read_counts(&mut self, channel: Channel) -> Result<u16, AdcError> {
///         self.asked.push(channel);
///         Ok(self.counts[channel as usize])
///     }
/// }
///
/// let mut adc = Still { counts: [1067, 2400], asked: Vec::new() };
/// // Every sample reads both channels, T1 first.
/// let [t1, t2] = adc.read_both();
/// assert_eq!(adc.asked, [Channel::T1, Channel::T2]);
///
/// // Zero at 400 counts, 0.015 N per count: (1067 − 400) × 0.015 = 10.005 N.
/// let cal = Calibration::default();
/// assert!((cal.t1.newtons(t1.unwrap() as f32) - 10.005).abs() < 1e-3);
/// assert!((cal.t2.newtons(t2.unwrap() as f32) - 30.0).abs() < 1e-3);
///
/// // A borrowed ADC is an ADC too (the runner borrows the board's).
/// fn sample(mut adc: impl ForceAdc) -> [Result<u16, AdcError>; 2] {
///     adc.read_both()
/// }
/// assert_eq!(sample(&mut adc), [Ok(1067), Ok(2400)]);
/// assert_eq!(adc.asked.len(), 4);
/// ```
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
///
/// The runner feeds it once a sample. Before a flash write, which holds the loop, it asks for
/// room with [`Watchdog::allow_ms`]; a watchdog that cannot widen its timeout just feeds:
///
/// ```
/// use capstan_rig::hal::Watchdog;
///
/// #[derive(Default)]
/// struct Counting {
///     feeds: u32,
/// }
///
/// impl Watchdog for Counting {
///     fn feed(&mut self) {
///         self.feeds += 1;
///     }
/// }
///
/// let mut dog = Counting::default();
/// dog.feed();
/// dog.allow_ms(400); // the default: one ordinary feed
/// assert_eq!(dog.feeds, 2);
///
/// // A rig without a watchdog (the host's tests) passes `()`.
/// ().allow_ms(400);
/// ```
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
///
/// The runner drains it every sample into a [`crate::command::LineBuffer`], which gives a
/// command at each newline:
///
/// ```
/// use capstan_rig::command::LineBuffer;
/// use capstan_rig::hal::{Channel, Console};
/// use capstan_rig::{Command, CommandError};
///
/// /// What `capstan rig` wrote, not yet read.
/// struct Host<'a>(core::slice::Iter<'a, u8>);
///
/// impl Console for Host<'_> {
///     fn read_byte(&mut self) -> Option<u8> {
///         self.0.next().copied()
///     }
/// }
///
/// let mut host = Host(b"setup\nweigh t1 9.80665\n\nfly\nzero".iter());
/// let mut line = LineBuffer::default();
/// let commands: Vec<_> = core::iter::from_fn(|| host.read_byte())
///     .filter_map(|byte| line.push(byte))
///     .collect();
/// assert_eq!(commands.len(), 3); // a blank line is no command; `zero` has no newline yet
/// assert_eq!(commands[0], Ok(Command::Setup));
/// assert_eq!(commands[1], Ok(Command::Weigh(Channel::T1, 9.80665)));
/// assert!(matches!(commands[2], Err(CommandError::Unknown)));
///
/// // No host: nothing arrives.
/// assert_eq!(().read_byte(), None);
/// ```
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
