//! The bare-metal log sink: each record becomes one defmt frame with a fixed, flat format
//! string (`capstan log` on the host matches on the leading word and reads the typed
//! arguments in order). Changing a format string here means changing the decoder too.

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

/// One record as one defmt frame.
fn write(seq: u32, record: &Record) {
    {
        // Each record ends with the CRC-32 of its fields, in the order written here.
        let crc = record_crc(seq, record);
        match record {
            Record::RunStart(s) => {
                let p = &s.protocol;
                let c = &s.calibration;
                defmt::info!(
                    "run_start seq={=u32} run={=u32} order={=u8} rest_deg={=f32} step_deg={=f32} final_deg={=f32} dwell_ms={=u32} pre_trigger_ms={=u32} trigger_ms={=u32} tare_ms={=u32} amp_control_v={=f32} sample_hz={=u32} raw_log_hz={=u32} window_after_ms={=u32} window_before_ms={=u32} diameter_mm={=f32} wrap_deg={=f32} amp_gain={=f32} t1_zero={=f32} t1_n_per_count={=f32} t2_zero={=f32} t2_n_per_count={=f32} tare_reference_n={=f32} servo_min_us={=f32} servo_max_us={=f32} servo_max_deg={=f32} amp_full_scale_v={=f32} crc={=u32}",
                    seq,
                    s.run,
                    p.order.code(),
                    p.rest_deg,
                    p.step_deg,
                    p.final_deg,
                    p.dwell_ms,
                    p.pre_trigger_ms,
                    p.trigger_ms,
                    p.tare_ms,
                    p.amp_control_v,
                    p.sample_hz,
                    p.raw_log_hz,
                    p.window_after_change_ms,
                    p.window_before_next_ms,
                    p.capstan_diameter_mm,
                    p.wrap_deg,
                    c.amp.amp_gain,
                    c.t1.zero_counts,
                    c.t1.n_per_count,
                    c.t2.zero_counts,
                    c.t2.n_per_count,
                    c.tare_reference_n,
                    c.servo.pulse_at_min_us,
                    c.servo.pulse_at_max_us,
                    c.servo.max_deg,
                    c.amp.full_scale_v,
                    crc
                );
            }
            Record::Settings(r) => {
                let p = &r.settings.protocol;
                let c = &r.settings.calibration;
                defmt::info!(
                    "settings seq={=u32} source={=u8} order={=u8} rest_deg={=f32} step_deg={=f32} final_deg={=f32} dwell_ms={=u32} pre_trigger_ms={=u32} trigger_ms={=u32} tare_ms={=u32} amp_control_v={=f32} sample_hz={=u32} raw_log_hz={=u32} window_after_ms={=u32} window_before_ms={=u32} diameter_mm={=f32} wrap_deg={=f32} amp_gain={=f32} t1_zero={=f32} t1_n_per_count={=f32} t2_zero={=f32} t2_n_per_count={=f32} tare_reference_n={=f32} servo_min_us={=f32} servo_max_us={=f32} servo_max_deg={=f32} amp_full_scale_v={=f32} crc={=u32}",
                    seq,
                    r.source.code(),
                    p.order.code(),
                    p.rest_deg,
                    p.step_deg,
                    p.final_deg,
                    p.dwell_ms,
                    p.pre_trigger_ms,
                    p.trigger_ms,
                    p.tare_ms,
                    p.amp_control_v,
                    p.sample_hz,
                    p.raw_log_hz,
                    p.window_after_change_ms,
                    p.window_before_next_ms,
                    p.capstan_diameter_mm,
                    p.wrap_deg,
                    c.amp.amp_gain,
                    c.t1.zero_counts,
                    c.t1.n_per_count,
                    c.t2.zero_counts,
                    c.t2.n_per_count,
                    c.tare_reference_n,
                    c.servo.pulse_at_min_us,
                    c.servo.pulse_at_max_us,
                    c.servo.max_deg,
                    c.amp.full_scale_v,
                    crc
                );
            }
            Record::Live(l) => defmt::info!(
                "live seq={=u32} t_ms={=u32} c1={=u16} c2={=u16} t1_n={=f32} t2_n={=f32} servo_deg={=f32} crc={=u32}",
                seq,
                l.t_ms,
                l.counts[0],
                l.counts[1],
                l.force_n[0],
                l.force_n[1],
                l.servo_deg,
                crc
            ),
            Record::Reply(r) => defmt::info!(
                "reply seq={=u32} command={=u8} error={=u8} v1={=f32} v2={=f32} crc={=u32}",
                seq,
                r.command.code(),
                r.error.map_or(0, |e| e.code()),
                r.values[0],
                r.values[1],
                crc
            ),
            Record::Raw(r) => defmt::info!(
                "raw seq={=u32} t_us={=i64} c1={=u16} c2={=u16} t1_n={=f32} t2_n={=f32} crc={=u32}",
                seq,
                r.t_us,
                r.counts[0],
                r.counts[1],
                r.force_n[0],
                r.force_n[1],
                crc
            ),
            Record::Pair(p) => defmt::info!(
                "pair seq={=u32} step={=u32} level={=u32} angle_deg={=f32} t_mid_ms={=u32} t1_mean_n={=f32} t1_std_n={=f32} t1_count={=u32} t2_mean_n={=f32} t2_std_n={=f32} t2_count={=u32} crc={=u32}",
                seq,
                p.step,
                p.level,
                p.angle_deg,
                p.t_mid_ms,
                p.t1.mean_n,
                p.t1.std_n,
                p.t1.count,
                p.t2.mean_n,
                p.t2.std_n,
                p.t2.count,
                crc
            ),
            Record::Fault(f) => defmt::warn!(
                "fault seq={=u32} kind={=u8} channel={=u8} value={=f32} t_us={=i64} crc={=u32}",
                seq,
                f.kind.code(),
                f.channel.map_or(NONE_CODE, |c| c as u8),
                f.value,
                f.t_us,
                crc
            ),
            Record::RunEnd(e) => defmt::info!(
                "run_end seq={=u32} t_us={=i64} pairs={=u32} fault={=u8} crc={=u32}",
                seq,
                e.t_us,
                e.pairs,
                e.fault.map_or(NONE_CODE, |k| k.code()),
                crc
            ),
        }
    }
}
