//! host-sim: the rig firmware's own code (`capstan_rig::run_once` driving a `capstan_rig::Rig`)
//! against the simulated plant (`capstan-plant`), in virtual time.
//!
//! * [`time`]: the embassy-time driver (thread-local virtual clock) and `block_on`.
//! * [`run`]: one run: plant + firmware + `Vec` sink.
//! * [`panic`](mod@panic): one run in which the firmware panics, and the board's panic path on the plant.
//! * [`setup`]: a cord's ranges, protocol and plant constants (campaigns and two-control).
//! * [`noise`]: the quiet simulator or the thesis rig's scatter ([`noise::NoiseProfile`]).
//! * [`flash`]: a NOR flash in RAM, the board's flash traits, for the settings store.
//! * [`session`]: a bench session: boot from flash, host commands, weights, presses, resets.
//! * [`campaign`]: many runs over diameters, wraps and voltages, in parallel threads.
//! * [`force`]: force control (issue 43): the firmware holding T2 at a target on the plant,
//!   open loop against feedback.
//! * [`two_control`]: several cords, each with its own servo and firmware, on one capstan and
//!   one drive motor (the thesis's two-control, single-drive rig).
//!
//! This crate provides the one embassy-time driver of any host binary it is linked into.
#![deny(missing_docs)]

pub mod campaign;
pub mod flash;
pub mod force;
pub mod noise;
pub mod panic;
pub mod run;
pub mod session;
pub mod setup;
pub mod time;
pub mod two_control;

pub use campaign::{
    run_campaign, CampaignConfig, CampaignResult, FaultSpec, FaultSpecError, PairRow,
};
pub use capstan_plant as plant;
