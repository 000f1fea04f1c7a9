//! The firmware's side of the wire: its defmt table, read from the ELF, and the layout of each
//! rig record in it.
//!
//! defmt-decoder's [`Table`] decodes every frame. Around it this module keeps its own view of
//! the same `.defmt` symbols, for two things the table does not offer:
//!
//! - the rig records, found by their format strings (`firmware/src/defmt_sink.rs`): each is
//!   `WORD name={=type} name={=type} ...`, so fields are read by name and type, and an ELF whose
//!   records lack a field this decoder needs is refused when it is loaded, not mid-run;
//! - a bounds check of every frame before it reaches the table. defmt-decoder trusts the bytes
//!   it is given: a garbage slice length makes it reserve gigabytes (an abort, not a panic), a
//!   deep nesting of `{=?}` can overflow the stack. [`Firmware::check_frame`] walks the frame
//!   with the same rules, without allocating, and refuses what would be dangerous or wrong.

use anyhow::{anyhow, bail, Context};
use defmt_decoder::{Encoding, Table};
use defmt_parser::{Fragment, Parameter, ParserMode, Type};
use object::{Object, ObjectSection, ObjectSymbol};
use std::collections::HashMap;
use std::ops::Range;
use std::panic::AssertUnwindSafe;
use std::path::Path;

/// The rig's record kinds, by the leading word of their format string.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum RecordKind {
    /// `run_start`
    RunStart,
    /// `raw`
    Raw,
    /// `pair`
    Pair,
    /// `fault`
    Fault,
    /// `run_end`
    RunEnd,
}

impl RecordKind {
    /// All kinds.
    pub const ALL: [RecordKind; 5] = [
        RecordKind::RunStart,
        RecordKind::Raw,
        RecordKind::Pair,
        RecordKind::Fault,
        RecordKind::RunEnd,
    ];

    /// The leading word of the format string.
    pub const fn word(self) -> &'static str {
        match self {
            RecordKind::RunStart => "run_start",
            RecordKind::Raw => "raw",
            RecordKind::Pair => "pair",
            RecordKind::Fault => "fault",
            RecordKind::RunEnd => "run_end",
        }
    }

    fn from_word(word: &str) -> Option<RecordKind> {
        RecordKind::ALL.into_iter().find(|k| k.word() == word)
    }

    /// The fields this decoder needs, with their wire types.
    pub fn required_fields(self) -> &'static [(&'static str, Prim)] {
        use Prim::*;
        match self {
            RecordKind::RunStart => &[
                ("seq", U32),
                ("run", U32),
                ("order", U8),
                ("rest_deg", F32),
                ("step_deg", F32),
                ("final_deg", F32),
                ("dwell_ms", U32),
                ("pre_trigger_ms", U32),
                ("trigger_ms", U32),
                ("tare_ms", U32),
                ("amp_control_v", F32),
                ("sample_hz", U32),
                ("raw_log_hz", U32),
                ("window_after_ms", U32),
                ("window_before_ms", U32),
                ("diameter_mm", F32),
                ("wrap_deg", F32),
                ("amp_gain", F32),
                ("t1_zero", F32),
                ("t1_n_per_count", F32),
                ("t2_zero", F32),
                ("t2_n_per_count", F32),
            ],
            RecordKind::Raw => &[
                ("seq", U32),
                ("t_us", I64),
                ("c1", U16),
                ("c2", U16),
                ("t1_n", F32),
                ("t2_n", F32),
            ],
            RecordKind::Pair => &[
                ("seq", U32),
                ("step", U32),
                ("level", U32),
                ("angle_deg", F32),
                ("t_mid_ms", U32),
                ("t1_mean_n", F32),
                ("t1_std_n", F32),
                ("t1_count", U32),
                ("t2_mean_n", F32),
                ("t2_std_n", F32),
                ("t2_count", U32),
            ],
            RecordKind::Fault => &[
                ("seq", U32),
                ("kind", U8),
                ("channel", U8),
                ("value", F32),
                ("t_us", I64),
            ],
            RecordKind::RunEnd => &[("seq", U32), ("t_us", I64), ("pairs", U32), ("fault", U8)],
        }
    }
}

/// The primitive wire types the records use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Prim {
    /// `{=u8}`
    U8,
    /// `{=u16}`
    U16,
    /// `{=u32}`
    U32,
    /// `{=i64}`
    I64,
    /// `{=f32}`
    F32,
}

impl Prim {
    fn of(ty: &Type) -> Option<Prim> {
        Some(match ty {
            Type::U8 => Prim::U8,
            Type::U16 => Prim::U16,
            Type::U32 => Prim::U32,
            Type::I64 => Prim::I64,
            Type::F32 => Prim::F32,
            _ => return None,
        })
    }
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

/// One `.defmt` symbol.
#[derive(Clone, Debug)]
struct Entry {
    /// defmt tag without the `defmt_` prefix (`info`, `derived`, `str`, ...).
    tag: String,
    /// The format string.
    format: String,
    /// Its parameters in decoding order, or why it cannot be decoded.
    params: Result<Vec<Parameter>, String>,
    /// For an enum format (`A|B({=u8})|C`): each variant's parameters.
    variants: Option<Vec<Result<Vec<Parameter>, String>>>,
}

impl Entry {
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
    timestamp: Option<Result<Vec<Parameter>, String>>,
    records: HashMap<u64, RecordLayout>,
}

/// Most elements a `{=[?]}` slice may claim in one frame (defmt-decoder reserves memory for
/// the claimed count before reading any element).
const MAX_SLICE_ELEMENTS: u64 = 4096;
/// Deepest nesting of formats inside formats.
const MAX_DEPTH: u32 = 24;
/// Most parameters decoded for one frame.
const MAX_STEPS: u32 = 20_000;
/// rzCOBS pads a frame with up to this many zero bytes.
pub const MAX_PADDING: usize = 7;

impl Firmware {
    /// Read an ELF from a file.
    pub fn load(path: &Path) -> anyhow::Result<Firmware> {
        let bytes = std::fs::read(path)
            .with_context(|| format!("cannot read the firmware ELF {}", path.display()))?;
        Firmware::from_elf_bytes(&bytes, &path.display().to_string())
    }

    /// Read an ELF from memory; `path` names it in messages.
    pub fn from_elf_bytes(elf: &[u8], path: &str) -> anyhow::Result<Firmware> {
        let parsed = std::panic::catch_unwind(AssertUnwindSafe(|| Table::parse(elf)));
        let table = match parsed {
            Err(_) => bail!("ELF {path}: defmt-decoder could not read it (it panicked)"),
            Ok(Err(e)) => bail!("ELF {path}: {e:#}"),
            Ok(Ok(None)) => bail!(
                "ELF {path} has no defmt table (no `.defmt` section): build the rig firmware \
                 with defmt and give the ELF cargo built (not a .bin/.uf2, not stripped)"
            ),
            Ok(Ok(Some(t))) => t,
        };
        if table.encoding() != Encoding::Rzcobs {
            bail!(
                "ELF {path}: the firmware uses defmt's `raw` encoding; `capstan log` needs the \
                 default rzcobs encoding, which lets a lost byte cost one record instead of the \
                 rest of the stream"
            );
        }
        let file = object::File::parse(elf).map_err(|e| anyhow!("ELF {path}: {e}"))?;
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
            let variants = raw
                .data
                .contains('|')
                .then(|| raw.data.split('|').map(prepared_params).collect());
            entries.insert(
                sym.address(),
                Entry {
                    tag: tag.to_string(),
                    params: prepared_params(&raw.data),
                    format: raw.data,
                    variants,
                },
            );
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

    /// The defmt table (defmt-decoder's).
    pub fn table(&self) -> &Table {
        &self.table
    }

    /// The record layout for a format index, if it is a rig record.
    pub fn record_layout(&self, index: u64) -> Option<&RecordLayout> {
        self.records.get(&index)
    }

    /// The format string of an index, if the table has it.
    pub fn format_of(&self, index: u64) -> Option<&str> {
        self.entries.get(&index).map(|e| e.format.as_str())
    }

    /// Check that a decoded (de-rzCOBSed) frame is well-formed for this table, the way
    /// defmt-decoder will read it, without trusting any count in it. Returns the format index.
    pub fn check_frame(&self, frame: &[u8]) -> Result<u64, String> {
        let mut cur = Cursor {
            bytes: frame,
            pos: 0,
            steps: 0,
        };
        let index = cur
            .read(2)
            .map_err(|_| "frame shorter than its 2-byte index".to_string())?;
        let index = u16::from_le_bytes([index[0], index[1]]) as u64;
        if let Some(ts) = &self.timestamp {
            let ts = ts.as_ref().map_err(|e| format!("timestamp format: {e}"))?;
            self.walk(ts, &mut cur, 0)
                .map_err(|e| format!("timestamp: {e}"))?;
        }
        let entry = self
            .entries
            .get(&index)
            .ok_or_else(|| format!("format index {index} is not in the ELF's defmt table"))?;
        let params = entry
            .params
            .as_ref()
            .map_err(|e| format!("format index {index} cannot be decoded: {e}"))?;
        self.walk(params, &mut cur, 0)
            .map_err(|e| format!("`{}`: {e}", short(&entry.format)))?;
        let rest = &frame[cur.pos..];
        if rest.len() > MAX_PADDING || rest.iter().any(|&b| b != 0) {
            return Err(format!(
                "`{}`: {} bytes left over after the arguments",
                short(&entry.format),
                rest.len()
            ));
        }
        Ok(index)
    }

    fn nested(&self, cur: &mut Cursor) -> Result<&Entry, String> {
        let i = cur.u16()? as u64;
        match self.entries.get(&i) {
            Some(e) if !e.has_level() => Ok(e),
            Some(_) => Err(format!("nested format index {i} is a log statement")),
            None => Err(format!("nested format index {i} is not in the table")),
        }
    }

    /// The parameters of one variant of an enum format (or of a plain format).
    fn variant<'e>(&self, entry: &'e Entry, cur: &mut Cursor) -> Result<&'e [Parameter], String> {
        let Some(variants) = &entry.variants else {
            return entry.params.as_deref().map_err(Clone::clone);
        };
        // The discriminant is as wide as needed for the number of `|` (as defmt-decoder reads it).
        let bars = variants.len() - 1;
        let d = if bars <= u8::MAX as usize {
            cur.read(1)?[0] as usize
        } else if bars <= u16::MAX as usize {
            cur.u16()? as usize
        } else {
            return Err("enum with too many variants".into());
        };
        variants
            .get(d)
            .ok_or_else(|| format!("enum variant {d} out of range"))?
            .as_deref()
            .map_err(Clone::clone)
    }

    fn walk(&self, params: &[Parameter], cur: &mut Cursor, depth: u32) -> Result<(), String> {
        if depth > MAX_DEPTH {
            return Err("formats nested too deep".into());
        }
        for p in params {
            cur.steps += 1;
            if cur.steps > MAX_STEPS {
                return Err("too many arguments".into());
            }
            match &p.ty {
                Type::Bool => {
                    if cur.read(1)?[0] > 1 {
                        return Err("bool is neither 0 nor 1".into());
                    }
                }
                Type::U8 | Type::I8 => cur.skip(1)?,
                Type::U16 | Type::I16 => cur.skip(2)?,
                Type::U32 | Type::I32 | Type::Usize | Type::Isize | Type::F32 => cur.skip(4)?,
                Type::U64 | Type::I64 | Type::F64 => cur.skip(8)?,
                Type::U128 | Type::I128 => cur.skip(16)?,
                Type::Char => {
                    let c = cur.u32()?;
                    if char::from_u32(c).is_none() {
                        return Err(format!("{c:#x} is not a char"));
                    }
                }
                Type::BitField(r) => cur.skip(bitfield_bytes(r)?)?,
                Type::Str => {
                    let n = cur.u32()? as usize;
                    let s = cur.read(n)?;
                    if std::str::from_utf8(s).is_err() {
                        return Err("string is not UTF-8".into());
                    }
                }
                Type::U8Slice => {
                    let n = cur.u32()? as usize;
                    cur.skip(n)?
                }
                Type::U8Array(n) => cur.skip(*n)?,
                Type::IStr => {
                    self.nested(cur)?;
                }
                Type::Debug | Type::Display => {
                    let rest = &cur.bytes[cur.pos..];
                    let end = rest
                        .iter()
                        .position(|&b| b == 0xff)
                        .ok_or("unterminated preformatted string")?;
                    if std::str::from_utf8(&rest[..end]).is_err() {
                        return Err("preformatted string is not UTF-8".into());
                    }
                    cur.pos += end + 1;
                }
                Type::Format => {
                    let entry = self.nested(cur)?;
                    let inner = self.variant(entry, cur)?;
                    self.walk(inner, cur, depth + 1)?;
                }
                Type::FormatSlice | Type::FormatArray(_) => {
                    let n = match p.ty {
                        Type::FormatArray(n) => n as u64,
                        _ => cur.u32()? as u64,
                    };
                    if n > MAX_SLICE_ELEMENTS {
                        return Err(format!("slice of {n} elements"));
                    }
                    let entry = self.nested(cur)?;
                    for _ in 0..n {
                        let inner = self.variant(entry, cur)?;
                        self.walk(inner, cur, depth + 1)?;
                    }
                }
                Type::FormatSequence => loop {
                    let i = cur.u16()? as u64;
                    if i == 0 {
                        break;
                    }
                    let entry = match self.entries.get(&i) {
                        Some(e) if !e.has_level() => e,
                        _ => return Err(format!("sequence element index {i} is not a format")),
                    };
                    let inner = entry.params.as_deref().map_err(Clone::clone)?;
                    self.walk(inner, cur, depth + 1)?;
                },
            }
        }
        Ok(())
    }
}

#[derive(serde::Deserialize)]
struct RawSymbol {
    tag: String,
    data: String,
}

struct Cursor<'a> {
    bytes: &'a [u8],
    pos: usize,
    steps: u32,
}

impl<'a> Cursor<'a> {
    fn read(&mut self, n: usize) -> Result<&'a [u8], String> {
        let end = self
            .pos
            .checked_add(n)
            .filter(|&e| e <= self.bytes.len())
            .ok_or_else(|| "frame ends inside an argument".to_string())?;
        let s = &self.bytes[self.pos..end];
        self.pos = end;
        Ok(s)
    }

    fn skip(&mut self, n: usize) -> Result<(), String> {
        self.read(n).map(|_| ())
    }

    fn u16(&mut self) -> Result<u16, String> {
        let b = self.read(2)?;
        Ok(u16::from_le_bytes([b[0], b[1]]))
    }

    fn u32(&mut self) -> Result<u32, String> {
        let b = self.read(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }
}

fn bitfield_bytes(r: &Range<u8>) -> Result<usize, String> {
    if r.end <= r.start || r.end > 128 {
        return Err("bad bitfield range".into());
    }
    Ok(match (r.end - 1) / 8 - r.start / 8 + 1 {
        1 => 1,
        2 => 2,
        3..=4 => 4,
        5..=8 => 8,
        _ => 16,
    })
}

/// A format's parameters as defmt-decoder consumes them: bitfields of one argument merged,
/// then one parameter per argument index, in index order.
fn prepared_params(format: &str) -> Result<Vec<Parameter>, String> {
    let fragments = defmt_parser::parse(format, ParserMode::ForwardsCompatible)
        .map_err(|e| format!("unparsable format string: {e}"))?;
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

/// A record format: `WORD name={=type} name={=type} ...` → its kind and fields.
fn record_layout(format: &str) -> Option<Result<RecordLayout, String>> {
    let kind = RecordKind::from_word(format.split(' ').next()?)?;
    if !format.starts_with(&format!("{} seq=", kind.word())) {
        return None;
    }
    let fragments = match defmt_parser::parse(format, ParserMode::Strict) {
        Ok(f) => f,
        Err(e) => return Some(Err(format!("unparsable: {e}"))),
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
                let Some(prim) = Prim::of(&p.ty).filter(|_| p.hint.is_none()) else {
                    return Some(Err(format!(
                        "field `{name}` has a type this decoder cannot read"
                    )));
                };
                if p.index != fields.len() {
                    return Some(Err("arguments out of order".into()));
                }
                fields.push((std::mem::take(&mut name), prim));
            }
        }
    }
    let layout = RecordLayout { kind, fields };
    for (need, ty) in kind.required_fields() {
        match layout.fields.iter().find(|(n, _)| n == need) {
            None => return Some(Err(format!("no field `{need}`"))),
            Some((_, t)) if t != ty => {
                return Some(Err(format!("field `{need}` is {t:?}, expected {ty:?}")))
            }
            Some(_) => {}
        }
    }
    Some(Ok(layout))
}

fn find_records(
    entries: &HashMap<u64, Entry>,
    path: &str,
) -> anyhow::Result<HashMap<u64, RecordLayout>> {
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
            Some(Err(why)) => bail!(
                "ELF {path}: its `{}` record does not match this decoder ({why}); format: \"{}\". \
                 Rebuild `capstan` from the same source as the firmware.",
                e.format.split(' ').next().unwrap_or(""),
                e.format
            ),
        }
    }
    let missing: Vec<&str> = RecordKind::ALL
        .into_iter()
        .filter(|k| !records.values().any(|l| l.kind == *k))
        .map(|k| k.word())
        .collect();
    if missing.len() == RecordKind::ALL.len() {
        bail!(
            "ELF {path} is not the capstan rig firmware: its defmt table has none of the rig's \
             records (run_start, raw, pair, fault, run_end)"
        );
    }
    if !missing.is_empty() {
        bail!(
            "ELF {path}: the defmt table lacks the rig record(s) {}: is it an older or newer \
             firmware than this `capstan`?",
            missing.join(", ")
        );
    }
    Ok(records)
}

/// A format string cut for messages.
pub fn short(format: &str) -> String {
    if format.chars().count() <= 48 {
        format.to_string()
    } else {
        format!("{}...", format.chars().take(45).collect::<String>())
    }
}
