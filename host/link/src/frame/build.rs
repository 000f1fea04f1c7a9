//! A record's field values, read by name from its format (`elf::RecordLayout`), into the
//! firmware's own typed [`Record`]: the same struct the rig emitted, so the host works with
//! what the firmware means, not with a copy of it. Which fields a record has, in which order
//! and at which type, is the wire schema's (`capstan-wire`); which struct field each one is,
//! the firmware's (`Record::from_fields`). Nothing here names a field.

use crate::elf::{Prim, RecordKind, RecordLayout};
use crate::error::FrameError;
use capstan_rig::record::{FieldsError, Record};
use capstan_rig::{Calibration, Protocol, Settings};
use capstan_wire::{Scalar, Setting};

/// Field values of one record, by name.
pub(super) struct Fields<'a> {
    pub layout: &'a RecordLayout,
    pub values: &'a [String],
}

impl Fields<'_> {
    fn raw(&self, name: &str) -> Result<&str, FrameError> {
        let i = self
            .layout
            .position(name)
            .ok_or_else(|| FrameError::NoField(name.to_string()))?;
        self.values
            .get(i)
            .map(String::as_str)
            .ok_or_else(|| FrameError::MissingValue(name.to_string()))
    }

    /// An unsigned field (the sequence number).
    pub fn u(&self, name: &str) -> Result<u32, FrameError> {
        match parse(name, Prim::U32, self.raw(name)?)? {
            Scalar::U32(v) => Ok(v),
            _ => unreachable!("parsed as u32"),
        }
    }
}

/// A field's value as defmt-decoder renders it, at its wire type.
pub(super) fn parse(name: &str, prim: Prim, v: &str) -> Result<Scalar, FrameError> {
    let not = |what| FrameError::NotOfType {
        field: name.to_string(),
        value: v.to_string(),
        what,
    };
    let unsigned =
        || -> Result<u64, FrameError> { v.parse().map_err(|_| not("an unsigned integer")) };
    let fit = |what| FrameError::DoesNotFit {
        field: name.to_string(),
        value: v.to_string(),
        what,
    };
    Ok(match prim {
        Prim::U8 => Scalar::U8(u8::try_from(unsigned()?).map_err(|_| fit("a byte"))?),
        Prim::U16 => Scalar::U16(u16::try_from(unsigned()?).map_err(|_| fit("16 bits"))?),
        Prim::U32 => Scalar::U32(u32::try_from(unsigned()?).map_err(|_| fit("32 bits"))?),
        Prim::I64 => Scalar::I64(v.parse().map_err(|_| not("an integer"))?),
        Prim::F32 => Scalar::F32(v.parse().map_err(|_| not("a number"))?),
    })
}

/// The typed record of a kind from its fields: each of the schema's, in its order, from the
/// frame; one the firmware's record does not carry (a field the schema does not require,
/// which an older firmware lacks) as the firmware's default (a setting's built-in value; a run
/// record's `t2_target_n`, 0: no target). Not NaN: records compare equal.
pub(super) fn build(kind: RecordKind, f: &Fields) -> Result<Record, FrameError> {
    let defaults = Settings {
        protocol: Protocol::default(),
        calibration: Calibration::default(),
    };
    let mut values = Vec::new();
    for field in kind.fields().filter(|field| field.name != "crc") {
        let value = match f.layout.position(field.name) {
            Some(_) => parse(field.name, field.prim, f.raw(field.name)?)?,
            None if !field.required && field.name == "t2_target_n" => Scalar::F32(0.0),
            None => Setting::from_name(field.name)
                .filter(|_| !field.required)
                .map(|s| defaults.scalar(s))
                .ok_or_else(|| FrameError::NoField(field.name.to_string()))?,
        };
        values.push(value);
    }
    let (_, record) = Record::from_fields(kind, &values).map_err(|e| match e {
        FieldsError::Code { field, code } => FrameError::Code {
            what: code_of(field),
            code,
        },
        FieldsError::Missing(name) => FrameError::NoField(name.to_string()),
        FieldsError::Type(name) => FrameError::FieldType(name),
        FieldsError::Extra => FrameError::Extra,
    })?;
    Ok(record)
}

/// What the codes of a field are.
fn code_of(field: &'static str) -> &'static str {
    match field {
        "kind" | "fault" => "fault kind",
        "source" => "settings source",
        "order" => "step order",
        "t1_cal" | "t2_cal" => "sensitivity source",
        f => f,
    }
}
