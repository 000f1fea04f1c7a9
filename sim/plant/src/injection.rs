//! Fault injection: what the plant can be made to suffer, on which cord and when, and what
//! became of it.

use capstan_rig::hal::Channel;
use capstan_rig::FaultKind;

/// A physical fault the plant can be made to suffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InjectionKind {
    /// The cord parts at the fixed sensor's hook. Both tensions collapse (a free end carries
    /// nothing, and the capstan feeds the loose cord towards the servo).
    CordBreak,
    /// A sensor's connector comes out: its ADC input is pulled to 0 counts.
    SensorUnplugged(Channel),
    /// The cord snags between capstan and fixed sensor: T2 jumps to `FaultConfig::snag_n`.
    OverForce,
    /// The operator presses the start/abort button during the run.
    Abort,
    /// A sensor's reading freezes at a plausible value: the divider's lead comes off the pin
    /// and its 100 nF holds the last voltage (or the sensor's amplifier freezes). The ADC
    /// still adds its own offset and noise ([`crate::AdcConfig`]).
    Frozen(Channel),
    /// The servo stops following its pulses where it is (a stripped gear, a dead motor).
    ServoStall,
}

impl InjectionKind {
    /// The fault the firmware should raise for it (by its name, so that this plant also
    /// drives a firmware that lacks the kind).
    pub const fn fault_name(self) -> &'static str {
        match self {
            InjectionKind::CordBreak => "cord_break",
            InjectionKind::SensorUnplugged(_) => "sensor_unplugged",
            InjectionKind::OverForce => "over_force",
            InjectionKind::Abort => "abort",
            InjectionKind::Frozen(_) => "sensor_frozen",
            InjectionKind::ServoStall => "servo_stall",
        }
    }

    /// The fault the firmware should raise for it.
    pub fn fault(self) -> FaultKind {
        FaultKind::ALL
            .into_iter()
            .find(|k| k.name() == self.fault_name())
            .expect("every injection's fault is the firmware's")
    }

    /// The firmware's name of that fault (`cord_break`, `sensor_unplugged`, `over_force`,
    /// `abort`, `sensor_frozen`, `servo_stall`).
    pub const fn name(self) -> &'static str {
        self.fault_name()
    }

    /// Parse a fault name; `sensor_unplugged` unplugs (`sensor_frozen` freezes) T2 (the fixed
    /// sensor), and `_t1` / `_t2` choose.
    pub fn from_name(name: &str) -> Option<InjectionKind> {
        match name {
            "cord_break" => Some(InjectionKind::CordBreak),
            "sensor_unplugged" | "sensor_unplugged_t2" => {
                Some(InjectionKind::SensorUnplugged(Channel::T2))
            }
            "sensor_unplugged_t1" => Some(InjectionKind::SensorUnplugged(Channel::T1)),
            "over_force" => Some(InjectionKind::OverForce),
            "abort" => Some(InjectionKind::Abort),
            "sensor_frozen" | "sensor_frozen_t2" => Some(InjectionKind::Frozen(Channel::T2)),
            "sensor_frozen_t1" => Some(InjectionKind::Frozen(Channel::T1)),
            "servo_stall" => Some(InjectionKind::ServoStall),
            _ => None,
        }
    }

    /// The names [`InjectionKind::from_name`] knows.
    pub const NAMES: [&'static str; 6] = [
        "cord_break",
        "sensor_unplugged",
        "over_force",
        "abort",
        "sensor_frozen",
        "servo_stall",
    ];
}

/// A fault to inject: what, on which cord, and when (µs after that cord's trigger rose; the
/// logger's timebase, the same as the pairs' `time_s`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Injection {
    /// What happens.
    pub kind: InjectionKind,
    /// Which cord (0-based).
    pub cord: u8,
    /// When, µs after the cord's trigger rising edge.
    pub after_trigger_us: u64,
}

/// What became of an injection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InjectionReport {
    /// The injection.
    pub injection: Injection,
    /// When it took effect, plant µs (`None`: the trigger never rose or time never got there).
    pub at_us: Option<u64>,
    /// First moment after it at which the plant saw that cord's servo commanded to rest and
    /// its amplifier at 0 V, plant µs.
    pub safe_at_us: Option<u64>,
}

impl InjectionReport {
    /// Time from the injection to the safe state, µs.
    pub fn safe_after_us(&self) -> Option<u64> {
        Some(self.safe_at_us? - self.at_us?)
    }
}
