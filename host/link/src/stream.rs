//! From bytes to frames: rzCOBS framing (each frame ends with a 0x00), with the frame number
//! and byte offset of every frame kept for messages, and the rzCOBS decoding of a frame's
//! bytes. What a frame says is `frame`'s business.

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

#[cfg(test)]
mod tests {
    use super::*;

    // rzCOBS round trips are checked in tests/log_stream.rs, with the tests' encoder (itself
    // checked against the firmware's recorded frames).

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
