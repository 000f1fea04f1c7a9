//! The host end of the wire to the rig: its log and its command line. The firmware sends each
//! record as one defmt frame (`firmware/rig/src/defmt_sink.rs`); this crate cuts the byte stream
//! into frames, decodes them with the firmware ELF's defmt table (defmt-decoder) and checks the
//! sequence numbers (for `capstan log`, which writes a session's files from the records), and
//! talks to the rig's command line (for `capstan rig`).
//!
//! Layers: `stream` cuts bytes into frames (rzCOBS), `elf` knows the firmware's table and
//! pre-validates frames, `frame` decodes one frame into a record or a message, `seq` follows the
//! sequence numbers, and `decoder` puts these together over a stream. `words` says the
//! setup-mode records (`settings`, `live`, `reply`) and faults in words, for `capstan log` and
//! `capstan rig` alike. [`rig`] sends command lines and waits for the records that answer them.
//!
//! The bytes come from a debug probe reading RTT (`probe`, feature `probe`), from a saved
//! stream, or from a pipe (QEMU's semihosting output in the end-to-end test); the decoding is
//! the same. Nothing here prints: what a caller may want said is handed to it.

pub mod decoder;
pub mod elf;
pub mod error;
pub mod frame;
#[cfg(feature = "probe")]
pub mod probe;
pub mod rig;
pub mod seq;
pub mod stream;
pub mod words;

pub use decoder::{decode_all, BadFrame, Decoder, Located};
pub use elf::Firmware;
pub use error::{ElfError, FormatError, FrameError, LayoutError};
pub use frame::Event;
