//! Frames as the firmware sends them, made from the wire schema's format strings
//! (`capstan-wire`, which the firmware's defmt calls are written from) for a defmt table
//! without an ELF
//! (`Firmware::from_formats`): each record's fields by name, at their wire widths, with the
//! CRC over them in format order (checked against the firmware's own `record_crc`).

use crate::log_support::rzcobs_encode;
use capstan_link::Firmware;
use capstan_rig::condition::ChannelStats;
use capstan_rig::record::{record_crc, CrcFields, Live, RawSample, Record, NONE_CODE};
use capstan_rig::Settings;

pub const WORDS: [&str; 8] = [
    "run_start",
    "raw",
    "pair",
    "fault",
    "run_end",
    "settings",
    "live",
    "reply",
];
/// Index of a text message in the made-up table.
pub const MESSAGE: u16 = 100;

pub fn format_of(word: &str) -> String {
    capstan_wire::RecordKind::from_word(word)
        .expect(word)
        .format()
        .to_string()
}

pub fn firmware() -> Firmware {
    let formats: Vec<String> = WORDS.iter().map(|w| format_of(w)).collect();
    let mut table: Vec<(u16, &str, &str)> = formats
        .iter()
        .enumerate()
        .map(|(i, f)| {
            (
                i as u16 + 1,
                if i == 3 { "warn" } else { "info" },
                f.as_str(),
            )
        })
        .collect();
    table.push((MESSAGE, "info", "setup mode: amplifier at 0 V"));
    Firmware::from_formats("made-up", &table).unwrap()
}

enum V {
    U(u64),
    I(i64),
    F(f32),
}

fn settings_value(name: &str, s: &Settings) -> V {
    let (p, c) = (&s.protocol, &s.calibration);
    match name {
        "order" => V::U(p.order.code() as u64),
        "rest_deg" => V::F(p.rest_deg),
        "step_deg" => V::F(p.step_deg),
        "final_deg" => V::F(p.final_deg),
        "dwell_ms" => V::U(p.dwell_ms as u64),
        "pre_trigger_ms" => V::U(p.pre_trigger_ms as u64),
        "trigger_ms" => V::U(p.trigger_ms as u64),
        "tare_ms" => V::U(p.tare_ms as u64),
        "amp_control_v" => V::F(p.amp_control_v),
        "sample_hz" => V::U(p.sample_hz as u64),
        "raw_log_hz" => V::U(p.raw_log_hz as u64),
        "window_after_ms" => V::U(p.window_after_change_ms as u64),
        "window_before_ms" => V::U(p.window_before_next_ms as u64),
        "diameter_mm" => V::F(p.capstan_diameter_mm),
        "wrap_deg" => V::F(p.wrap_deg),
        "amp_gain" => V::F(c.amp.amp_gain),
        "t1_zero" => V::F(c.t1.zero_counts),
        "t1_n_per_count" => V::F(c.t1.n_per_count),
        "t2_zero" => V::F(c.t2.zero_counts),
        "t2_n_per_count" => V::F(c.t2.n_per_count),
        "tare_reference_n" => V::F(c.tare_reference_n),
        "servo_min_us" => V::F(c.servo.pulse_at_min_us),
        "servo_max_us" => V::F(c.servo.pulse_at_max_us),
        "servo_max_deg" => V::F(c.servo.max_deg),
        "amp_full_scale_v" => V::F(c.amp.full_scale_v),
        // Force control's (issue 43), as the settings hold them.
        name => match capstan_wire::Setting::from_name(name).map(|x| s.scalar(x)) {
            Some(capstan_wire::Scalar::F32(v)) => V::F(v),
            Some(capstan_wire::Scalar::U8(v)) => V::U(v.into()),
            Some(capstan_wire::Scalar::U32(v)) => V::U(v.into()),
            _ => panic!("no setting {name}"),
        },
    }
}

/// A record's field by name (`seq` and `crc` are the caller's).
fn value(name: &str, r: &Record) -> V {
    let stats = |s: &ChannelStats, what: &str| match what {
        "mean_n" => V::F(s.mean_n),
        "std_n" => V::F(s.std_n),
        _ => V::U(s.count as u64),
    };
    match (r, name) {
        (Record::RunStart(s), "run") => V::U(s.run as u64),
        (Record::RunStart(s), n) => settings_value(
            n,
            &Settings {
                protocol: s.protocol,
                calibration: s.calibration,
            },
        ),
        (Record::Settings(s), "source") => V::U(s.source.code() as u64),
        (Record::Settings(s), n) => settings_value(n, &s.settings),
        (Record::Live(l), "t_ms") => V::U(l.t_ms as u64),
        (Record::Live(l), "servo_deg") => V::F(l.servo_deg),
        (Record::Raw(r), "t_us") => V::I(r.t_us),
        (Record::Raw(r), "t2_target_n") => V::F(r.t2_target_n),
        (Record::Pair(p), "t2_target_n") => V::F(p.t2_target_n),
        (Record::Live(Live { counts, .. }) | Record::Raw(RawSample { counts, .. }), c)
            if c.starts_with('c') =>
        {
            V::U(counts[(c == "c2") as usize] as u64)
        }
        (Record::Live(Live { force_n, .. }) | Record::Raw(RawSample { force_n, .. }), n) => {
            V::F(force_n[(n == "t2_n") as usize])
        }
        (Record::Reply(r), "command") => V::U(r.command.code() as u64),
        (Record::Reply(r), "error") => V::U(r.error.map_or(0, |e| e.code()) as u64),
        (Record::Reply(r), v) => V::F(r.values[(v == "v2") as usize]),
        (Record::Pair(p), "step") => V::U(p.step as u64),
        (Record::Pair(p), "level") => V::U(p.level as u64),
        (Record::Pair(p), "angle_deg") => V::F(p.angle_deg),
        (Record::Pair(p), "t_mid_ms") => V::U(p.t_mid_ms as u64),
        (Record::Pair(p), n) if n.starts_with("t1_") => stats(&p.t1, &n[3..]),
        (Record::Pair(p), n) => stats(&p.t2, &n[3..]),
        (Record::Fault(f), "kind") => V::U(f.kind.code() as u64),
        (Record::Fault(f), "channel") => V::U(f.channel.map_or(NONE_CODE, |c| c as u8) as u64),
        (Record::Fault(f), "value") => V::F(f.value),
        (Record::Fault(f), _) => V::I(f.t_us),
        (Record::RunEnd(e), "t_us") => V::I(e.t_us),
        (Record::RunEnd(e), "pairs") => V::U(e.pairs as u64),
        (Record::RunEnd(e), _) => V::U(e.fault.map_or(NONE_CODE, |k| k.code()) as u64),
    }
}

fn word(r: &Record) -> usize {
    match r {
        Record::RunStart(_) => 0,
        Record::Raw(_) => 1,
        Record::Pair(_) => 2,
        Record::Fault(_) => 3,
        Record::RunEnd(_) => 4,
        Record::Settings(_) => 5,
        Record::Live(_) => 6,
        Record::Reply(_) => 7,
    }
}

/// The frame the firmware sends for a record (rzCOBS-encoded, with its separator).
pub fn frame(seq: u32, r: &Record) -> Vec<u8> {
    let w = word(r);
    let (bytes, crc) = frame_as(&format_of(WORDS[w]), w as u16 + 1, seq, r);
    // The CRC over the fields in format order is the firmware's own `record_crc`.
    assert_eq!(crc, record_crc(seq, r), "{}", WORDS[w]);
    bytes
}

/// A frame of `r` with the format `format` at table index `index`, and its CRC: the fields in
/// the format's order, the CRC over them in that order.
pub fn frame_as(format: &str, index: u16, seq: u32, r: &Record) -> (Vec<u8>, u32) {
    let mut bytes = index.to_le_bytes().to_vec();
    let mut crc = CrcFields::new();
    for field in format.split(' ').skip(1) {
        let (name, ty) = field.split_once("={=").unwrap();
        if name == "crc" {
            let sum = crc.finish();
            bytes.extend(sum.to_le_bytes());
            let mut out = rzcobs_encode(&bytes);
            out.push(0);
            return (out, sum);
        }
        let v = match name {
            "seq" => V::U(seq as u64),
            n => value(n, r),
        };
        crc = match (ty.trim_end_matches('}'), v) {
            ("u8", V::U(x)) => {
                bytes.push(x as u8);
                crc.u8(x as u8)
            }
            ("u16", V::U(x)) => {
                bytes.extend((x as u16).to_le_bytes());
                crc.u16(x as u16)
            }
            ("u32", V::U(x)) => {
                bytes.extend((x as u32).to_le_bytes());
                crc.u32(x as u32)
            }
            ("i64", V::I(x)) => {
                bytes.extend(x.to_le_bytes());
                crc.i64(x)
            }
            ("f32", V::F(x)) => {
                bytes.extend(x.to_le_bytes());
                crc.f32(x)
            }
            (t, _) => panic!("{name}: {t} does not match its value"),
        };
    }
    panic!("{format}: no crc field")
}

pub fn message_frame() -> Vec<u8> {
    let mut out = rzcobs_encode(&MESSAGE.to_le_bytes());
    out.push(0);
    out
}
