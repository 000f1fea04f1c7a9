//! Shared by the log session's tests (`host/log/tests/`) and `capstan log`'s (the root's
//! `tests/log_cli.rs`): the recorded QEMU stream and its ELF, and tools to take a stream apart
//! frame by frame.
#![allow(dead_code)]

use capstan_link::Firmware;
use std::path::PathBuf;

/// `tests/data/<name>` at the workspace's root (the recorded stream is shared with the CLI's
/// tests, the fuzzers and `scripts/qemu-e2e`). Found from the including crate: the root
/// (`tests/log_cli.rs`) or `host/log`.
pub fn data(name: &str) -> PathBuf {
    let manifest = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let root = if manifest.join("tests/data").is_dir() {
        manifest
    } else {
        manifest.join("../..")
    };
    root.join("tests/data").join(name)
}

/// A fresh directory for one test's output: `capstan-log-KIND-PID-NAME` in the system's temp
/// directory, emptied (not created).
pub fn fresh_dir(kind: &str, name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("capstan-log-{kind}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// The ELF that produced [`stream`] (qemu-fw, recorded by `scripts/qemu-e2e --record`).
pub fn elf_path() -> PathBuf {
    data("qemu-fw.elf")
}

/// The firmware of the recorded stream.
pub fn firmware() -> Firmware {
    Firmware::load(&elf_path()).expect("the recorded ELF loads")
}

/// A recorded QEMU run (lm3s6965evb): a banner, two runs (the second ended by an over-force
/// fault); 217 frames.
pub fn stream() -> Vec<u8> {
    std::fs::read(data("qemu-run.defmt")).expect("recorded stream")
}

/// A stream cut into its frames: each with its byte offset, and its bytes including the 0x00
/// that ends it. The leading separator (defmt writes one at boot) is `lead`.
pub struct Frames {
    pub lead: Vec<u8>,
    pub frames: Vec<(usize, Vec<u8>)>,
}

pub fn split(stream: &[u8]) -> Frames {
    let lead_len = stream.iter().take_while(|&&b| b == 0).count();
    let mut frames = Vec::new();
    let mut start = lead_len;
    for (i, &b) in stream.iter().enumerate().skip(lead_len) {
        if b == 0 {
            frames.push((start, stream[start..=i].to_vec()));
            start = i + 1;
        }
    }
    assert_eq!(
        start,
        stream.len(),
        "the recorded stream ends with a separator"
    );
    Frames {
        lead: stream[..lead_len].to_vec(),
        frames,
    }
}

impl Frames {
    /// The stream without the frames whose numbers are in `drop`.
    pub fn without(&self, drop: &[usize]) -> Vec<u8> {
        let mut out = self.lead.clone();
        for (i, (_, f)) in self.frames.iter().enumerate() {
            if !drop.contains(&i) {
                out.extend_from_slice(f);
            }
        }
        out
    }
}

/// rzCOBS-encode a frame (what defmt's encoder does), without the separator.
pub fn rzcobs_encode(data: &[u8]) -> Vec<u8> {
    // Groups of 7 bytes: the non-zero bytes, then a code byte whose bits mark the zeros; a
    // group with no zero is extended into a run of literals (up to 134) ended by 0x80 + len-7.
    let mut out = Vec::new();
    let mut i = 0;
    while i < data.len() {
        let group = &data[i..(i + 7).min(data.len())];
        if group.len() == 7 && !group.contains(&0) {
            let run: usize = data[i..].iter().take(134).take_while(|&&b| b != 0).count();
            out.extend_from_slice(&data[i..i + run]);
            i += run;
            if run == 134 {
                out.push(0xff);
            } else {
                // The run ends at a zero (consumed here) or at the end of the frame.
                out.push(0x80 | (run - 7) as u8);
                i += 1;
            }
            continue;
        }
        let mut code = 0u8;
        for (bit, &b) in group.iter().enumerate() {
            if b == 0 {
                code |= 1 << bit;
            } else {
                out.push(b);
            }
        }
        for bit in group.len()..7 {
            code |= 1 << bit;
        }
        out.push(code);
        i += 7;
    }
    out
}

/// Undo rzCOBS (the decoder's own function).
pub fn rzcobs_decode(data: &[u8]) -> Vec<u8> {
    capstan_link::stream::rzcobs_decode(data).expect("valid rzCOBS")
}
