//! The rig's records as the firmware's defmt table declares them: the record kinds, found by
//! the leading word of their format string (`firmware/src/defmt_sink.rs`), each
//! `WORD name={=type} name={=type} ...`, so fields are read by name and type; and the check,
//! when the ELF is loaded, that every record has the fields this decoder needs.

use super::Entry;
use anyhow::bail;
use defmt_parser::{Fragment, ParserMode, Type};
use std::collections::HashMap;

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

pub(super) fn find_records(
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
