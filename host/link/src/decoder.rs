//! The stream decoder: bytes in (in chunks of any size), located events out, with every bad
//! frame and every sequence jump accounted for. Never panics on its input.

use super::elf::Firmware;
use super::error::FrameError;
use super::frame::{decode_frame, Event};
use super::seq::{SeqEvent, SeqTracker};
use super::stream::{Deframer, RawFrame, MAX_FRAME_BYTES};
use serde::Serialize;

/// A frame that did not decode.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct BadFrame {
    /// Frame number in the stream, from 0.
    pub frame: u64,
    /// Byte offset of its first byte.
    pub byte_offset: u64,
    /// Its encoded length, bytes.
    pub bytes: u64,
    /// What is wrong with it.
    pub reason: String,
}

/// An event with where it came from.
#[derive(Clone, Debug, PartialEq)]
pub struct Located {
    /// Frame number in the stream, from 0.
    pub frame: u64,
    /// Byte offset of the frame.
    pub byte_offset: u64,
    /// What it was.
    pub event: Event,
    /// For a record: how its sequence number followed the previous one.
    pub seq: Option<SeqEvent>,
}

/// How many bad frames are kept in full (all are counted).
pub const KEEP_BAD_FRAMES: usize = 200;

/// Decodes one stream.
pub struct Decoder<'f> {
    /// `None`: records that arrive already decoded ([`Decoder::push_records`]).
    fw: Option<&'f Firmware>,
    deframer: Deframer,
    frames: Vec<RawFrame>,
    /// Sequence numbers so far.
    pub seq: SeqTracker,
    /// Frames cut from the stream so far.
    pub frames_seen: u64,
    /// Frames that decoded to a record.
    pub records: u64,
    /// Frames that decoded to a text message.
    pub messages: u64,
    /// Frames that did not decode.
    pub bad_frames: u64,
    /// The first [`KEEP_BAD_FRAMES`] of them.
    pub bad_examples: Vec<BadFrame>,
}

impl<'f> Decoder<'f> {
    /// A decoder at the start of a stream from the firmware `fw`.
    pub fn new(fw: &'f Firmware) -> Self {
        Decoder {
            fw: Some(fw),
            ..Decoder::new_parts()
        }
    }

    /// A decoder for records that arrive already decoded, with no firmware table (the
    /// simulated board, which runs the firmware's code on the host): the same sequence
    /// tracking and counts, no bytes.
    pub fn records_only() -> Self {
        Decoder::new_parts()
    }

    fn new_parts() -> Self {
        Decoder {
            fw: None,
            deframer: Deframer::new(),
            frames: Vec::new(),
            seq: SeqTracker::new(),
            frames_seen: 0,
            records: 0,
            messages: 0,
            bad_frames: 0,
            bad_examples: Vec::new(),
        }
    }

    /// The firmware whose table decodes the stream (`None` for [`Decoder::records_only`]).
    pub fn firmware(&self) -> Option<&'f Firmware> {
        self.fw
    }

    /// Take records already decoded (with their sequence numbers), in order: each counted as
    /// a frame and tracked like a decoded one, appended to `out`.
    pub fn push_records(
        &mut self,
        records: impl IntoIterator<Item = Event>,
        out: &mut Vec<Located>,
    ) {
        for event in records {
            let number = self.frames_seen;
            self.frames_seen += 1;
            let seq = match &event {
                Event::Record { seq, .. } => {
                    self.records += 1;
                    Some(self.seq.observe(*seq, number, 0))
                }
                Event::Message { .. } => {
                    self.messages += 1;
                    None
                }
            };
            out.push(Located {
                frame: number,
                byte_offset: 0,
                event,
                seq,
            });
        }
    }

    /// Bytes fed so far.
    pub fn bytes_seen(&self) -> u64 {
        self.deframer.bytes_seen()
    }

    /// Feed a chunk; the events of the frames it completes are appended to `out`, bad frames
    /// are counted (and returned through `bad`, for live reporting).
    pub fn push(&mut self, bytes: &[u8], out: &mut Vec<Located>, bad: &mut Vec<BadFrame>) {
        self.deframer.push(bytes, &mut self.frames);
        for raw in std::mem::take(&mut self.frames) {
            self.frames_seen += 1;
            let result = match &raw.bytes {
                None => Err(FrameError::NoSeparator {
                    bytes: raw.len,
                    max: MAX_FRAME_BYTES,
                }),
                Some(b) => match self.fw {
                    Some(fw) => decode_frame(fw, b),
                    None => Err(FrameError::NoFirmware),
                },
            };
            match result {
                Ok(event) => {
                    let seq = match &event {
                        Event::Record { seq, .. } => {
                            self.records += 1;
                            Some(self.seq.observe(*seq, raw.number, raw.offset))
                        }
                        Event::Message { .. } => {
                            self.messages += 1;
                            None
                        }
                    };
                    out.push(Located {
                        frame: raw.number,
                        byte_offset: raw.offset,
                        event,
                        seq,
                    });
                }
                Err(reason) => {
                    self.bad_frames += 1;
                    let b = BadFrame {
                        frame: raw.number,
                        byte_offset: raw.offset,
                        bytes: raw.len,
                        reason: reason.to_string(),
                    };
                    if self.bad_examples.len() < KEEP_BAD_FRAMES {
                        self.bad_examples.push(b.clone());
                    }
                    bad.push(b);
                }
            }
        }
    }

    /// The end of the stream: the unfinished frame at its end, if any (byte offset, length).
    pub fn finish(&mut self) -> Option<(u64, u64)> {
        self.deframer.finish()
    }
}

/// Decode a whole stream held in memory: events, and the decoder for its counts.
pub fn decode_all<'f>(fw: &'f Firmware, bytes: &[u8]) -> (Vec<Located>, Decoder<'f>) {
    let mut d = Decoder::new(fw);
    let mut out = Vec::new();
    let mut bad = Vec::new();
    d.push(bytes, &mut out, &mut bad);
    (out, d)
}
