//! Frame pre-validation: [`Firmware::check_frame`] walks a decoded frame against the format
//! strings of the table, the way defmt-decoder will read it, without allocating and without
//! trusting any count in it. defmt-decoder trusts the bytes it is given: a garbage slice
//! length makes it reserve gigabytes (an abort, not a panic), a deep nesting of `{=?}` can
//! overflow the stack. Frames that would, that leave bytes over, or whose index is not in the
//! table are refused here, with the reason.

use super::{short, Entry, Firmware};
use crate::error::{FormatError, FrameError};
use defmt_parser::{Parameter, Type};
use std::ops::Range;

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
    /// Check that a decoded (de-rzCOBSed) frame is well-formed for this table, the way
    /// defmt-decoder will read it, without trusting any count in it. Returns the format index.
    pub fn check_frame(&self, frame: &[u8]) -> Result<u64, FrameError> {
        let mut cur = Cursor {
            bytes: frame,
            pos: 0,
            steps: 0,
        };
        let index = cur.read(2).map_err(|_| FrameError::NoIndex)?;
        let index = u16::from_le_bytes([index[0], index[1]]) as u64;
        if let Some(ts) = &self.timestamp {
            let ts = (ts.as_ref()).map_err(|e| FrameError::TimestampFormat(e.clone()))?;
            self.walk(ts, &mut cur, 0)
                .map_err(|e| FrameError::Timestamp(Box::new(e)))?;
        }
        let entry = self
            .entries
            .get(&index)
            .ok_or(FrameError::UnknownIndex(index))?;
        let params = entry
            .params
            .as_ref()
            .map_err(|why| FrameError::Undecodable {
                index,
                why: why.clone(),
            })?;
        self.walk(params, &mut cur, 0)
            .map_err(|why| FrameError::Arguments {
                format: short(&entry.format),
                why: Box::new(why),
            })?;
        let rest = &frame[cur.pos..];
        if rest.len() > MAX_PADDING || rest.iter().any(|&b| b != 0) {
            return Err(FrameError::LeftOver {
                format: short(&entry.format),
                bytes: rest.len(),
            });
        }
        Ok(index)
    }

    fn nested(&self, cur: &mut Cursor) -> Result<&Entry, FrameError> {
        let i = cur.u16()? as u64;
        match self.entries.get(&i) {
            Some(e) if !e.has_level() => Ok(e),
            Some(_) => Err(FrameError::NestedLog(i)),
            None => Err(FrameError::NestedUnknown(i)),
        }
    }

    /// The parameters of one variant of an enum format (or of a plain format).
    fn variant<'e>(
        &self,
        entry: &'e Entry,
        cur: &mut Cursor,
    ) -> Result<&'e [Parameter], FrameError> {
        let Some(variants) = &entry.variants else {
            return entry.params.as_deref().map_err(format_error);
        };
        // The discriminant is as wide as needed for the number of `|` (as defmt-decoder reads it).
        let bars = variants.len() - 1;
        let d = if bars <= u8::MAX as usize {
            cur.read(1)?[0] as usize
        } else if bars <= u16::MAX as usize {
            cur.u16()? as usize
        } else {
            return Err(FrameError::TooManyVariants);
        };
        variants
            .get(d)
            .ok_or(FrameError::Variant(d))?
            .as_deref()
            .map_err(format_error)
    }

    fn walk(&self, params: &[Parameter], cur: &mut Cursor, depth: u32) -> Result<(), FrameError> {
        if depth > MAX_DEPTH {
            return Err(FrameError::TooDeep);
        }
        for p in params {
            cur.steps += 1;
            if cur.steps > MAX_STEPS {
                return Err(FrameError::TooManyArguments);
            }
            match fixed_bytes(&p.ty).map_err(FrameError::Format)? {
                Some(n) => cur.skip(n)?,
                None => self.variable(&p.ty, cur, depth)?,
            }
        }
        Ok(())
    }

    /// An argument whose length or validity is in its bytes: a checked value, a string, or
    /// nested formats.
    fn variable(&self, ty: &Type, cur: &mut Cursor, depth: u32) -> Result<(), FrameError> {
        match ty {
            Type::Bool => {
                if cur.read(1)?[0] > 1 {
                    return Err(FrameError::Bool);
                }
            }
            Type::Char => {
                let c = cur.u32()?;
                if char::from_u32(c).is_none() {
                    return Err(FrameError::Char(c));
                }
            }
            Type::Str => {
                let n = cur.u32()? as usize;
                if std::str::from_utf8(cur.read(n)?).is_err() {
                    return Err(FrameError::Str);
                }
            }
            Type::U8Slice => {
                let n = cur.u32()? as usize;
                cur.skip(n)?
            }
            Type::IStr => {
                self.nested(cur)?;
            }
            Type::Debug | Type::Display => cur.preformatted()?,
            _ => self.formats(ty, cur, depth)?,
        }
        Ok(())
    }

    /// Nested formats: one (`{=?}`), a slice or array of them, or a sequence ended by index 0.
    fn formats(&self, ty: &Type, cur: &mut Cursor, depth: u32) -> Result<(), FrameError> {
        match ty {
            Type::Format => {
                let entry = self.nested(cur)?;
                let inner = self.variant(entry, cur)?;
                self.walk(inner, cur, depth + 1)?;
            }
            Type::FormatSlice | Type::FormatArray(_) => {
                let n = match ty {
                    Type::FormatArray(n) => *n as u64,
                    _ => cur.u32()? as u64,
                };
                if n > MAX_SLICE_ELEMENTS {
                    return Err(FrameError::Slice(n));
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
                    _ => return Err(FrameError::Sequence(i)),
                };
                let inner = entry.params.as_deref().map_err(format_error)?;
                self.walk(inner, cur, depth + 1)?;
            },
            other => return Err(FrameError::Unhandled(format!("{other:?}"))),
        }
        Ok(())
    }
}

/// The bytes of an argument of fixed length (`None`: its length or validity is in its bytes).
fn fixed_bytes(ty: &Type) -> Result<Option<usize>, FormatError> {
    Ok(Some(match ty {
        Type::U8 | Type::I8 => 1,
        Type::U16 | Type::I16 => 2,
        Type::U32 | Type::I32 | Type::Usize | Type::Isize | Type::F32 => 4,
        Type::U64 | Type::I64 | Type::F64 => 8,
        Type::U128 | Type::I128 => 16,
        Type::BitField(r) => bitfield_bytes(r)?,
        Type::U8Array(n) => *n,
        _ => return Ok(None),
    }))
}

struct Cursor<'a> {
    bytes: &'a [u8],
    pos: usize,
    steps: u32,
}

impl<'a> Cursor<'a> {
    fn read(&mut self, n: usize) -> Result<&'a [u8], FrameError> {
        let end = self
            .pos
            .checked_add(n)
            .filter(|&e| e <= self.bytes.len())
            .ok_or(FrameError::Truncated)?;
        let s = &self.bytes[self.pos..end];
        self.pos = end;
        Ok(s)
    }

    /// A `{:?}`/`{}` argument: UTF-8 text ended by 0xff.
    fn preformatted(&mut self) -> Result<(), FrameError> {
        let rest = &self.bytes[self.pos..];
        let end = rest
            .iter()
            .position(|&b| b == 0xff)
            .ok_or(FrameError::Unterminated)?;
        if std::str::from_utf8(&rest[..end]).is_err() {
            return Err(FrameError::Preformatted);
        }
        self.pos += end + 1;
        Ok(())
    }

    fn skip(&mut self, n: usize) -> Result<(), FrameError> {
        self.read(n).map(|_| ())
    }

    fn u16(&mut self) -> Result<u16, FrameError> {
        let b = self.read(2)?;
        Ok(u16::from_le_bytes([b[0], b[1]]))
    }

    fn u32(&mut self) -> Result<u32, FrameError> {
        let b = self.read(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }
}

pub(super) fn bitfield_bytes(r: &Range<u8>) -> Result<usize, FormatError> {
    if r.end <= r.start || r.end > 128 {
        return Err(FormatError::Bitfield);
    }
    Ok(match (r.end - 1) / 8 - r.start / 8 + 1 {
        1 => 1,
        2 => 2,
        3..=4 => 4,
        5..=8 => 8,
        _ => 16,
    })
}

/// A format that cannot be decoded, met inside a frame.
fn format_error(e: &FormatError) -> FrameError {
    FrameError::Format(e.clone())
}
