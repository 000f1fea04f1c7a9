//! `capstan log`: the host end of the rig's log. The firmware sends each record as one defmt
//! frame (`firmware/src/defmt_sink.rs`); this module cuts the byte stream into frames, decodes
//! them with the firmware ELF's defmt table (defmt-decoder), checks the sequence numbers, and
//! writes the run's files as the records arrive.
//!
//! Layers: `stream` cuts bytes into frames (rzCOBS), `elf` knows the firmware's table and
//! pre-validates frames, `frame` decodes one frame into a record or a message, `seq` follows the
//! sequence numbers, `decoder` puts these together over a stream, and `output` writes a
//! session's files. `words` says the setup-mode records (`settings`, `live`, `reply`) in
//! words, for `capstan log` and `capstan rig` alike.
//!
//! The bytes come from a debug probe reading RTT ([`probe`], feature `probe`), from a saved
//! stream, or from a pipe (QEMU's semihosting output in the end-to-end test); the decoding is
//! the same.

pub mod decoder;
pub mod elf;
pub mod frame;
pub mod output;
#[cfg(feature = "probe")]
pub mod probe;
pub mod seq;
pub mod stream;
pub mod words;

pub use decoder::{decode_all, BadFrame, Decoder, Located};
pub use elf::Firmware;
pub use frame::Event;
pub use output::{LogOptions, Logger, SetupFlags, Stop, Summary};
