//! The board's defmt logger: each frame is encoded into RAM whole, then copied into the RTT up
//! channel in one write.
//!
//! rtt-target's own defmt logger hands every byte the encoder makes to the channel as a
//! separate write (the channel's mode, both offsets read, a copy, the write offset stored:
//! ~250 cycles a byte on the Cortex-M0+). A record of the 47 settings (~210 bytes) cost
//! ~50 000 cycles that way, 40 % of a 1 ms sample (README, "The board image on an emulated
//! RP2040"). Here defmt's bytes are gathered first (a field costs a copy), rzCOBS-encoded in one
//! pass at the frame's end, and the encoded frame copied into the channel at once.
//!
//! The bytes on the wire are the same (defmt's rzCOBS frames, as `probe-rs run` and `capstan
//! log` decode them). One thing is better: the channel is non-blocking and skips a write that
//! does not fit whole (`ChannelMode::NoBlockSkip`), so when the host falls behind a frame is
//! now lost whole, never cut, and the loss shows only as a gap in the records' `seq`. A frame
//! longer than [`FRAME_BYTES`] (only a long panic message can be) goes out in pieces, each
//! whole or skipped: such a frame can still be cut, as any frame could before.

use core::ptr::addr_of_mut;
use core::sync::atomic::{AtomicBool, Ordering};
use rtt_target::UpChannel;

/// The frame buffer, bytes before encoding: the longest record whole (`run_start`: its index,
/// `seq`, `run`, the 47 settings and `crc`, 192 bytes).
pub const FRAME_BYTES: usize = 224;

/// rzCOBS adds at most a byte per 7, and the frame's end its two.
const ENCODED_BYTES: usize = FRAME_BYTES + FRAME_BYTES / 7 + 3;

/// A buffer of bytes.
struct Bytes<const N: usize> {
    bytes: [u8; N],
    len: usize,
}

// The logger's state, touched only between `acquire` and `release` (a critical section, and
// `TAKEN` refuses re-entry), or by `set_channel` before the first log.
static mut CHANNEL: Option<UpChannel> = None;
static mut ENCODER: defmt::Encoder = defmt::Encoder::new();
/// The frame's bytes as defmt gives them.
static mut FRAME: Bytes<FRAME_BYTES> = Bytes {
    bytes: [0; FRAME_BYTES],
    len: 0,
};
/// The same encoded (rzCOBS), as they go to the channel.
static mut ENCODED: Bytes<ENCODED_BYTES> = Bytes {
    bytes: [0; ENCODED_BYTES],
    len: 0,
};
static mut CS_RESTORE: critical_section::RestoreState = critical_section::RestoreState::invalid();
static TAKEN: AtomicBool = AtomicBool::new(false);

/// The channel the frames go to (RTT up channel 0). Until it is set, frames are dropped.
pub fn set_channel(channel: UpChannel) {
    critical_section::with(|_| {
        // SAFETY: in a critical section, and never while a frame is being encoded (the logger
        // holds its own critical section from acquire to release).
        unsafe { *addr_of_mut!(CHANNEL) = Some(channel) }
    });
}

#[defmt::global_logger]
struct Logger;

// SAFETY: acquire/release bracket every frame in a critical section, and a nested acquire
// panics instead of interleaving frames (as defmt's own loggers do).
unsafe impl defmt::Logger for Logger {
    fn acquire() {
        // SAFETY: paired with the release in `release`.
        let restore = unsafe { critical_section::acquire() };
        if TAKEN.load(Ordering::Relaxed) {
            panic!("defmt logger taken reentrantly")
        }
        TAKEN.store(true, Ordering::Relaxed);
        // SAFETY: interrupts are off and the logger is ours until release.
        unsafe {
            CS_RESTORE = restore;
            (*addr_of_mut!(ENCODER)).start_frame(encoded);
        }
    }

    unsafe fn flush() {}

    unsafe fn release() {
        // SAFETY: called after acquire, in its critical section.
        unsafe {
            encode();
            (*addr_of_mut!(ENCODER)).end_frame(encoded);
            send();
            TAKEN.store(false, Ordering::Relaxed);
            critical_section::release(CS_RESTORE);
        }
    }

    unsafe fn write(bytes: &[u8]) {
        // SAFETY: called between acquire and release.
        let frame = unsafe { &mut *addr_of_mut!(FRAME) };
        for chunk in bytes.chunks(FRAME_BYTES) {
            if frame.len + chunk.len() > FRAME_BYTES {
                // A frame longer than the buffer (a long panic message): out in pieces.
                encode();
                send();
            }
            frame.bytes[frame.len..frame.len + chunk.len()].copy_from_slice(chunk);
            frame.len += chunk.len();
        }
    }
}

/// The frame's bytes so far through the encoder, into `ENCODED`.
fn encode() {
    // SAFETY: only called between acquire and release.
    let (encoder, frame) = unsafe { (&mut *addr_of_mut!(ENCODER), &mut *addr_of_mut!(FRAME)) };
    encoder.write(&frame.bytes[..frame.len], encoded);
    frame.len = 0;
}

/// Encoded bytes into `ENCODED`, which holds a whole frame's (only the pieces of a frame
/// longer than the buffers can fill it: then it goes out first).
fn encoded(bytes: &[u8]) {
    // SAFETY: only called by the encoder between acquire and release.
    let out = unsafe { &mut *addr_of_mut!(ENCODED) };
    for &b in bytes {
        if out.len == ENCODED_BYTES {
            send_out(out);
        }
        out.bytes[out.len] = b;
        out.len += 1;
    }
}

/// The encoded bytes into the channel, in one write: whole, or skipped whole if they do not
/// fit (the channel's mode).
fn send() {
    // SAFETY: only called between acquire and release, with no other reference to `ENCODED`.
    send_out(unsafe { &mut *addr_of_mut!(ENCODED) });
}

fn send_out(out: &mut Bytes<ENCODED_BYTES>) {
    // SAFETY: only called between acquire and release.
    if let Some(c) = unsafe { &mut *addr_of_mut!(CHANNEL) } {
        c.write(&out.bytes[..out.len]);
    }
    out.len = 0;
}
