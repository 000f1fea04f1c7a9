//! The capstan rig's wire schema, defined once for both ends (as hubris defines an interface
//! once and derives its client and server): the board firmware and the host (`capstan log`,
//! `capstan rig`, the emulated board) build from this crate, so they cannot disagree.
//!
//! * [`settings`]: the settings (protocol and calibration) with their names, units and
//!   meanings, in wire order, and the keys the host may set by name;
//! * [`records`]: the log records, each kind's fields with their wire types and units, and
//!   their defmt format strings;
//! * [`codes`]: the codes the records carry (step order, channel, fault kind, settings source);
//! * [`force`]: force control's codes (the control mode, the T2 target profile);
//! * [`commands`]: the command words and the `reply` record's codes and messages;
//! * [`pins`]: the Pico's pin map.
//!
//! No dependencies (`defmt`, optional, gives the codes `defmt::Format` on the board).
#![cfg_attr(not(test), no_std)]
#![deny(missing_docs)]
#![forbid(unsafe_code)]

pub mod codes;
pub mod commands;
pub mod force;
pub mod pins;
mod prim;
pub mod records;
pub mod settings;

pub use codes::{CalSource, Channel, FaultKind, SettingsSource, StepOrder, NONE_CODE};
pub use commands::{CommandError, CommandKind, MAX_LINE};
pub use force::{ControlMode, ForceProfile};
pub use prim::{canonical_bits, Prim, Scalar};
pub use records::{Field, Level, RecordKind};
pub use settings::{Group, Key, Setting, Since, Value};
