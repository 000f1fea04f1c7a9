//! The rig around the emulated RP2040: `capstan-plant` on the pins of the board image that
//! `sim/emu/harness.mjs` runs on rp2040js. Built to WebAssembly for the harness (see `wasm`), and
//! for the host, where `tests/emu_rp2040.rs` takes the cases from it to run host-sim on the
//! same rig.
//!
//! * [`case`]: the cases (rig, operator, faults, end); [`hazards`]: parts that fail;
//!   [`cases`]: every case, by name;
//! * [`bench`]: the plant on the pins, the pin meters' records, the loop budget;
//! * [`meter`]: a PWM measured from its pin's edges;
//! * [`report`]: what the bench saw, for the harness's JSON;
//! * [`front_end`]: a force sensor through the board's divider into the RP2040's ADC.
#![deny(missing_docs)]

pub mod bench;
pub mod case;
pub mod cases;
pub mod front_end;
pub mod hazards;
pub mod meter;
pub mod report;
#[cfg(target_arch = "wasm32")]
mod wasm;

pub use bench::{Bench, Report};
/// The board's pin map (the wire schema's), for the harness's job and the tests.
pub use capstan_wire::pins;
pub use case::{Case, CoreFault, HostLine, Stop};
