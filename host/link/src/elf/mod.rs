//! The firmware's side of the wire: its defmt table, read from the ELF, and the layout of each
//! rig record in it.
//!
//! defmt-decoder's [`Table`] decodes every frame. Around it this module keeps its own view of
//! the same `.defmt` symbols, for two things the table does not offer:
//!
//! - the rig records, found by their format strings (`firmware/rig/src/defmt_sink.rs`): each is
//!   `WORD name={=type} name={=type} ...`, so fields are read by name and type, and an ELF whose
//!   records lack a field this decoder needs is refused when it is loaded, not mid-run;
//! - a bounds check of every frame before it reaches the table. defmt-decoder trusts the bytes
//!   it is given: a garbage slice length makes it reserve gigabytes (an abort, not a panic), a
//!   deep nesting of `{=?}` can overflow the stack. [`Firmware::check_frame`] walks the frame
//!   with the same rules, without allocating, and refuses what would be dangerous or wrong.
//!
//! This file loads the table and indexes the `.defmt` symbols; `records` holds the rig
//! records' schema and its check, `check` the frame pre-validation.

mod check;
mod records;

pub use check::MAX_PADDING;
#[cfg(test)]
pub(crate) use records::record_layout;
pub use records::{Prim, RecordKind, RecordLayout};

use crate::error::{ElfError, FormatError};
use check::bitfield_bytes;
use defmt_decoder::{Encoding, Table};
use defmt_parser::{Fragment, Parameter, ParserMode, Type};
use object::{Object, ObjectSection, ObjectSymbol};
use records::find_records;
use std::collections::HashMap;
use std::io::Read;
use std::ops::Range;
use std::panic::AssertUnwindSafe;
use std::path::Path;

/// One `.defmt` symbol.
#[derive(Clone, Debug)]
struct Entry {
    /// defmt tag without the `defmt_` prefix (`info`, `derived`, `str`, ...).
    tag: String,
    /// The format string.
    format: String,
    /// Its parameters in decoding order, or why it cannot be decoded.
    params: Result<Vec<Parameter>, FormatError>,
    /// For an enum format (`A|B({=u8})|C`): each variant's parameters.
    variants: Option<Vec<Result<Vec<Parameter>, FormatError>>>,
}

impl Entry {
    fn new(tag: &str, format: String) -> Entry {
        let variants = format
            .contains('|')
            .then(|| format.split('|').map(prepared_params).collect());
        Entry {
            tag: tag.to_string(),
            params: prepared_params(&format),
            format,
            variants,
        }
    }

    /// True for log statements (they have a level); false for formats nested in arguments.
    fn has_level(&self) -> bool {
        matches!(
            self.tag.as_str(),
            "trace" | "debug" | "info" | "warn" | "error"
        )
    }
}

/// A loaded firmware ELF: its defmt table and the rig records in it.
pub struct Firmware {
    /// Where it was read from (for messages).
    pub path: String,
    table: Table,
    entries: HashMap<u64, Entry>,
    timestamp: Option<Result<Vec<Parameter>, FormatError>>,
    records: HashMap<u64, RecordLayout>,
}

impl Firmware {
    /// Read an ELF from a file.
    pub fn load(path: &Path) -> Result<Firmware, ElfError> {
        // Bounded: a firmware ELF with its debug info is a few MB; /dev/zero is not one.
        const MAX_ELF_BYTES: u64 = 256 << 20;
        let mut bytes = Vec::new();
        std::fs::File::open(path)
            .and_then(|f| f.take(MAX_ELF_BYTES + 1).read_to_end(&mut bytes))
            .map_err(|source| ElfError::Read {
                path: path.display().to_string(),
                source,
            })?;
        if bytes.len() as u64 > MAX_ELF_BYTES {
            return Err(ElfError::TooLarge {
                path: path.display().to_string(),
                mib: MAX_ELF_BYTES >> 20,
            });
        }
        Firmware::from_elf_bytes(&bytes, &path.display().to_string())
    }

    /// Read an ELF from memory; `path` names it in messages.
    pub fn from_elf_bytes(elf: &[u8], path: &str) -> Result<Firmware, ElfError> {
        let path_ = || path.to_string();
        let parsed = std::panic::catch_unwind(AssertUnwindSafe(|| Table::parse(elf)));
        let table = match parsed {
            Err(_) => return Err(ElfError::DecoderPanicked { path: path_() }),
            Ok(Err(e)) => {
                return Err(ElfError::Unreadable {
                    path: path_(),
                    why: format!("{e:#}"),
                })
            }
            Ok(Ok(None)) => return Err(ElfError::NoTable { path: path_() }),
            Ok(Ok(Some(t))) => t,
        };
        if table.encoding() != Encoding::Rzcobs {
            return Err(ElfError::RawEncoding { path: path_() });
        }
        let file = object::File::parse(elf).map_err(|e| ElfError::Unreadable {
            path: path_(),
            why: e.to_string(),
        })?;
        let sections: Vec<_> = file
            .sections()
            .filter(|s| {
                s.name()
                    .is_ok_and(|n| n == ".defmt" || n.starts_with(".defmt."))
            })
            .map(|s| s.index())
            .collect();
        let mut entries = HashMap::new();
        let mut timestamp = None;
        for sym in file.symbols() {
            let (Ok(name), Some(section)) = (sym.name(), sym.section_index()) else {
                continue;
            };
            if !sections.contains(&section) || !name.starts_with('{') {
                continue;
            }
            let Ok(raw) = serde_json::from_str::<RawSymbol>(name) else {
                continue;
            };
            let Some(tag) = raw.tag.strip_prefix("defmt_") else {
                continue;
            };
            if tag == "timestamp" {
                timestamp = Some(prepared_params(&raw.data));
                continue;
            }
            if tag == "bitflags_value" {
                continue;
            }
            entries.insert(sym.address(), Entry::new(tag, raw.data));
        }
        let records = find_records(&entries, path)?;
        Ok(Firmware {
            path: path.to_string(),
            table,
            entries,
            timestamp,
            records,
        })
    }

    /// A firmware known by its log statements alone, without an ELF: `(index, level, format)`
    /// each, `level` one of `trace`, `debug`, `info`, `warn`, `error`; no timestamp, rzCOBS
    /// encoding. For tests and tools that make a stream themselves (a frame is the index, u16
    /// little-endian, then the arguments at their wire widths). Checked like an ELF's table.
    pub fn from_formats(name: &str, formats: &[(u16, &str, &str)]) -> Result<Firmware, ElfError> {
        let mut json = serde_json::Map::new();
        let mut entries = HashMap::new();
        for &(index, level, format) in formats {
            let tag = match level {
                "trace" => "Trace",
                "debug" => "Debug",
                "info" => "Info",
                "warn" => "Warn",
                "error" => "Error",
                other => {
                    return Err(ElfError::Level {
                        path: name.to_string(),
                        level: other.to_string(),
                    })
                }
            };
            let entry = serde_json::json!({
                "string": { "tag": tag, "string": format },
                "raw_symbol": format!("{{\"tag\":\"defmt_{level}\",\"data\":{format:?}}}"),
            });
            json.insert(index.to_string(), entry);
            entries.insert(index as u64, Entry::new(level, format.to_string()));
        }
        let table = serde_json::json!({
            "timestamp": null,
            "entries": json,
            "bitflags": {},
            "encoding": "Rzcobs",
        });
        let table: Table = serde_json::from_value(table).map_err(|why| ElfError::Table {
            path: name.to_string(),
            why,
        })?;
        let records = find_records(&entries, name)?;
        Ok(Firmware {
            path: name.to_string(),
            table,
            entries,
            timestamp: None,
            records,
        })
    }

    /// The defmt table (defmt-decoder's).
    pub fn table(&self) -> &Table {
        &self.table
    }

    /// The record layout for a format index, if it is a rig record.
    pub fn record_layout(&self, index: u64) -> Option<&RecordLayout> {
        self.records.get(&index)
    }

    /// Whether this firmware's records of `kind` carry the field `name` (an optional field,
    /// `RecordKind::optional_fields`, is decoded as its default when they do not).
    pub fn record_has_field(&self, kind: RecordKind, name: &str) -> bool {
        self.records
            .values()
            .any(|l| l.kind == kind && l.position(name).is_some())
    }

    /// The format string of an index, if the table has it.
    pub fn format_of(&self, index: u64) -> Option<&str> {
        self.entries.get(&index).map(|e| e.format.as_str())
    }
}

#[derive(serde::Deserialize)]
struct RawSymbol {
    tag: String,
    data: String,
}

/// A format's parameters as defmt-decoder consumes them: bitfields of one argument merged,
/// then one parameter per argument index, in index order.
fn prepared_params(format: &str) -> Result<Vec<Parameter>, FormatError> {
    let fragments = defmt_parser::parse(format, ParserMode::ForwardsCompatible)
        .map_err(|e| FormatError::Unparsable(e.to_string()))?;
    let mut params: Vec<Parameter> = fragments
        .into_iter()
        .filter_map(|f| match f {
            Fragment::Parameter(p) => Some(p),
            Fragment::Literal(_) => None,
        })
        .collect();
    let mut merged: Vec<Parameter> = Vec::new();
    let mut bitfields: Vec<(usize, Range<u8>)> = Vec::new();
    for p in params.drain(..) {
        if let Type::BitField(r) = &p.ty {
            match bitfields.iter_mut().find(|(i, _)| *i == p.index) {
                Some((_, range)) => {
                    range.start = range.start.min(r.start);
                    range.end = range.end.max(r.end);
                }
                None => bitfields.push((p.index, r.clone())),
            }
        } else {
            merged.push(p);
        }
    }
    for (index, r) in bitfields {
        bitfield_bytes(&r)?;
        merged.push(Parameter {
            index,
            ty: Type::BitField(r),
            hint: None,
        });
    }
    merged.sort_by_key(|p| p.index);
    merged.dedup_by_key(|p| p.index);
    Ok(merged)
}

/// A format string cut for messages.
pub fn short(format: &str) -> String {
    if format.chars().count() <= 48 {
        format.to_string()
    } else {
        format!("{}...", format.chars().take(45).collect::<String>())
    }
}
