//! The log records, defined once: each kind's leading word, log level and fields (name, wire
//! type, unit), in order. From this the firmware's build makes the defmt format strings (defmt
//! needs literals: `firmware/rig/build.rs` writes a macro per record), and the host reads the
//! records by the same table.
//!
//! A record's format string is `WORD name={=type} name={=type} ...`; the first field is always
//! `seq` (the sequence number since boot) and the last `crc` (the CRC-32 of every field before
//! it, each little-endian at its wire width, `seq` included).

use crate::settings::{Setting, Since};
use crate::Prim;
use core::fmt;

/// One field of a record.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Field {
    /// Its name in the format string.
    pub name: &'static str,
    /// Its wire type.
    pub prim: Prim,
    /// Its unit (empty for counts of things, codes and the checksum).
    pub unit: &'static str,
    /// The host refuses a firmware whose record lacks it; `false`: a firmware built before the
    /// field existed is still read (the field's default is used).
    pub required: bool,
}

const fn field(name: &'static str, prim: Prim, unit: &'static str) -> Part {
    Part::Field(Field {
        name,
        prim,
        unit,
        required: true,
    })
}

/// A piece of a record's field list.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    /// One field.
    Field(Field),
    /// Every setting, in wire order ([`Setting::ALL`]).
    Settings,
}

/// The log level a record is sent at.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Level {
    /// `info`
    Info,
    /// `warn`
    Warn,
}

impl Level {
    /// Its name (defmt's macro, the ELF's tag).
    pub const fn name(self) -> &'static str {
        match self {
            Level::Info => "info",
            Level::Warn => "warn",
        }
    }
}

/// The rig's record kinds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum RecordKind {
    /// A run begins (after its tare): the protocol and the calibration it runs with.
    RunStart,
    /// A decimated raw sample of a run.
    Raw,
    /// The conditioned pair of one step.
    Pair,
    /// A safety fault: the rig went to its safe state.
    Fault,
    /// A run is over.
    RunEnd,
    /// The settings in force and where they came from (at boot and on request; not part of a
    /// run).
    Settings,
    /// Live values in setup mode, ~10 a second.
    Live,
    /// The answer to a host command.
    Reply,
}

use Prim::{F32, I64, U16, U32, U8};

const SEQ: Part = field("seq", U32, "");
/// The run records' checksum: a firmware built before it is still read.
const CRC_SINCE_LATER: Part = Part::Field(Field {
    name: "crc",
    prim: U32,
    unit: "",
    required: false,
});
const CRC: Part = field("crc", U32, "");
/// The T2 target of force control (issue 43), in the run records: 0 when there is none (the
/// protocol's runs, a force run's rest). A firmware built before it is still read (0).
const T2_TARGET: Part = Part::Field(Field {
    name: "t2_target_n",
    prim: F32,
    unit: "N",
    required: false,
});

const RUN_START: &[Part] = &[SEQ, field("run", U32, ""), Part::Settings, CRC_SINCE_LATER];
const SETTINGS: &[Part] = &[SEQ, field("source", U8, ""), Part::Settings, CRC];
const RAW: &[Part] = &[
    SEQ,
    field("t_us", I64, "µs"),
    field("c1", U16, "counts"),
    field("c2", U16, "counts"),
    field("t1_n", F32, "N"),
    field("t2_n", F32, "N"),
    T2_TARGET,
    CRC_SINCE_LATER,
];
const PAIR: &[Part] = &[
    SEQ,
    field("step", U32, ""),
    field("level", U32, ""),
    field("angle_deg", F32, "°"),
    field("t_mid_ms", U32, "ms"),
    field("t1_mean_n", F32, "N"),
    field("t1_std_n", F32, "N"),
    field("t1_count", U32, ""),
    field("t2_mean_n", F32, "N"),
    field("t2_std_n", F32, "N"),
    field("t2_count", U32, ""),
    T2_TARGET,
    CRC_SINCE_LATER,
];
const FAULT: &[Part] = &[
    SEQ,
    field("kind", U8, ""),
    field("channel", U8, ""),
    // N for force faults, counts for rail faults, ms for the watchdog.
    field("value", F32, ""),
    field("t_us", I64, "µs"),
    CRC_SINCE_LATER,
];
const RUN_END: &[Part] = &[
    SEQ,
    field("t_us", I64, "µs"),
    field("pairs", U32, ""),
    field("fault", U8, ""),
    CRC_SINCE_LATER,
];
const LIVE: &[Part] = &[
    SEQ,
    field("t_ms", U32, "ms"),
    field("c1", U16, "counts"),
    field("c2", U16, "counts"),
    field("t1_n", F32, "N"),
    field("t2_n", F32, "N"),
    field("servo_deg", F32, "°"),
    CRC,
];
const REPLY: &[Part] = &[
    SEQ,
    field("command", U8, ""),
    field("error", U8, ""),
    field("v1", F32, ""),
    field("v2", F32, ""),
    CRC,
];

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

    /// The kind of a leading word.
    pub fn from_word(word: &str) -> Option<RecordKind> {
        RecordKind::ALL.into_iter().find(|k| k.word() == word)
    }

    /// The level it is logged at (a fault is a warning).
    pub const fn level(self) -> Level {
        match self {
            RecordKind::Fault => Level::Warn,
            _ => Level::Info,
        }
    }

    /// Its fields, as pieces: leading fields, the settings, `crc`.
    pub const fn parts(self) -> &'static [Part] {
        match self {
            RecordKind::RunStart => RUN_START,
            RecordKind::Settings => SETTINGS,
            RecordKind::Raw => RAW,
            RecordKind::Pair => PAIR,
            RecordKind::Fault => FAULT,
            RecordKind::RunEnd => RUN_END,
            RecordKind::Live => LIVE,
            RecordKind::Reply => REPLY,
        }
    }

    /// Its fields in order, the settings spelled out.
    pub fn fields(self) -> impl Iterator<Item = Field> + Clone {
        self.parts().iter().flat_map(move |part| {
            let (one, settings) = match *part {
                Part::Field(f) => (Some(f), &[][..]),
                Part::Settings => (None, &Setting::ALL[..]),
            };
            one.into_iter()
                .chain(settings.iter().map(move |&s| self.setting_field(s)))
        })
    }

    /// A setting as a field of this record: required in `settings` unless it came with force
    /// control or the calibration's provenance (an older firmware lacks them), in `run_start`
    /// only if the first firmware had it.
    pub const fn setting_field(self, s: Setting) -> Field {
        let required = match s.since() {
            Since::First => true,
            Since::SetupMode => matches!(self, RecordKind::Settings),
            Since::ForceControl | Since::Provenance => false,
        };
        Field {
            name: s.name(),
            prim: s.value().prim(),
            unit: s.unit(),
            required,
        }
    }

    /// Its format string: `WORD name={=type} ...` (displayed).
    pub const fn format(self) -> Format {
        Format(self)
    }
}

/// A record's defmt format string, written by [`fmt::Display`].
#[derive(Clone, Copy, Debug)]
pub struct Format(RecordKind);

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.0.word())?;
        for field in self.0.fields() {
            write!(f, " {}={{={}}}", field.name, field.prim.name())?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_are_the_wire_format() {
        assert_eq!(
            RecordKind::Raw.format().to_string(),
            "raw seq={=u32} t_us={=i64} c1={=u16} c2={=u16} t1_n={=f32} t2_n={=f32} t2_target_n={=f32} crc={=u32}"
        );
        assert_eq!(
            RecordKind::RunEnd.format().to_string(),
            "run_end seq={=u32} t_us={=i64} pairs={=u32} fault={=u8} crc={=u32}"
        );
        let settings = RecordKind::Settings.format().to_string();
        assert!(settings.starts_with(
            "settings seq={=u32} source={=u8} order={=u8} rest_deg={=f32} step_deg={=f32} final_deg={=f32} dwell_ms={=u32}"
        ));
        assert!(settings.contains("servo_max_deg={=f32} amp_full_scale_v={=f32} mode={=u8}"));
        assert!(settings.ends_with(
            "model_exponent={=f32} t1_cal={=u8} t1_cal_zero={=f32} t2_cal={=u8} t2_cal_zero={=f32} crc={=u32}"
        ));
    }

    #[test]
    fn every_record_leads_with_seq_and_ends_with_its_checksum() {
        for k in RecordKind::ALL {
            let fields: std::vec::Vec<Field> = k.fields().collect();
            assert_eq!(fields[0].name, "seq");
            assert_eq!(fields.last().map(|f| f.name), Some("crc"));
            for (i, f) in fields.iter().enumerate() {
                assert!(fields[..i].iter().all(|g| g.name != f.name), "{}", f.name);
            }
            assert_eq!(RecordKind::from_word(k.word()), Some(k));
        }
        assert_eq!(RecordKind::RunStart.fields().count(), 2 + 47 + 1);
        let optional: std::vec::Vec<&str> = RecordKind::RunStart
            .fields()
            .filter(|f| !f.required)
            .map(|f| f.name)
            .collect();
        assert_eq!(
            optional,
            [
                "tare_reference_n",
                "servo_min_us",
                "servo_max_us",
                "servo_max_deg",
                "amp_full_scale_v",
                "mode",
                "force_profile",
                "force_level1_n",
                "force_level2_n",
                "force_level3_n",
                "force_level4_n",
                "force_sine_hz",
                "force_sine_to_hz",
                "force_sine_steps",
                "force_kp",
                "force_ki",
                "force_t1_gain",
                "force_rate_deg_s",
                "force_shape_ms",
                "model_mu",
                "model_heat_per_n",
                "model_t2_offset_n",
                "model_exponent",
                "t1_cal",
                "t1_cal_zero",
                "t2_cal",
                "t2_cal_zero",
                "crc"
            ]
        );
    }
}
