//! The rig's command line from the host: one command line of the firmware's
//! (`firmware/rig/src/command.rs`) at a time, checked here first ([`check`]), sent to the board,
//! and answered from the `reply` record the firmware logs ([`link`]: the [`RigLink`] trait and
//! the wait for an answer). The board is reached through a debug probe (`probe_link`, feature
//! `probe`: RTT down channel for the lines, the defmt up-channel for the records); the
//! simulated rig takes the same lines through `capstan_sim::session`, in the tests.

pub mod check;
pub mod link;
#[cfg(feature = "probe")]
pub mod probe_link;

pub use check::{check_set, command_line, CheckError};
pub use link::{exchange, exchange_within, take, timeout_for, Answer, LinkError, NoReply, RigLink};
