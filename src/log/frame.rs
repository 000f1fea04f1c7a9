//! From a frame to an event: an rzCOBS-decoded, pre-validated frame decoded with the
//! firmware's defmt table (defmt-decoder) into a rig record, its fields read by name from the
//! record's format (`elf::RecordLayout`), or into a text message.

use super::elf::{Firmware, Prim, RecordKind, RecordLayout};
use super::stream::rzcobs_decode;
use defmt_parser::Fragment;
use firmware::calib::{AmpMap, Calibration, ChannelCal};
use firmware::condition::ChannelStats;
use firmware::hal::Channel;
use firmware::record::{
    CrcFields, Fault, FaultKind, RawSample, Record, RunEnd, RunStart, StepPair,
};
use firmware::{Protocol, StepOrder};
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

/// Decode one encoded frame. The error says what is wrong with it (not where: the caller
/// knows the frame number and offset).
pub fn decode_frame(fw: &Firmware, encoded: &[u8]) -> Result<Event, String> {
    let bytes = rzcobs_decode(encoded).map_err(|e| format!("not rzCOBS: {e}"))?;
    let index = fw.check_frame(&bytes)?;
    type Decoded = Result<Result<Event, Vec<String>>, String>;
    let decoded = std::panic::catch_unwind(AssertUnwindSafe(|| -> Decoded {
        let (frame, _) = fw.table().decode(&bytes).map_err(|e| e.to_string())?;
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
        Err(_) => Err("defmt-decoder panicked on this frame".into()),
        Ok(Err(e)) => Err(format!("defmt-decoder: {e}")),
        Ok(Ok(Ok(message))) => Ok(message),
        Ok(Ok(Err(values))) => {
            let layout = fw.record_layout(index).expect("checked above");
            record_from_values(layout, &values)
        }
    }
}

/// Field values of one record, by name.
struct Fields<'a> {
    layout: &'a RecordLayout,
    values: &'a [String],
}

impl Fields<'_> {
    fn raw(&self, name: &str) -> Result<&str, String> {
        let i = self
            .layout
            .position(name)
            .ok_or_else(|| format!("no field `{name}`"))?;
        self.values
            .get(i)
            .map(String::as_str)
            .ok_or_else(|| format!("field `{name}` missing from the frame"))
    }

    fn u(&self, name: &str) -> Result<u32, String> {
        let v = self.raw(name)?;
        v.parse()
            .map_err(|_| format!("field `{name}`: `{v}` is not an unsigned integer"))
    }

    fn u8(&self, name: &str) -> Result<u8, String> {
        let v = self.u(name)?;
        u8::try_from(v).map_err(|_| format!("field `{name}`: {v} does not fit a byte"))
    }

    fn i64(&self, name: &str) -> Result<i64, String> {
        let v = self.raw(name)?;
        v.parse()
            .map_err(|_| format!("field `{name}`: `{v}` is not an integer"))
    }

    fn f32(&self, name: &str) -> Result<f32, String> {
        let v = self.raw(name)?;
        v.parse()
            .map_err(|_| format!("field `{name}`: `{v}` is not a number"))
    }
}

fn record_from_values(layout: &RecordLayout, values: &[String]) -> Result<Event, String> {
    if values.len() != layout.fields.len() {
        return Err(format!(
            "`{}` record with {} values for {} fields",
            layout.kind.word(),
            values.len(),
            layout.fields.len()
        ));
    }
    debug_assert!(layout
        .fields
        .iter()
        .all(|(_, p)| matches!(p, Prim::U8 | Prim::U16 | Prim::U32 | Prim::I64 | Prim::F32)));
    let f = Fields { layout, values };
    let seq = f.u("seq")?;
    let word = layout.kind.word();
    check_crc(layout, values).map_err(|e| format!("`{word}` record seq {seq}: {e}"))?;
    let record = build(layout.kind, &f).map_err(|e| format!("`{word}` record seq {seq}: {e}"))?;
    Ok(Event::Record { seq, record })
}

/// The record's `crc` field (firmware since the records carry one) against the CRC-32 of its
/// other fields as received (`firmware::record::CrcFields`, the firmware's own code): a
/// mismatch is a corrupted record, refused rather than decoded into wrong numbers. Records of
/// a firmware without the field are not checked (`Firmware::records_checked` says which).
fn check_crc(layout: &RecordLayout, values: &[String]) -> Result<(), String> {
    let Some(at) = layout.position("crc") else {
        return Ok(());
    };
    let bad = |name: &str, v: &str| format!("field `{name}`: `{v}` is not its type");
    let mut c = CrcFields::new();
    for ((name, prim), v) in layout
        .fields
        .iter()
        .zip(values)
        .filter(|((n, _), _)| n != "crc")
    {
        c = match prim {
            Prim::U8 => c.u8(v.parse().map_err(|_| bad(name, v))?),
            Prim::U16 => c.u16(v.parse().map_err(|_| bad(name, v))?),
            Prim::U32 => c.u32(v.parse().map_err(|_| bad(name, v))?),
            Prim::I64 => c.i64(v.parse().map_err(|_| bad(name, v))?),
            Prim::F32 => c.f32(v.parse().map_err(|_| bad(name, v))?),
        };
    }
    let sent: u32 = values[at].parse().map_err(|_| bad("crc", &values[at]))?;
    let got = c.finish();
    if sent != got {
        return Err(format!(
            "checksum mismatch (sent {sent:#010x}, computed {got:#010x}): the record was \
             corrupted on its way"
        ));
    }
    Ok(())
}

fn build(kind: RecordKind, f: &Fields) -> Result<Record, String> {
    Ok(match kind {
        RecordKind::RunStart => {
            let order = f.u8("order")?;
            let protocol = Protocol {
                rest_deg: f.f32("rest_deg")?,
                step_deg: f.f32("step_deg")?,
                final_deg: f.f32("final_deg")?,
                order: StepOrder::from_code(order)
                    .ok_or_else(|| format!("unknown step order code {order}"))?,
                dwell_ms: f.u("dwell_ms")?,
                pre_trigger_ms: f.u("pre_trigger_ms")?,
                trigger_ms: f.u("trigger_ms")?,
                tare_ms: f.u("tare_ms")?,
                amp_control_v: f.f32("amp_control_v")?,
                sample_hz: f.u("sample_hz")?,
                raw_log_hz: f.u("raw_log_hz")?,
                window_after_change_ms: f.u("window_after_ms")?,
                window_before_next_ms: f.u("window_before_ms")?,
                capstan_diameter_mm: f.f32("diameter_mm")?,
                wrap_deg: f.f32("wrap_deg")?,
            };
            // The record carries what the log needs; the rest of the calibration (servo map,
            // amplifier full scale, tare reference) stays at its defaults.
            let calibration = Calibration {
                t1: ChannelCal {
                    zero_counts: f.f32("t1_zero")?,
                    n_per_count: f.f32("t1_n_per_count")?,
                },
                t2: ChannelCal {
                    zero_counts: f.f32("t2_zero")?,
                    n_per_count: f.f32("t2_n_per_count")?,
                },
                amp: AmpMap {
                    amp_gain: f.f32("amp_gain")?,
                    ..AmpMap::default()
                },
                ..Calibration::default()
            };
            Record::RunStart(RunStart {
                run: f.u("run")?,
                protocol,
                calibration,
            })
        }
        RecordKind::Raw => Record::Raw(RawSample {
            t_us: f.i64("t_us")?,
            counts: [f.u("c1")? as u16, f.u("c2")? as u16],
            force_n: [f.f32("t1_n")?, f.f32("t2_n")?],
        }),
        RecordKind::Pair => Record::Pair(StepPair {
            step: f.u("step")?,
            level: f.u("level")?,
            angle_deg: f.f32("angle_deg")?,
            t_mid_ms: f.u("t_mid_ms")?,
            t1: ChannelStats {
                mean_n: f.f32("t1_mean_n")?,
                std_n: f.f32("t1_std_n")?,
                count: f.u("t1_count")?,
            },
            t2: ChannelStats {
                mean_n: f.f32("t2_mean_n")?,
                std_n: f.f32("t2_std_n")?,
                count: f.u("t2_count")?,
            },
        }),
        RecordKind::Fault => {
            let code = f.u8("kind")?;
            Record::Fault(Fault {
                kind: FaultKind::from_code(code)
                    .ok_or_else(|| format!("unknown fault kind code {code}"))?,
                channel: channel(f.u8("channel")?)?,
                value: f.f32("value")?,
                t_us: f.i64("t_us")?,
            })
        }
        RecordKind::RunEnd => {
            let code = f.u8("fault")?;
            Record::RunEnd(RunEnd {
                t_us: f.i64("t_us")?,
                pairs: f.u("pairs")?,
                fault: match code {
                    NONE_CODE => None,
                    c => Some(
                        FaultKind::from_code(c)
                            .ok_or_else(|| format!("unknown fault kind code {c}"))?,
                    ),
                },
            })
        }
    })
}

pub use firmware::record::NONE_CODE;

fn channel(code: u8) -> Result<Option<Channel>, String> {
    match code {
        0 => Ok(Some(Channel::T1)),
        1 => Ok(Some(Channel::T2)),
        NONE_CODE => Ok(None),
        c => Err(format!("unknown channel code {c}")),
    }
}
