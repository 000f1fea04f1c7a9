//! What the emulated board did in the setup case, on the plant's sample grid, and host-sim's
//! session given the same lines at the same samples.

use crate::setup::{Emulated, Setup};
use crate::{f, MS};
use capstan_emu_bench::case::{board_calibration, board_limits, board_protocol, Case, BURST_AT_MS};
use capstan_link::{decode_all, Firmware};
use capstan_rig::record::{Live, Record};
use capstan_sim::flash::RamFlash;
use capstan_sim::session::{run_session, SessionOutput, SessionSpec, Step, FLASH_PAGES};

/// A record as the host received it.
pub struct Got {
    /// When the harness read it from the RTT up channel (polled every 1 ms), ns.
    pub at_ns: f64,
    pub seq: u32,
    pub record: Record,
}

/// A host line as the harness wrote it.
pub struct Line {
    pub text: String,
    /// When its last byte was in the down channel, ns.
    pub written_ns: f64,
    /// The sample that took it, ms of plant time.
    pub sample: u64,
}

/// What the emulated board did, on the plant's sample grid (sample k at plant time k ms).
pub struct Board {
    pub origin_ns: f64,
    /// Every sample's codes as the bench's ADC returned them: (T1 conversion's start, ns; T1;
    /// T2).
    pub samples: Vec<(f64, u16, u16)>,
    pub records: Vec<Got>,
    pub lines: Vec<Line>,
}

impl Board {
    pub fn new(setup: &Setup, e: &Emulated) -> Board {
        let b = e.bench();
        let samples: Vec<(f64, u16, u16)> = serde_json::from_value(b["samples"].clone()).unwrap();
        let mut board = Board {
            origin_ns: f(&b["origin_ns"]),
            samples,
            records: records(setup, e),
            lines: Vec::new(),
        };
        for c in e.emulation["commands"].as_array().unwrap() {
            let written_ns = f(&c["written_ns"]);
            // The firmware reads the console after both conversions, and takes one line per
            // sample: a line is taken by the first sample whose T1 conversion starts after it
            // was written, or after the one that took the line before. (Written 100 µs or more
            // after the previous sample's conversion, it cannot have been seen by that one.)
            let i = board.samples.iter().position(|s| s.0 > written_ns).unwrap();
            assert!(
                written_ns - board.samples[i - 1].0 > 0.1 * MS,
                "{c}: too close"
            );
            let first = board.sample_of(board.samples[i].0);
            let after = board.lines.last().map_or(0, |l| l.sample + 1);
            board.lines.push(Line {
                text: c["line"].as_str().unwrap().to_string(),
                written_ns,
                sample: first.max(after),
            });
        }
        board
    }

    pub fn sample_of(&self, t_ns: f64) -> u64 {
        ((t_ns - self.origin_ns) / MS).round() as u64
    }

    pub fn codes_at(&self, k: u64) -> (u16, u16) {
        let s = self.samples[(k - self.sample_of(self.samples[0].0)) as usize];
        assert_eq!(self.sample_of(s.0), k);
        (s.1, s.2)
    }

    /// The sample of a `live` record: its `t_ms` is the chip's clock (since power-up), read
    /// just before the sample's conversions.
    pub fn live_sample(&self, l: &Live) -> u64 {
        let at: Vec<_> = self
            .samples
            .iter()
            .filter(|s| (s.0 / MS).floor() as u32 == l.t_ms)
            .collect();
        assert_eq!(at.len(), 1, "samples in chip ms {}", l.t_ms);
        assert_eq!(
            (at[0].1, at[0].2),
            (l.counts[0], l.counts[1]),
            "{l:?}: not the ADC's codes"
        );
        self.sample_of(at[0].0)
    }

    pub fn burst_ns(&self) -> f64 {
        BURST_AT_MS as f64 * MS
    }

    pub fn line(&self, text: &str) -> &Line {
        self.lines.iter().find(|l| l.text == text).unwrap()
    }
}

/// The stream decoded into records, each with when it reached the host.
fn records(setup: &Setup, e: &Emulated) -> Vec<Got> {
    let fw = Firmware::load(&setup.image.elf).expect("the board image's defmt table");
    let bytes = std::fs::read(e.dir.join("stream.defmt")).unwrap();
    let (events, d) = decode_all(&fw, &bytes);
    assert_eq!(d.bad_frames, 0);
    let reads: Vec<(f64, u64)> = serde_json::from_value(e.emulation["rtt_reads"].clone()).unwrap();
    events
        .iter()
        .filter_map(|l| {
            let (seq, record) = l.event.record()?;
            let at_ns = reads.iter().find(|r| r.1 > l.byte_offset).unwrap().0;
            Some(Got {
                at_ns,
                seq,
                record: *record,
            })
        })
        .collect()
}

/// The zero's measurement, ms: its reply comes this much after the sample that took it.
pub const ZERO_MS: u64 = capstan_rig::setup::MEASURE_MS as u64;

/// host-sim's session with each line taken by the same sample as on the board, until the same
/// plant time. Its host sends a line between two samples and polls for the reply every 1 ms:
/// pushed at k − 1 ms (after that sample ran) it is taken at k, and the host has seen the
/// reply at k (k + 500 ms for a zero).
pub fn host_sim(c: &Case, board: &Board, end_ms: u64) -> SessionOutput {
    let mut steps = Vec::new();
    let mut host_ms = 50; // run_session's host lets the board boot first
                          // The operator's press, if the case has one (a session's presses are steps).
    let mut press = c
        .cord
        .press_at_us
        .map(|at_us| (at_us / 1000, (c.cord.press_us / 1000) as u32));
    for l in &board.lines {
        if let Some((at_ms, hold_ms)) = press.filter(|&(at_ms, _)| at_ms < l.sample) {
            steps.push(Step::Wait((at_ms - host_ms) as u32));
            steps.push(Step::Press(hold_ms));
            host_ms = at_ms + hold_ms as u64;
            press = None;
        }
        steps.push(Step::Wait((l.sample - 1 - host_ms) as u32));
        steps.push(Step::Send(l.text.clone()));
        host_ms = l.sample + if l.text == "zero" { ZERO_MS } else { 0 };
    }
    if let Some((at_ms, hold_ms)) = press {
        steps.push(Step::Wait((at_ms - host_ms) as u32));
        steps.push(Step::Press(hold_ms));
        host_ms = at_ms + hold_ms as u64;
    }
    steps.push(Step::Wait((end_ms - host_ms) as u32));
    let spec = SessionSpec {
        plant: c.plant,
        cord: c.cord,
        protocol: board_protocol(),
        calibration: board_calibration(),
        limits: board_limits(),
        seed: c.seed,
        trace_every_ms: 0,
        injections: Vec::new(),
    };
    let out = run_session(&spec, RamFlash::new(FLASH_PAGES), &steps).expect("host-sim session");
    assert!(out.unanswered.is_empty(), "host-sim: {:?}", out.unanswered);
    out
}
