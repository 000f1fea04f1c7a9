//! From bytes to frames to events: rzCOBS framing (each frame ends with a 0x00), with the frame
//! number and byte offset of every frame kept for messages, then decoding of each frame with
//! the firmware's defmt table into a rig record or a text message.

use super::elf::{Firmware, Prim, RecordKind, RecordLayout};
use defmt_parser::Fragment;
use firmware::calib::{AmpMap, Calibration, ChannelCal};
use firmware::condition::ChannelStats;
use firmware::hal::Channel;
use firmware::record::{Fault, FaultKind, RawSample, Record, RunEnd, RunStart, StepPair};
use firmware::{Protocol, StepOrder};
use std::panic::AssertUnwindSafe;

/// The longest encoded frame accepted, bytes. The rig's longest record (run_start) is under
/// 120; anything much longer is not a frame of ours (or two frames whose separator was lost).
pub const MAX_FRAME_BYTES: usize = 1024;

/// A frame cut from the stream, still rzCOBS-encoded.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RawFrame {
    /// Frame number in the stream, from 0.
    pub number: u64,
    /// Byte offset of its first byte in the stream.
    pub offset: u64,
    /// The encoded bytes (without the separator), or `None` if it was too long to keep.
    pub bytes: Option<Vec<u8>>,
    /// Its encoded length.
    pub len: u64,
}

/// Cuts a byte stream into frames at the 0x00 separators.
#[derive(Debug, Default)]
pub struct Deframer {
    buf: Vec<u8>,
    start: u64,
    pos: u64,
    len: u64,
    next_number: u64,
}

impl Deframer {
    /// A deframer at the start of a stream.
    pub fn new() -> Self {
        Deframer::default()
    }

    /// Bytes seen so far.
    pub fn bytes_seen(&self) -> u64 {
        self.pos
    }

    /// Feed bytes; complete frames are appended to `out`.
    pub fn push(&mut self, bytes: &[u8], out: &mut Vec<RawFrame>) {
        for &b in bytes {
            let at = self.pos;
            self.pos += 1;
            if b != 0 {
                if self.len == 0 {
                    self.start = at;
                }
                self.len += 1;
                if self.len as usize <= MAX_FRAME_BYTES {
                    self.buf.push(b);
                }
                continue;
            }
            if self.len == 0 {
                continue; // separators between frames, or at the start of the stream
            }
            out.push(self.take());
        }
    }

    fn take(&mut self) -> RawFrame {
        let frame = RawFrame {
            number: self.next_number,
            offset: self.start,
            bytes: (self.len as usize <= MAX_FRAME_BYTES).then(|| std::mem::take(&mut self.buf)),
            len: self.len,
        };
        self.buf.clear();
        self.len = 0;
        self.next_number += 1;
        frame
    }

    /// The end of the stream: bytes of an unfinished frame, if any (offset, length).
    pub fn finish(&mut self) -> Option<(u64, u64)> {
        if self.len == 0 {
            return None;
        }
        let tail = (self.start, self.len);
        self.buf.clear();
        self.len = 0;
        Some(tail)
    }
}

/// Undo rzCOBS. The result may carry up to 7 zero bytes of padding at its end.
pub fn rzcobs_decode(enc: &[u8]) -> Result<Vec<u8>, &'static str> {
    // The encoding is read from the end: each code byte describes the bytes before it.
    let mut out = Vec::with_capacity(enc.len() + enc.len() / 6 + 8);
    let mut i = enc.len();
    let literal = |i: &mut usize, out: &mut Vec<u8>| -> Result<(), &'static str> {
        *i = i
            .checked_sub(1)
            .ok_or("rzCOBS code runs past the frame start")?;
        out.push(enc[*i]);
        Ok(())
    };
    while i > 0 {
        i -= 1;
        match enc[i] {
            0 => return Err("zero byte inside a frame"),
            code @ 0x01..=0x7f => {
                // Seven positions, last first: a set bit is a zero byte, a clear bit a literal.
                for bit in (0..7).rev() {
                    if code & (1 << bit) != 0 {
                        out.push(0);
                    } else {
                        literal(&mut i, &mut out)?;
                    }
                }
            }
            code @ 0x80..=0xfe => {
                out.push(0);
                for _ in 0..(code & 0x7f) as usize + 7 {
                    literal(&mut i, &mut out)?;
                }
            }
            0xff => {
                for _ in 0..134 {
                    literal(&mut i, &mut out)?;
                }
            }
        }
    }
    out.reverse();
    Ok(out)
}

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
    let record = build(layout.kind, &f).map_err(|e| format!("`{word}` record seq {seq}: {e}"))?;
    Ok(Event::Record { seq, record })
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

/// Wire value for "no channel" / "no fault" (`firmware::defmt_sink::NONE_CODE`).
pub const NONE_CODE: u8 = 0xff;

fn channel(code: u8) -> Result<Option<Channel>, String> {
    match code {
        0 => Ok(Some(Channel::T1)),
        1 => Ok(Some(Channel::T2)),
        NONE_CODE => Ok(None),
        c => Err(format!("unknown channel code {c}")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// rzCOBS encoding, for tests (the firmware's encoder is defmt's).
    fn encode(data: &[u8]) -> Vec<u8> {
        let mut out = Vec::new();
        let (mut run, mut zeros) = (0u8, 0u8);
        for &b in data {
            if run < 7 {
                if b == 0 {
                    zeros |= 1 << run;
                } else {
                    out.push(b);
                }
                run += 1;
                if run == 7 && zeros != 0 {
                    out.push(zeros);
                    run = 0;
                    zeros = 0;
                }
            } else if b == 0 {
                out.push((run - 7) | 0x80);
                run = 0;
                zeros = 0;
            } else {
                out.push(b);
                run += 1;
                if run == 134 {
                    out.push(0xff);
                    run = 0;
                    zeros = 0;
                }
            }
        }
        match run {
            0 => {}
            1..=6 => out.push((zeros | (0xff << run)) & 0x7f),
            _ => out.push((run - 7) | 0x80),
        }
        out
    }

    #[test]
    fn rzcobs_round_trips_up_to_padding() {
        let cases: Vec<Vec<u8>> = vec![
            vec![],
            vec![0],
            vec![1],
            vec![1, 0],
            vec![0, 1],
            vec![0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77],
            vec![0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x00],
            (1..=255).collect(),
            (0..600).map(|i| (i % 7) as u8).collect(),
            vec![5; 300],
        ];
        for data in cases {
            let enc = encode(&data);
            assert!(!enc.contains(&0), "{data:?}");
            let dec = rzcobs_decode(&enc).unwrap();
            assert!(dec.len() >= data.len(), "{data:?}");
            assert_eq!(&dec[..data.len()], &data[..]);
            assert!(dec[data.len()..].iter().all(|&b| b == 0));
            assert!(dec.len() - data.len() <= super::super::elf::MAX_PADDING);
        }
        assert!(rzcobs_decode(&[0x11, 0x00]).is_err());
        assert!(rzcobs_decode(&[0x01]).is_err());
        assert!(rzcobs_decode(&[0x85]).is_err());
    }

    #[test]
    fn deframer_numbers_frames_and_keeps_offsets_across_pushes() {
        let mut d = Deframer::new();
        let mut out = Vec::new();
        d.push(&[0, 0, 1, 2], &mut out);
        assert!(out.is_empty());
        d.push(&[3, 0, 0, 9, 0, 7], &mut out);
        assert_eq!(out.len(), 2);
        assert_eq!((out[0].number, out[0].offset, out[0].len), (0, 2, 3));
        assert_eq!(out[0].bytes.as_deref(), Some(&[1u8, 2, 3][..]));
        assert_eq!((out[1].number, out[1].offset), (1, 7));
        assert_eq!(d.finish(), Some((9, 1)));
        assert_eq!(d.finish(), None);
        let mut big = vec![1u8; MAX_FRAME_BYTES + 10];
        big.push(0);
        out.clear();
        d.push(&big, &mut out);
        assert_eq!(out[0].bytes, None);
        assert_eq!(out[0].len, MAX_FRAME_BYTES as u64 + 10);
    }
}
