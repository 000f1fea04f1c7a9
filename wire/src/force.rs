//! The codes of force control (issue 43): what a run does ([`ControlMode`]) and the T2 target
//! profile of a force run ([`ForceProfile`]), with their names as `set KEY NAME` takes them.
//! The settings that go with them (levels, frequencies, gains, the fitted law) are rows of the
//! settings table ([`crate::settings`]).

/// What a run does.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ControlMode {
    /// The test protocol: the servo steps through its angles (the thesis's runs).
    Protocol = 0,
    /// Force control: the servo holds T2 at a target (a feedforward through the fitted capstan
    /// law, with feedback on the measured T2).
    Force = 1,
}

impl ControlMode {
    /// Every mode, by code.
    pub const ALL: [ControlMode; 2] = [ControlMode::Protocol, ControlMode::Force];

    /// Wire code (the `mode` setting).
    pub const fn code(self) -> u8 {
        self as u8
    }

    /// Inverse of [`ControlMode::code`].
    pub const fn from_code(code: u8) -> Option<ControlMode> {
        match code {
            0 => Some(ControlMode::Protocol),
            1 => Some(ControlMode::Force),
            _ => None,
        }
    }

    /// Its name, as `set mode NAME` and the CLI take it.
    pub const fn name(self) -> &'static str {
        match self {
            ControlMode::Protocol => "protocol",
            ControlMode::Force => "force",
        }
    }
}

/// The T2 target of a force run, segment by segment (a segment is one of the protocol's
/// dwells: its window gives the segment's pair).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ForceProfile {
    /// One level a segment: `force_level1_n` .. `force_level4_n` (a 0 ends the list).
    Steps = 0,
    /// Hold `force_level1_n`, ramp to `force_level2_n` over one dwell, hold it.
    Ramp = 1,
    /// Hold the mean `force_level1_n`, then a sine of amplitude `force_level2_n` about it at
    /// `force_sine_steps` frequencies from `force_sine_hz` to `force_sine_to_hz` (log-spaced),
    /// one a segment: a stepped sine sweep, for the closed loop's bandwidth.
    Sine = 2,
}

impl ForceProfile {
    /// Every profile, by code.
    pub const ALL: [ForceProfile; 3] =
        [ForceProfile::Steps, ForceProfile::Ramp, ForceProfile::Sine];

    /// Wire code (the `force_profile` setting).
    pub const fn code(self) -> u8 {
        self as u8
    }

    /// Inverse of [`ForceProfile::code`].
    pub const fn from_code(code: u8) -> Option<ForceProfile> {
        match code {
            0 => Some(ForceProfile::Steps),
            1 => Some(ForceProfile::Ramp),
            2 => Some(ForceProfile::Sine),
            _ => None,
        }
    }

    /// Its name, as `set force_profile NAME` and the CLI take it.
    pub const fn name(self) -> &'static str {
        match self {
            ForceProfile::Steps => "steps",
            ForceProfile::Ramp => "ramp",
            ForceProfile::Sine => "sine",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_and_names_round_trip() {
        for m in ControlMode::ALL {
            assert_eq!(ControlMode::from_code(m.code()), Some(m));
        }
        for p in ForceProfile::ALL {
            assert_eq!(ForceProfile::from_code(p.code()), Some(p));
        }
        assert_eq!(ControlMode::from_code(2), None);
        assert_eq!(ForceProfile::from_code(3), None);
    }
}
