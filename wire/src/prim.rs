//! The primitive wire types of the records' fields.

/// A field's type on the wire: what defmt encodes (`{=u8}`, ...), little-endian at this width,
/// and what the record's checksum covers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
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
    /// Every type.
    pub const ALL: [Prim; 5] = [Prim::U8, Prim::U16, Prim::U32, Prim::I64, Prim::F32];

    /// Its name in a defmt format string (`u8` in `{=u8}`) and in Rust.
    pub const fn name(self) -> &'static str {
        match self {
            Prim::U8 => "u8",
            Prim::U16 => "u16",
            Prim::U32 => "u32",
            Prim::I64 => "i64",
            Prim::F32 => "f32",
        }
    }

    /// Bytes on the wire (and in the checksum).
    pub const fn bytes(self) -> usize {
        match self {
            Prim::U8 => 1,
            Prim::U16 => 2,
            Prim::U32 | Prim::F32 => 4,
            Prim::I64 => 8,
        }
    }
}

/// One field's value at its wire type.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scalar {
    /// A `u8` field.
    U8(u8),
    /// A `u16` field.
    U16(u16),
    /// A `u32` field.
    U32(u32),
    /// An `i64` field.
    I64(i64),
    /// An `f32` field.
    F32(f32),
}

impl Scalar {
    /// Its wire type.
    pub const fn prim(self) -> Prim {
        match self {
            Scalar::U8(_) => Prim::U8,
            Scalar::U16(_) => Prim::U16,
            Scalar::U32(_) => Prim::U32,
            Scalar::I64(_) => Prim::I64,
            Scalar::F32(_) => Prim::F32,
        }
    }

    /// Its bytes as the checksum covers them: little-endian at its width, a NaN as the
    /// canonical NaN (the host reads a NaN back from its text, without its payload). The first
    /// [`Prim::bytes`] of the 8.
    pub fn le_bytes(self) -> [u8; 8] {
        let mut b = [0; 8];
        match self {
            Scalar::U8(v) => b[0] = v,
            Scalar::U16(v) => b[..2].copy_from_slice(&v.to_le_bytes()),
            Scalar::U32(v) => b[..4].copy_from_slice(&v.to_le_bytes()),
            Scalar::I64(v) => b.copy_from_slice(&v.to_le_bytes()),
            Scalar::F32(v) => b[..4].copy_from_slice(&canonical_bits(v).to_le_bytes()),
        }
        b
    }
}

/// An `f32`'s bits, a NaN's as the canonical NaN's. By the bits (a NaN: exponent all ones, a
/// fraction not 0), not by `is_nan`: a float comparison is a library call on a core without an
/// FPU (the Cortex-M0+), and the board checksums every real of every record.
pub const fn canonical_bits(v: f32) -> u32 {
    let bits = v.to_bits();
    if bits & 0x7fff_ffff > 0x7f80_0000 {
        f32::NAN.to_bits()
    } else {
        bits
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn canonical_bits_keep_every_number_and_make_every_nan_one() {
        for v in [
            0.0f32,
            -0.0,
            1.5,
            -2.25e-40,
            f32::MAX,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ] {
            assert_eq!(canonical_bits(v), v.to_bits(), "{v}");
        }
        for bits in [
            0x7fc0_0001u32,
            0xffc0_0000,
            0x7f80_0001,
            0xff80_0001,
            0x7fff_ffff,
        ] {
            assert!(f32::from_bits(bits).is_nan());
            assert_eq!(
                canonical_bits(f32::from_bits(bits)),
                f32::NAN.to_bits(),
                "{bits:#x}"
            );
        }
    }
}
