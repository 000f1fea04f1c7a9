//! A NOR flash in RAM for the simulated board: the `embedded-storage-async` traits the board's
//! flash (embassy-rp) implements, with the same geometry (1-byte writes, 4 KiB erase pages)
//! and NOR rules (a write can only clear bits; an erase sets a page to 0xFF). Erases and
//! writes take virtual time, as on the Pico's W25Q16, so the rig's watchdog allowance and the
//! supervisor's gap check see a store as the board would.

use embassy_time::Timer;
use embedded_storage_async::nor_flash::{
    ErrorType, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash,
};

/// Erase page, bytes (the W25Q16's sector).
pub const ERASE_BYTES: usize = 4096;
/// Time to erase one page, µs (W25Q16 typical 45 ms).
pub const ERASE_US: u64 = 45_000;
/// Time to program one 256-byte page, µs (typical 0.7 ms; charged per write call).
pub const WRITE_US: u64 = 700;

/// An access outside the flash or not aligned to its geometry.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FlashError(NorFlashErrorKind);

impl NorFlashError for FlashError {
    fn kind(&self) -> NorFlashErrorKind {
        self.0
    }
}

/// A flash of `pages` erase pages, all erased.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RamFlash {
    bytes: Vec<u8>,
    /// Page erases so far.
    pub erases: u64,
    /// The next this many reads fail (a test's flash that cannot be read).
    pub failing_reads: u32,
}

impl RamFlash {
    /// `pages` erased pages.
    pub fn new(pages: usize) -> Self {
        RamFlash {
            bytes: vec![0xff; pages * ERASE_BYTES],
            erases: 0,
            failing_reads: 0,
        }
    }

    /// A flash holding `bytes` (a saved image); `None` unless whole pages.
    pub fn from_bytes(bytes: Vec<u8>) -> Option<Self> {
        (!bytes.is_empty() && bytes.len().is_multiple_of(ERASE_BYTES)).then_some(RamFlash {
            bytes,
            erases: 0,
            failing_reads: 0,
        })
    }

    /// The whole content.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }

    /// Flip the bits of `mask` in the byte at `offset` (a test's damage).
    pub fn flip(&mut self, offset: usize, mask: u8) {
        if let Some(b) = self.bytes.get_mut(offset) {
            *b ^= mask;
        }
    }

    fn range(&self, offset: u32, len: usize) -> Result<core::ops::Range<usize>, FlashError> {
        let start = offset as usize;
        let end = start
            .checked_add(len)
            .filter(|&e| e <= self.bytes.len())
            .ok_or(FlashError(NorFlashErrorKind::OutOfBounds))?;
        Ok(start..end)
    }
}

impl ErrorType for RamFlash {
    type Error = FlashError;
}

impl ReadNorFlash for RamFlash {
    const READ_SIZE: usize = 1;

    async fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), FlashError> {
        if self.failing_reads > 0 {
            self.failing_reads -= 1;
            return Err(FlashError(NorFlashErrorKind::Other));
        }
        let r = self.range(offset, bytes.len())?;
        bytes.copy_from_slice(&self.bytes[r]);
        Ok(())
    }

    fn capacity(&self) -> usize {
        self.bytes.len()
    }
}

impl NorFlash for RamFlash {
    const WRITE_SIZE: usize = 1;
    const ERASE_SIZE: usize = ERASE_BYTES;

    async fn erase(&mut self, from: u32, to: u32) -> Result<(), FlashError> {
        let aligned = |a: u32| (a as usize).is_multiple_of(ERASE_BYTES);
        if !aligned(from) || !aligned(to) || to < from {
            return Err(FlashError(NorFlashErrorKind::NotAligned));
        }
        let r = self.range(from, (to - from) as usize)?;
        let pages = (r.len() / ERASE_BYTES) as u64;
        self.bytes[r].fill(0xff);
        self.erases += pages;
        Timer::after_micros(ERASE_US * pages).await;
        Ok(())
    }

    async fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), FlashError> {
        let r = self.range(offset, bytes.len())?;
        // NOR programming only clears bits.
        for (cell, b) in self.bytes[r].iter_mut().zip(bytes) {
            *cell &= *b;
        }
        Timer::after_micros(WRITE_US).await;
        Ok(())
    }
}
