//! `capstan log`'s decoder on a recorded stream (a QEMU run of the rig firmware, kept in
//! tests/data with the ELF that made it):
//!
//! - `decoding`: clean decoding, the rzCOBS framing, a wrong ELF and a stream from another
//!   firmware;
//! - `damage`: records dropped from the stream (sequence gaps counted and located),
//!   truncation, corruption, a board restart;
//! - `session`: the files a session writes when the stream is damaged or joined mid-run.

#[path = "../support/mod.rs"]
mod log_support;

mod damage;
mod decoding;
mod session;

use capstan_link::{decode_all, Event, Firmware, Located};

/// The sequence numbers of the records in a stream, in order.
fn seqs(fw: &Firmware, bytes: &[u8]) -> Vec<u32> {
    decode_all(fw, bytes)
        .0
        .into_iter()
        .filter_map(|l| match l.event {
            Event::Record { seq, .. } => Some(seq),
            _ => None,
        })
        .collect()
}

/// The sequence number of a record's event.
fn record_seq(l: &Located) -> u32 {
    match l.event {
        Event::Record { seq, .. } => seq,
        _ => unreachable!(),
    }
}
