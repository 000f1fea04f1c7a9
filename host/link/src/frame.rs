//! From a frame to an event: an rzCOBS-decoded, pre-validated frame decoded with the
//! firmware's defmt table (defmt-decoder) into a rig record, its fields read by name from the
//! record's format (`elf::RecordLayout`), or into a text message.
//!
//! A record decodes into the firmware's own [`Record`] (`build`), whatever its kind: the run
//! records, and the setup-mode records `settings`, `live` and `reply` that are not part of a
//! run. Every record's `crc` is checked against its fields as received, in format order.

mod build;
#[cfg(test)]
mod tests;

use super::elf::{Firmware, RecordLayout};
use super::stream::rzcobs_decode;
use crate::error::FrameError;
use build::{build, parse, Fields};
use capstan_rig::record::{CrcFields, Record};
use defmt_parser::Fragment;
use std::panic::AssertUnwindSafe;

/// What one frame was.
#[derive(Clone, Debug, PartialEq)]
pub enum Event {
    /// A rig record with its sequence number.
    Record {
        /// Sequence number.
        seq: u32,
        /// The record.
        record: Record,
    },
    /// Any other log statement of the firmware, rendered.
    Message {
        /// `INFO`, `WARN`, ... (empty for `println!`).
        level: String,
        /// The text.
        text: String,
    },
}

impl Event {
    /// The typed record and its sequence number, if this event is a record.
    pub fn record(&self) -> Option<(u32, &Record)> {
        match self {
            Event::Record { seq, record } => Some((*seq, record)),
            Event::Message { .. } => None,
        }
    }
}

/// Decode one encoded frame. The error says what is wrong with it (not where: the caller
/// knows the frame number and offset).
pub fn decode_frame(fw: &Firmware, encoded: &[u8]) -> Result<Event, FrameError> {
    let bytes = rzcobs_decode(encoded).map_err(FrameError::NotRzcobs)?;
    let index = fw.check_frame(&bytes)?;
    type Decoded = Result<Result<Event, Vec<String>>, FrameError>;
    let decoded = std::panic::catch_unwind(AssertUnwindSafe(|| -> Decoded {
        let (frame, _) =
            (fw.table().decode(&bytes)).map_err(|e| FrameError::Decoder(e.to_string()))?;
        let level = frame.level().map(|l| l.as_str().to_uppercase());
        match fw.record_layout(index) {
            Some(_) => {
                let kinds = frame.fragments();
                let values: Vec<String> = kinds
                    .iter()
                    .zip(frame.display_fragments())
                    .filter(|(k, _)| matches!(k, Fragment::Parameter(_)))
                    .map(|(_, v)| v)
                    .collect();
                Ok(Err(values))
            }
            None => Ok(Ok(Event::Message {
                level: level.unwrap_or_default(),
                text: frame.display_message().to_string(),
            })),
        }
    }));
    match decoded {
        Err(_) => Err(FrameError::DecoderPanicked),
        Ok(Err(e)) => Err(e),
        Ok(Ok(Ok(message))) => Ok(message),
        Ok(Ok(Err(values))) => {
            let layout = fw.record_layout(index).expect("checked above");
            record_from_values(layout, &values)
        }
    }
}

/// A record from its field values as defmt-decoder renders them, in the layout's order.
pub(crate) fn record_from_values(
    layout: &RecordLayout,
    values: &[String],
) -> Result<Event, FrameError> {
    if values.len() != layout.fields.len() {
        return Err(FrameError::ValueCount {
            word: layout.kind.word(),
            values: values.len(),
            fields: layout.fields.len(),
        });
    }
    let f = Fields { layout, values };
    let seq = f.u("seq")?;
    let word = layout.kind.word();
    let in_record = |e| FrameError::Record {
        word,
        seq,
        why: Box::new(e),
    };
    check_crc(layout, values).map_err(in_record)?;
    let record = build(layout.kind, &f).map_err(in_record)?;
    Ok(Event::Record { seq, record })
}

/// The record's `crc` field (firmware since the records carry one) against the CRC-32 of its
/// other fields as received (`capstan_rig::record::CrcFields`, the firmware's own code): a
/// mismatch is a corrupted record, refused rather than decoded into wrong numbers. Records of
/// a firmware without the field are not checked (the setup-mode records always have it: their
/// layout requires it). The fields are fed in format order, whichever they are, so the check
/// covers every field the firmware sent, the optional ones included.
fn check_crc(layout: &RecordLayout, values: &[String]) -> Result<(), FrameError> {
    let Some(at) = layout.position("crc") else {
        return Ok(());
    };
    let mut c = CrcFields::new();
    for ((name, prim), v) in layout
        .fields
        .iter()
        .zip(values)
        .filter(|((n, _), _)| n != "crc")
    {
        c.push(parse(name, *prim, v)?);
    }
    let sent: u32 = values[at].parse().map_err(|_| FrameError::NotOfType {
        field: "crc".to_string(),
        value: values[at].clone(),
        what: "its type",
    })?;
    let computed = c.finish();
    if sent != computed {
        return Err(FrameError::Checksum { sent, computed });
    }
    Ok(())
}

pub use capstan_rig::record::NONE_CODE;
