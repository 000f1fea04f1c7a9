//! The rig's records as the firmware's defmt table declares them: the record kinds, found by
//! the leading word of their format string (`firmware/src/defmt_sink.rs`), each
//! `WORD name={=type} name={=type} ...`, so fields are read by name and type; and the check,
//! when the ELF is loaded, that every record has the fields this decoder needs.
//!
//! The run records (`run_start`, `raw`, `pair`, `fault`, `run_end`) must all be there; the
//! setup-mode records (`settings`, `live`, `reply`) and the calibration fields `run_start`
//! gained with them are read when present, so an ELF built before them still decodes.

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
    /// `settings` (setup mode, at boot and on request: not part of a run)
    Settings,
    /// `live` (setup mode)
    Live,
    /// `reply` (the answer to a host command)
    Reply,
}

impl RecordKind {
    /// All kinds.
    pub const ALL: [RecordKind; 8] = [
        RecordKind::RunStart,
        RecordKind::Raw,
        RecordKind::Pair,
        RecordKind::Fault,
        RecordKind::RunEnd,
        RecordKind::Settings,
        RecordKind::Live,
        RecordKind::Reply,
    ];

    /// The kinds every rig firmware has: an ELF lacking one is refused. The setup-mode kinds
    /// (`settings`, `live`, `reply`) came later; an ELF without them still decodes.
    pub const RUN_KINDS: [RecordKind; 5] = [
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
            RecordKind::Settings => "settings",
            RecordKind::Live => "live",
            RecordKind::Reply => "reply",
        }
    }

    fn from_word(word: &str) -> Option<RecordKind> {
        RecordKind::ALL.into_iter().find(|k| k.word() == word)
    }

    /// The fields this decoder needs, with their wire types.
    pub fn required_fields(self) -> Vec<(&'static str, Prim)> {
        use Prim::*;
        let lead: &[(&str, Prim)] = match self {
            RecordKind::RunStart => &[("seq", U32), ("run", U32)],
            RecordKind::Settings => &[("seq", U32), ("source", U8)],
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
            RecordKind::Live => &[
                ("seq", U32),
                ("t_ms", U32),
                ("c1", U16),
                ("c2", U16),
                ("t1_n", F32),
                ("t2_n", F32),
                ("servo_deg", F32),
                ("crc", U32),
            ],
            RecordKind::Reply => &[
                ("seq", U32),
                ("command", U8),
                ("error", U8),
                ("v1", F32),
                ("v2", F32),
                ("crc", U32),
            ],
        };
        let mut fields = lead.to_vec();
        match self {
            RecordKind::RunStart => fields.extend_from_slice(SETTINGS_FIELDS),
            RecordKind::Settings => {
                fields.extend_from_slice(SETTINGS_FIELDS);
                fields.extend_from_slice(CALIBRATION_EXTRA_FIELDS);
                fields.push(("crc", U32));
            }
            _ => {}
        }
        fields
    }

    /// Fields read when the record has them (firmware built before them lacks them): checked
    /// for their type when present. `crc` of the run records is optional the same way.
    pub fn optional_fields(self) -> &'static [(&'static str, Prim)] {
        match self {
            RecordKind::RunStart => CALIBRATION_EXTRA_FIELDS,
            _ => &[],
        }
    }
}

/// The protocol and calibration fields `run_start` and `settings` share (after their leading
/// fields), in the firmware's order.
const SETTINGS_FIELDS: &[(&str, Prim)] = &[
    ("order", Prim::U8),
    ("rest_deg", Prim::F32),
    ("step_deg", Prim::F32),
    ("final_deg", Prim::F32),
    ("dwell_ms", Prim::U32),
    ("pre_trigger_ms", Prim::U32),
    ("trigger_ms", Prim::U32),
    ("tare_ms", Prim::U32),
    ("amp_control_v", Prim::F32),
    ("sample_hz", Prim::U32),
    ("raw_log_hz", Prim::U32),
    ("window_after_ms", Prim::U32),
    ("window_before_ms", Prim::U32),
    ("diameter_mm", Prim::F32),
    ("wrap_deg", Prim::F32),
    ("amp_gain", Prim::F32),
    ("t1_zero", Prim::F32),
    ("t1_n_per_count", Prim::F32),
    ("t2_zero", Prim::F32),
    ("t2_n_per_count", Prim::F32),
];

/// The rest of the calibration (tare reference, servo map, amplifier full scale): always in
/// `settings`, in `run_start` since setup mode.
const CALIBRATION_EXTRA_FIELDS: &[(&str, Prim)] = &[
    ("tare_reference_n", Prim::F32),
    ("servo_min_us", Prim::F32),
    ("servo_max_us", Prim::F32),
    ("servo_max_deg", Prim::F32),
    ("amp_full_scale_v", Prim::F32),
];

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
pub(crate) fn record_layout(format: &str) -> Option<Result<RecordLayout, String>> {
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
    let optional = kind
        .optional_fields()
        .iter()
        .chain(&[("crc", Prim::U32)])
        .map(|&(n, t)| (n, t, false));
    let required = kind
        .required_fields()
        .into_iter()
        .map(|(n, t)| (n, t, true));
    for (name, ty, needed) in required.chain(optional) {
        match layout.fields.iter().find(|(n, _)| n == name) {
            None if needed => return Some(Err(format!("no field `{name}`"))),
            Some((_, t)) if *t != ty => {
                return Some(Err(format!("field `{name}` is {t:?}, expected {ty:?}")))
            }
            _ => {}
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
    let missing: Vec<&str> = RecordKind::RUN_KINDS
        .into_iter()
        .filter(|k| !records.values().any(|l| l.kind == *k))
        .map(|k| k.word())
        .collect();
    if missing.len() == RecordKind::RUN_KINDS.len() {
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
