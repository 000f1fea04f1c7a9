//! The rig's records as the firmware's defmt table declares them: the record kinds, found by
//! the leading word of their format string, each `WORD name={=type} name={=type} ...`, so
//! fields are read by name and type; and the check, when the ELF is loaded, that every record
//! has the fields this decoder needs. Kinds, fields and types are the wire schema's
//! (`capstan-wire`, which the firmware's format strings are written from too).
//!
//! The run records (`run_start`, `raw`, `pair`, `fault`, `run_end`) must all be there; the
//! setup-mode records (`settings`, `live`, `reply`) and the fields the schema marks as not
//! required (the calibration fields `run_start` gained with setup mode, the run records'
//! `crc`) are read when present, so an ELF built before them still decodes.

use super::Entry;
use crate::error::{ElfError, LayoutError};
use defmt_parser::{Fragment, ParserMode, Type};
use std::collections::HashMap;

pub use capstan_wire::{Prim, RecordKind};

/// The wire type of a format parameter, if it is one the records use.
fn prim_of(ty: &Type) -> Option<Prim> {
    Some(match ty {
        Type::U8 => Prim::U8,
        Type::U16 => Prim::U16,
        Type::U32 => Prim::U32,
        Type::I64 => Prim::I64,
        Type::F32 => Prim::F32,
        _ => return None,
    })
}

/// Where each field of one record kind sits among the format's parameters.
#[derive(Clone, Debug)]
pub struct RecordLayout {
    /// Which record.
    pub kind: RecordKind,
    /// Field names in parameter order, with their types (only primitive types are allowed).
    pub fields: Vec<(String, Prim)>,
}

impl RecordLayout {
    /// Position of a field among the parameters.
    pub fn position(&self, name: &str) -> Option<usize> {
        self.fields.iter().position(|(n, _)| n == name)
    }
}

/// A record format: `WORD name={=type} name={=type} ...` → its kind and fields.
pub(crate) fn record_layout(format: &str) -> Option<Result<RecordLayout, LayoutError>> {
    let kind = RecordKind::from_word(format.split(' ').next()?)?;
    if !format.starts_with(&format!("{} seq=", kind.word())) {
        return None;
    }
    let fragments = match defmt_parser::parse(format, ParserMode::Strict) {
        Ok(f) => f,
        Err(e) => return Some(Err(LayoutError::Unparsable(e.to_string()))),
    };
    let mut fields = Vec::new();
    let mut name = String::new();
    for f in fragments {
        match f {
            Fragment::Literal(lit) => {
                name = lit
                    .rsplit(' ')
                    .next()
                    .unwrap_or("")
                    .trim_end_matches('=')
                    .to_string();
            }
            Fragment::Parameter(p) => {
                let Some(prim) = prim_of(&p.ty).filter(|_| p.hint.is_none()) else {
                    return Some(Err(LayoutError::FieldType(name)));
                };
                if p.index != fields.len() {
                    return Some(Err(LayoutError::OutOfOrder));
                }
                fields.push((std::mem::take(&mut name), prim));
            }
        }
    }
    let layout = RecordLayout { kind, fields };
    for field in kind.fields() {
        match layout.fields.iter().find(|(n, _)| n == field.name) {
            None if field.required => return Some(Err(LayoutError::NoField(field.name))),
            Some((_, t)) if *t != field.prim => {
                return Some(Err(LayoutError::WrongType {
                    field: field.name,
                    found: *t,
                    expected: field.prim,
                }))
            }
            _ => {}
        }
    }
    Some(Ok(layout))
}

pub(super) fn find_records(
    entries: &HashMap<u64, Entry>,
    path: &str,
) -> Result<HashMap<u64, RecordLayout>, ElfError> {
    let mut records = HashMap::new();
    for (&index, e) in entries {
        if !e.has_level() {
            continue;
        }
        match record_layout(&e.format) {
            None => {}
            Some(Ok(layout)) => {
                records.insert(index, layout);
            }
            Some(Err(why)) => {
                return Err(ElfError::Record {
                    path: path.to_string(),
                    word: e.format.split(' ').next().unwrap_or("").to_string(),
                    why,
                    format: e.format.clone(),
                })
            }
        }
    }
    let missing: Vec<&str> = RecordKind::RUN_KINDS
        .into_iter()
        .filter(|k| !records.values().any(|l| l.kind == *k))
        .map(|k| k.word())
        .collect();
    if missing.len() == RecordKind::RUN_KINDS.len() {
        return Err(ElfError::NotRig {
            path: path.to_string(),
        });
    }
    if !missing.is_empty() {
        return Err(ElfError::MissingRecords {
            path: path.to_string(),
            missing,
        });
    }
    Ok(records)
}
