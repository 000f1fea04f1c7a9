//! The capstan rig core: the test protocol, calibration, conditioning, safety supervision and
//! the log records, as pure state machines, plus a thin async runner on embassy-time.
//!
//! It is generic over embedded-hal 1.0 traits ([`SetDutyCycle`] for the servo and the
//! amplifier's control voltage, [`OutputPin`]/[`InputPin`] for trigger, LED and button) and
//! two small traits of ours ([`hal::ForceAdc`], [`hal::Watchdog`]) where embedded-hal has
//! none. It never names a chip: the RP2040 binary (`src/main.rs`), the emulated-ARM build and
//! the host simulator all drive this same code. The last-resort path of a panic or HardFault
//! is here too, as a sequence over a trait ([`safe_state::force_safe`] on
//! [`safe_state::ForceOutputs`]): the board implements it on raw registers, the simulated plant
//! on its pins.
//!
//! [`SetDutyCycle`]: embedded_hal::pwm::SetDutyCycle
//! [`OutputPin`]: embedded_hal::digital::OutputPin
//! [`InputPin`]: embedded_hal::digital::InputPin
#![cfg_attr(not(test), no_std)]
#![deny(missing_docs)]
// The board's register access (panic path, reset memory) lives in the binary, not here.
#![forbid(unsafe_code)]

#[macro_use]
mod fmt;

pub mod button;
pub mod calib;
pub mod command;
pub mod condition;
#[cfg(target_os = "none")]
pub mod defmt_sink;
pub mod force;
pub mod hal;
pub mod protocol;
pub mod record;
pub mod reset;
pub mod rig;
#[cfg(test)]
mod rig_tests;
pub mod runner;
pub mod safe_state;
pub mod safety;
pub mod settings;
pub mod setup;
pub mod store;

pub use calib::{AmpMap, Calibration, CalibrationError, ChannelCal, ServoMap};
pub use command::{Command, CommandError};
pub use force::{BoardLaw, ControlMode, ForceConfig, ForceError, ForceProfile};
pub use protocol::{Protocol, ProtocolError, StepOrder};
pub use record::{FaultKind, LogSink, Record};
pub use rig::Rig;
pub use runner::{run_once, RigIo, RunError};
pub use safe_state::{force_safe, ForceOutputs, SafeDuties};
pub use settings::{Settings, SettingsError};
