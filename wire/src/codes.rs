//! The codes the records carry, with their names: the step order, the channel, the fault kind
//! and where the settings in force came from.

/// Wire value of "no channel" / "no fault" in the records.
pub const NONE_CODE: u8 = 0xff;

/// The order in which the N tension levels are visited.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StepOrder {
    /// Levels 1, 2, ..., N: tension rises with time (the thesis).
    Monotone = 0,
    /// Odd levels up, then even levels down (1, 3, 5, ..., 6, 4, 2): every level is visited
    /// once, no step moves more than two levels, and level is nearly uncorrelated with time, so
    /// heating can be told from tension.
    UpDown = 1,
    /// Alternates level 1 and level N: a periodic pulse (for the two-control experiments).
    Pulse = 2,
}

impl StepOrder {
    /// Every order, by code.
    pub const ALL: [StepOrder; 3] = [StepOrder::Monotone, StepOrder::UpDown, StepOrder::Pulse];

    /// Wire code (the `order` setting).
    pub const fn code(self) -> u8 {
        self as u8
    }

    /// Inverse of [`StepOrder::code`].
    pub const fn from_code(code: u8) -> Option<StepOrder> {
        match code {
            0 => Some(StepOrder::Monotone),
            1 => Some(StepOrder::UpDown),
            2 => Some(StepOrder::Pulse),
            _ => None,
        }
    }

    /// Its name, as `set order NAME` and the CLI take it.
    pub const fn name(self) -> &'static str {
        match self {
            StepOrder::Monotone => "monotone",
            StepOrder::UpDown => "updown",
            StepOrder::Pulse => "pulse",
        }
    }

    /// The order of a name (as bytes: the board's parser has no `str`).
    pub fn from_name(name: &[u8]) -> Option<StepOrder> {
        StepOrder::ALL
            .into_iter()
            .find(|o| o.name().as_bytes() == name)
    }
}

/// The two force channels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Channel {
    /// T1: the low-side tension, the cord end pulled by the servo.
    T1 = 0,
    /// T2: the high-side tension, the cord end on the fixed sensor.
    T2 = 1,
}

impl Channel {
    /// Both channels, T1 first.
    pub const BOTH: [Channel; 2] = [Channel::T1, Channel::T2];

    /// Wire code (a fault's `channel`; [`NONE_CODE`] for none).
    pub const fn code(self) -> u8 {
        self as u8
    }

    /// Inverse of [`Channel::code`].
    pub const fn from_code(code: u8) -> Option<Channel> {
        match code {
            0 => Some(Channel::T1),
            1 => Some(Channel::T2),
            _ => None,
        }
    }

    /// Its name, as `weigh NAME NEWTONS` takes it.
    pub const fn name(self) -> &'static str {
        match self {
            Channel::T1 => "t1",
            Channel::T2 => "t2",
        }
    }

    /// The channel of a name.
    pub fn from_name(name: &[u8]) -> Option<Channel> {
        Channel::BOTH
            .into_iter()
            .find(|c| c.name().as_bytes() == name)
    }
}

/// Why a run was stopped, or what latched while none ran.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FaultKind {
    /// A channel read above the force limit.
    OverForce = 0,
    /// T2 collapsed while T1 was held: the cord broke.
    CordBreak = 1,
    /// A channel sat at an ADC rail (unplugged or shorted sensor) or failed to convert.
    SensorRail = 2,
    /// The button was pressed during the run.
    Abort = 3,
    /// The sample loop missed its deadline, or (latched at boot) the hardware watchdog reset
    /// the chip.
    Watchdog = 4,
    /// The tare saw a load beyond its bound on a channel (the firmware's `TARE_MAX_N`): a
    /// weight or a preload on the cord, or a zero that is wrong. Taken as zero, it would blind
    /// the over-force check.
    TareLoad = 5,
    /// The calibration cannot show the over-force limit below the rail check.
    Blind = 6,
    /// A channel read far below zero: a reversed sensor or a wrong zero.
    NegativeForce = 7,
    /// Latched at boot: the panic or HardFault handler reset the chip.
    Panic = 8,
    /// Latched at boot: the chip was reset (a debugger, the RUN pin) while the rig was not at
    /// rest, or by a reset that keeps nothing (the RUN pin, the debug port) whatever it was
    /// doing.
    Reset = 9,
    /// A force channel's reading is not a sensor's while the capstan is driven: it held one
    /// count (no noise at all), or it did not answer a servo step the other channel answered
    /// (a lead off the pin, its 100 nF holding the last voltage; a frozen amplifier).
    SensorFrozen = 10,
    /// Neither channel answered a servo step, or T1 moved against it: the servo does not
    /// follow its command (stalled, unpowered, its horn slipping).
    ServoStall = 11,
    /// The friction load on the capstan, (T2 − T1)·r (the drive motor's current), reached the
    /// motor's stall torque at the commanded drive: the motor is stalled.
    MotorStall = 12,
    /// T2 above what the capstan can make of T1 (e^(μ_max·wrap) beyond the sensors' errors):
    /// one of the channels reads wrong.
    Implausible = 13,
    /// The button was held down longer than a press (a lead or switch shorted, or stuck):
    /// nothing started.
    ButtonHeld = 14,
}

impl FaultKind {
    /// Every fault, by code.
    pub const ALL: [FaultKind; 15] = [
        FaultKind::OverForce,
        FaultKind::CordBreak,
        FaultKind::SensorRail,
        FaultKind::Abort,
        FaultKind::Watchdog,
        FaultKind::TareLoad,
        FaultKind::Blind,
        FaultKind::NegativeForce,
        FaultKind::Panic,
        FaultKind::Reset,
        FaultKind::SensorFrozen,
        FaultKind::ServoStall,
        FaultKind::MotorStall,
        FaultKind::Implausible,
        FaultKind::ButtonHeld,
    ];

    /// Stable name, as used by the CLI (`--fault NAME@SECONDS`) and in CSV/JSON.
    pub const fn name(self) -> &'static str {
        match self {
            FaultKind::OverForce => "over_force",
            FaultKind::CordBreak => "cord_break",
            FaultKind::SensorRail => "sensor_unplugged",
            FaultKind::Abort => "abort",
            FaultKind::Watchdog => "watchdog",
            FaultKind::TareLoad => "tare_load",
            FaultKind::Blind => "blind_calibration",
            FaultKind::NegativeForce => "negative_force",
            FaultKind::Panic => "panic",
            FaultKind::Reset => "reset",
            FaultKind::SensorFrozen => "sensor_frozen",
            FaultKind::ServoStall => "servo_stall",
            FaultKind::MotorStall => "motor_stall",
            FaultKind::Implausible => "implausible",
            FaultKind::ButtonHeld => "button_held",
        }
    }

    /// Wire code (a fault's `kind`, a run end's `fault`; [`NONE_CODE`] for none).
    pub const fn code(self) -> u8 {
        self as u8
    }

    /// Inverse of [`FaultKind::code`].
    pub fn from_code(code: u8) -> Option<FaultKind> {
        FaultKind::ALL.get(code as usize).copied()
    }

    /// The fault of a name (as [`FaultKind::name`] gives it).
    pub fn from_name(name: &str) -> Option<FaultKind> {
        FaultKind::ALL.into_iter().find(|k| k.name() == name)
    }

    /// Only a press at the rig clears it: a fault latched by a reset (watchdog, panic, reset),
    /// after which the servo has no pulses until a person is there. The host's `ack` is refused.
    pub const fn needs_press(self) -> bool {
        matches!(
            self,
            FaultKind::Watchdog | FaultKind::Panic | FaultKind::Reset
        )
    }
}

/// How a force channel's sensitivity came to be (the `t1_cal`/`t2_cal` settings): a run needs
/// both measured or typed, never the built-in placeholder.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CalSource {
    /// Nobody measured or typed it: the firmware's built-in placeholder (a fresh board,
    /// `defaults`, a stored record that was damaged or of an older layout), or its zero moved
    /// more than a tare's bound from the zero it was measured at.
    Placeholder = 0,
    /// Measured with a known weight (`weigh`).
    Weighed = 1,
    /// Typed by a person (`set tN_n_per_count`).
    Typed = 2,
}

impl CalSource {
    /// Every source, by code.
    pub const ALL: [CalSource; 3] = [CalSource::Placeholder, CalSource::Weighed, CalSource::Typed];

    /// Wire code.
    pub const fn code(self) -> u8 {
        self as u8
    }

    /// Inverse of [`CalSource::code`].
    pub const fn from_code(code: u8) -> Option<CalSource> {
        match code {
            0 => Some(CalSource::Placeholder),
            1 => Some(CalSource::Weighed),
            2 => Some(CalSource::Typed),
            _ => None,
        }
    }

    /// A stable name, for CSV, JSON and `rig show`.
    pub const fn name(self) -> &'static str {
        match self {
            CalSource::Placeholder => "unmeasured",
            CalSource::Weighed => "weighed",
            CalSource::Typed => "typed",
        }
    }

    /// Measured or typed by a person: a run may use it.
    pub const fn is_measured(self) -> bool {
        !matches!(self, CalSource::Placeholder)
    }
}

/// Where the settings in force came from (the `settings` record's `source`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SettingsSource {
    /// Changed by `set` since they were loaded, stored or reset to the defaults.
    Current = 0,
    /// Just written to flash (`store`).
    Stored = 1,
    /// Read from flash at boot.
    Loaded = 2,
    /// Built-in defaults: nothing stored yet.
    DefaultsNoRecord = 3,
    /// Built-in defaults: the newest stored record is corrupt, so none is used.
    DefaultsCorrupt = 4,
    /// Built-in defaults: the stored record does not validate (another version, bad values).
    DefaultsInvalid = 5,
    /// Built-in defaults: the flash could not be read.
    DefaultsFlashError = 6,
    /// Built-in defaults restored by `defaults` (not yet stored).
    DefaultsAsked = 7,
}

impl SettingsSource {
    /// Every source, by code.
    pub const ALL: [SettingsSource; 8] = [
        SettingsSource::Current,
        SettingsSource::Stored,
        SettingsSource::Loaded,
        SettingsSource::DefaultsNoRecord,
        SettingsSource::DefaultsCorrupt,
        SettingsSource::DefaultsInvalid,
        SettingsSource::DefaultsFlashError,
        SettingsSource::DefaultsAsked,
    ];

    /// Wire code.
    pub const fn code(self) -> u8 {
        self as u8
    }

    /// Inverse of [`SettingsSource::code`].
    pub fn from_code(code: u8) -> Option<SettingsSource> {
        SettingsSource::ALL.get(code as usize).copied()
    }

    /// A stable name, for CSV and JSON.
    pub const fn name(self) -> &'static str {
        match self {
            SettingsSource::Current => "changed",
            SettingsSource::Stored => "stored",
            SettingsSource::Loaded => "loaded",
            SettingsSource::DefaultsNoRecord => "defaults_no_record",
            SettingsSource::DefaultsCorrupt => "defaults_corrupt",
            SettingsSource::DefaultsInvalid => "defaults_invalid",
            SettingsSource::DefaultsFlashError => "defaults_flash_error",
            SettingsSource::DefaultsAsked => "defaults_asked",
        }
    }

    /// What it means, for a person.
    pub const fn message(self) -> &'static str {
        match self {
            SettingsSource::Current => {
                "changed by `set` since they were loaded or stored (send store to keep them)"
            }
            SettingsSource::Stored => "stored in flash",
            SettingsSource::Loaded => "loaded from flash at boot",
            SettingsSource::DefaultsNoRecord => "no settings stored: using the built-in defaults",
            SettingsSource::DefaultsCorrupt => {
                "the stored settings are corrupt: using the built-in defaults"
            }
            SettingsSource::DefaultsInvalid => {
                "the stored settings are of another version or invalid: using the built-in defaults"
            }
            SettingsSource::DefaultsFlashError => {
                "the flash could not be read: using the built-in defaults"
            }
            SettingsSource::DefaultsAsked => "built-in defaults restored (send store to keep them)",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_round_trip_and_names_are_unique() {
        for o in StepOrder::ALL {
            assert_eq!(StepOrder::from_code(o.code()), Some(o));
            assert_eq!(StepOrder::from_name(o.name().as_bytes()), Some(o));
        }
        for c in Channel::BOTH {
            assert_eq!(Channel::from_code(c.code()), Some(c));
            assert_eq!(Channel::from_name(c.name().as_bytes()), Some(c));
        }
        for (i, k) in FaultKind::ALL.into_iter().enumerate() {
            assert_eq!(FaultKind::from_code(k.code()), Some(k));
            assert!(FaultKind::ALL[..i].iter().all(|j| j.name() != k.name()));
        }
        for (i, s) in SettingsSource::ALL.into_iter().enumerate() {
            assert_eq!(SettingsSource::from_code(s.code()), Some(s));
            assert!(SettingsSource::ALL[..i]
                .iter()
                .all(|j| j.name() != s.name()));
        }
        for c in CalSource::ALL {
            assert_eq!(CalSource::from_code(c.code()), Some(c));
        }
        assert_eq!(FaultKind::from_code(NONE_CODE), None);
        assert_eq!(
            FaultKind::from_name("button_held"),
            Some(FaultKind::ButtonHeld)
        );
        assert_eq!(Channel::from_code(NONE_CODE), None);
    }
}
