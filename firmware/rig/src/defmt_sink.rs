//! The bare-metal log sink: each record becomes one defmt frame with a fixed, flat format
//! string (`capstan log` on the host matches on the leading word and reads the typed
//! arguments by name). The format strings are the wire schema's (`capstan-wire`'s record
//! table, made into literals by `firmware/rig/build.rs`), which the host's decoder reads too.

use crate::record::{record_crc, LogSink, Record, NONE_CODE};

/// Records held back in one sample period at most (a run's end: the last pair and `run_end`;
/// with a host command's reply and settings report, and a fault: five).
const HELD: usize = 5;

/// Sends records as defmt frames on whatever global logger the binary links (RTT on the
/// Pico, semihosting on QEMU). Records emitted during a sample are held until the runner has
/// applied that sample's outputs ([`LogSink::flush`]): a run's end or a fault reaches the pins
/// before the records that tell of it are encoded.
#[derive(Default)]
pub struct DefmtSink {
    held: [Option<(u32, Record)>; HELD],
}

impl LogSink for DefmtSink {
    fn emit(&mut self, seq: u32, record: &Record) {
        match self.held.iter_mut().find(|h| h.is_none()) {
            Some(slot) => *slot = Some((seq, *record)),
            None => {
                self.flush();
                write(seq, record);
            }
        }
    }

    fn flush(&mut self) {
        for (seq, record) in self.held.iter_mut().filter_map(Option::take) {
            write(seq, &record);
        }
    }
}

// `wire_record!`: each record kind's defmt call, its format string from the wire schema
// (firmware/rig/build.rs).
include!(concat!(env!("OUT_DIR"), "/wire_record.rs"));

/// One record as one defmt frame: the schema's fields, in its order, each named (a name that is
/// not the schema's, or out of its order, does not compile), and the CRC-32 of them.
fn write(seq: u32, record: &Record) {
    let crc = record_crc(seq, record);
    match record {
        Record::RunStart(s) => {
            let settings = s.settings().fields();
            wire_record!(run_start: seq = seq, run = s.run, settings = settings, crc = crc)
        }
        Record::Settings(r) => {
            let (source, settings) = (r.source.code(), r.settings.fields());
            wire_record!(settings: seq = seq, source = source, settings = settings, crc = crc)
        }
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
