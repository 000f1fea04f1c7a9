//! The bare-metal log sink: each record becomes one defmt frame with a fixed, flat format
//! string (`capstan log` on the host matches on the leading word and reads the typed
//! arguments by name). The format strings are the wire schema's (`capstan-wire`'s record
//! table, made into literals by `firmware/rig/build.rs`), which the host's decoder reads too.

use crate::record::{
    record_crc, settings_record_crc, Held, LogSink, Record, LONG_RECORD_UNTIL_US, NONE_CODE,
};
use capstan_wire::Scalar;
use embassy_time::Instant;

/// Records held back at most: those of one sample (a run's end: the last pair and `run_end`;
/// with a host command's reply and settings report, and a fault: five), and of the next
/// while a long record waits for it. Should more come, the oldest goes out at once.
const HELD: usize = 8;

/// Sends records as defmt frames on whatever global logger the binary links (RTT on the
/// Pico, semihosting on QEMU). Records emitted during a sample are held until the runner has
/// applied that sample's outputs ([`LogSink::flush`]): a run's end or a fault reaches the pins
/// before the records that tell of it are encoded. A long record (the settings) waits, with
/// those behind it, for a sample that has time for it ([`LONG_RECORD_UNTIL_US`]; one long
/// record a sample at most, so a backlog of them drains one a sample). Whatever is
/// held when the sink is dropped is sent then.
#[derive(Default)]
pub struct DefmtSink {
    held: Held<HELD>,
    /// When the present sample began, µs (none before the first: at boot).
    sample_us: Option<u64>,
}

impl LogSink for DefmtSink {
    fn emit(&mut self, seq: u32, record: &Record) {
        if !self.held.push(seq, record) {
            // Full (a host sending `show` every sample in force mode outruns the one long
            // record a sample): the oldest goes now, in the sample, to make room; the order
            // stays.
            let mut first = true;
            self.held.send_while(|_| core::mem::take(&mut first), write);
            let pushed = self.held.push(seq, record);
            debug_assert!(pushed);
        }
    }

    fn flush(&mut self) {
        let Some(started) = self.sample_us else {
            // Not in a sample (the boot): the first sample sends them.
            return;
        };
        // One long record a sample at most, and only while the sample is young enough.
        let mut long_sent = false;
        let mut may = |r: &Record| {
            if !r.is_long() {
                return true;
            }
            let young = Instant::now().as_micros().saturating_sub(started) <= LONG_RECORD_UNTIL_US;
            let may = young && !long_sent;
            long_sent |= may;
            may
        };
        self.held.send_while(&mut may, write);
    }

    fn sample_started(&mut self, now_us: u64) {
        self.sample_us = Some(now_us);
    }
}

impl Drop for DefmtSink {
    fn drop(&mut self) {
        self.held.send_while(|_| true, write);
    }
}

// `wire_record!`: each record kind's defmt call, its format string from the wire schema
// (firmware/rig/build.rs).
include!(concat!(env!("OUT_DIR"), "/wire_record.rs"));

/// One record as one defmt frame: the schema's fields, in its order, each named (a name that is
/// not the schema's, or out of its order, does not compile), and the CRC-32 of them.
fn write(seq: u32, record: &Record) {
    // The settings' bits once, for the checksum and the frame.
    match record {
        Record::RunStart(s) => {
            let settings = s.settings().fields();
            let crc = settings_record_crc(seq, Scalar::U32(s.run), &settings);
            wire_record!(run_start: seq = seq, run = s.run, settings = settings, crc = crc)
        }
        Record::Settings(r) => {
            let (source, settings) = (r.source.code(), r.settings.fields());
            let crc = settings_record_crc(seq, Scalar::U8(source), &settings);
            wire_record!(settings: seq = seq, source = source, settings = settings, crc = crc)
        }
        other => write_small(seq, other, record_crc(seq, other)),
    }
}

/// Every other record: a few fields.
fn write_small(seq: u32, record: &Record, crc: u32) {
    match record {
        Record::RunStart(_) | Record::Settings(_) => {}
        Record::Live(l) => wire_record!(live:
            seq = seq,
            t_ms = l.t_ms,
            c1 = l.counts[0],
            c2 = l.counts[1],
            t1_n = l.force_n[0],
            t2_n = l.force_n[1],
            servo_deg = l.servo_deg,
            crc = crc
        ),
        Record::Reply(r) => wire_record!(reply:
            seq = seq,
            command = r.command.code(),
            error = r.error.map_or(0, |e| e.code()),
            v1 = r.values[0],
            v2 = r.values[1],
            crc = crc
        ),
        Record::Raw(r) => wire_record!(raw:
            seq = seq,
            t_us = r.t_us,
            c1 = r.counts[0],
            c2 = r.counts[1],
            t1_n = r.force_n[0],
            t2_n = r.force_n[1],
            t2_target_n = r.t2_target_n,
            crc = crc
        ),
        Record::Pair(p) => wire_record!(pair:
            seq = seq,
            step = p.step,
            level = p.level,
            angle_deg = p.angle_deg,
            t_mid_ms = p.t_mid_ms,
            t1_mean_n = p.t1.mean_n,
            t1_std_n = p.t1.std_n,
            t1_count = p.t1.count,
            t2_mean_n = p.t2.mean_n,
            t2_std_n = p.t2.std_n,
            t2_count = p.t2.count,
            t2_target_n = p.t2_target_n,
            crc = crc
        ),
        Record::Fault(f) => wire_record!(fault:
            seq = seq,
            kind = f.kind.code(),
            channel = f.channel.map_or(NONE_CODE, |c| c.code()),
            value = f.value,
            t_us = f.t_us,
            crc = crc
        ),
        Record::RunEnd(e) => wire_record!(run_end:
            seq = seq,
            t_us = e.t_us,
            pairs = e.pairs,
            fault = e.fault.map_or(NONE_CODE, |k| k.code()),
            crc = crc
        ),
    }
}
