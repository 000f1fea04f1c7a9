//! Round trips through the record decoder for the setup-mode records and the longer
//! `run_start`, with their format strings from the wire schema (`capstan-wire`, which the
//! firmware's defmt calls are written from) and their checksums from the firmware's own
//! `record_crc`:
//! a field renamed, reordered or left out of the checksum on either side fails here.

use super::{record_from_values, Event};
use crate::elf::{record_layout, RecordLayout};
use capstan_rig::command::{CommandError, CommandKind};
use capstan_rig::record::{
    record_crc, CrcFields, Live, Record, Reply, RunStart, SettingsReport, SettingsSource,
};
use capstan_rig::{Calibration, Protocol, Settings, StepOrder};

/// The format string of a record kind, as the wire schema gives it (the firmware's defmt calls
/// are written from the same table by `firmware/rig/build.rs`).
fn format_of(word: &str) -> String {
    capstan_wire::RecordKind::from_word(word)
        .unwrap_or_else(|| panic!("no `{word}` record in the wire schema"))
        .format()
        .to_string()
}

fn layout(format: &str) -> RecordLayout {
    record_layout(format)
        .expect("a record format")
        .unwrap_or_else(|e| panic!("{e}: {format}"))
}

fn bench_settings() -> Settings {
    let mut s = Settings {
        protocol: Protocol::default(),
        calibration: Calibration::default(),
    };
    s.protocol.order = StepOrder::UpDown;
    s.protocol.capstan_diameter_mm = 25.4;
    s.protocol.wrap_deg = 360.0;
    s.calibration.t1.zero_counts = 412.3;
    s.calibration.t2.n_per_count = 0.0163;
    s.calibration.tare_reference_n = 0.12;
    s.calibration.servo.pulse_at_min_us = 510.0;
    s.calibration.servo.pulse_at_max_us = 2490.0;
    s.calibration.servo.max_deg = 175.0;
    s.calibration.amp.full_scale_v = 3.2;
    s
}

/// A field's value by name, as defmt-decoder renders it (`crc` excluded).
fn field(name: &str, seq: u32, record: &Record) -> String {
    if name == "seq" {
        return seq.to_string();
    }
    let settings = |s: &Settings| settings_field(name, s);
    match record {
        Record::RunStart(r) if name == "run" => r.run.to_string(),
        Record::RunStart(r) => settings(&Settings {
            protocol: r.protocol,
            calibration: r.calibration,
        }),
        Record::Settings(r) if name == "source" => r.source.code().to_string(),
        Record::Settings(r) => settings(&r.settings),
        Record::Live(l) => match name {
            "t_ms" => l.t_ms.to_string(),
            "c1" => l.counts[0].to_string(),
            "c2" => l.counts[1].to_string(),
            "t1_n" => l.force_n[0].to_string(),
            "t2_n" => l.force_n[1].to_string(),
            "servo_deg" => l.servo_deg.to_string(),
            _ => panic!("live has no {name}"),
        },
        Record::Reply(r) => match name {
            "command" => r.command.code().to_string(),
            "error" => r.error.map_or(0, |e| e.code()).to_string(),
            "v1" => r.values[0].to_string(),
            "v2" => r.values[1].to_string(),
            _ => panic!("reply has no {name}"),
        },
        _ => panic!("not a record of this test"),
    }
}

fn settings_field(name: &str, s: &Settings) -> String {
    let (p, c) = (&s.protocol, &s.calibration);
    let f = |v: f32| v.to_string();
    match name {
        "order" => p.order.code().to_string(),
        "rest_deg" => f(p.rest_deg),
        "step_deg" => f(p.step_deg),
        "final_deg" => f(p.final_deg),
        "dwell_ms" => p.dwell_ms.to_string(),
        "pre_trigger_ms" => p.pre_trigger_ms.to_string(),
        "trigger_ms" => p.trigger_ms.to_string(),
        "tare_ms" => p.tare_ms.to_string(),
        "amp_control_v" => f(p.amp_control_v),
        "sample_hz" => p.sample_hz.to_string(),
        "raw_log_hz" => p.raw_log_hz.to_string(),
        "window_after_ms" => p.window_after_change_ms.to_string(),
        "window_before_ms" => p.window_before_next_ms.to_string(),
        "diameter_mm" => f(p.capstan_diameter_mm),
        "wrap_deg" => f(p.wrap_deg),
        "amp_gain" => f(c.amp.amp_gain),
        "t1_zero" => f(c.t1.zero_counts),
        "t1_n_per_count" => f(c.t1.n_per_count),
        "t2_zero" => f(c.t2.zero_counts),
        "t2_n_per_count" => f(c.t2.n_per_count),
        "tare_reference_n" => f(c.tare_reference_n),
        "servo_min_us" => f(c.servo.pulse_at_min_us),
        "servo_max_us" => f(c.servo.pulse_at_max_us),
        "servo_max_deg" => f(c.servo.max_deg),
        "amp_full_scale_v" => f(c.amp.full_scale_v),
        name => match capstan_wire::Setting::from_name(name) {
            // Force control's (issue 43), as the settings hold them.
            Some(setting) => match capstan_rig::settings::scalar(setting, s.get(setting)) {
                capstan_wire::Scalar::F32(v) => f(v),
                capstan_wire::Scalar::U8(v) => v.to_string(),
                capstan_wire::Scalar::U32(v) => v.to_string(),
                other => panic!("{name}: {other:?}"),
            },
            None => panic!("no settings field {name}"),
        },
    }
}

/// The values a frame of this record carries, in the layout's order, with the firmware's CRC.
fn values(layout: &RecordLayout, seq: u32, record: &Record) -> Vec<String> {
    let crc = record_crc(seq, record).to_string();
    layout
        .fields
        .iter()
        .map(|(n, _)| match n.as_str() {
            "crc" => crc.clone(),
            n => field(n, seq, record),
        })
        .collect()
}

fn round_trip(word: &str, seq: u32, record: Record) {
    let l = layout(&format_of(word));
    let got = record_from_values(&l, &values(&l, seq, &record));
    assert_eq!(got, Ok(Event::Record { seq, record }), "{word}");
}

#[test]
fn the_setup_records_and_the_full_run_start_decode_to_what_the_firmware_sent() {
    let s = bench_settings();
    for source in SettingsSource::ALL {
        let report = SettingsReport {
            source,
            settings: s,
        };
        round_trip("settings", 41, Record::Settings(report));
    }
    let live = Live {
        t_ms: 123_456,
        counts: [1012, 388],
        force_n: [9.80665, -0.02],
        servo_deg: 95.5,
    };
    round_trip("live", 7, Record::Live(live));
    let ok = Reply {
        command: CommandKind::Weigh,
        error: None,
        values: [0.0163, 1012.4],
    };
    round_trip("reply", 8, Record::Reply(ok));
    let refused = Reply {
        command: CommandKind::Unparsed,
        error: Some(CommandError::Unknown),
        values: [0.0; 2],
    };
    round_trip("reply", 9, Record::Reply(refused));
    let start = RunStart {
        run: 3,
        protocol: s.protocol,
        calibration: s.calibration,
    };
    round_trip("run_start", u32::MAX, Record::RunStart(start));
}

#[test]
fn a_changed_value_fails_the_checksum() {
    let l = layout(&format_of("reply"));
    let r = Record::Reply(Reply {
        command: CommandKind::Jog,
        error: None,
        values: [95.0, 0.0],
    });
    let mut v = values(&l, 5, &r);
    let at = l.position("v1").unwrap();
    v[at] = "96".into();
    let e = record_from_values(&l, &v).unwrap_err().to_string();
    assert!(e.contains("checksum mismatch"), "{e}");
    let l = layout(&format_of("settings"));
    let s = Record::Settings(SettingsReport {
        source: SettingsSource::Stored,
        settings: bench_settings(),
    });
    let mut v = values(&l, 6, &s);
    let at = l.position("servo_max_deg").unwrap();
    v[at] = "170".into();
    assert!(record_from_values(&l, &v).is_err());
}

#[test]
fn codes_the_firmware_does_not_know_are_refused() {
    let l = layout(&format_of("reply"));
    let r = Record::Reply(Reply {
        command: CommandKind::Zero,
        error: None,
        values: [412.3, 388.1],
    });
    let mut v = values(&l, 5, &r);
    let at = l.position("command").unwrap();
    v[at] = "99".into();
    // Checksum over the changed value, so only the code is wrong.
    let crc_at = l.position("crc").unwrap();
    v[crc_at] = crc_over(&l, &v).to_string();
    let e = record_from_values(&l, &v).unwrap_err().to_string();
    assert!(e.contains("unknown command code 99"), "{e}");
}

/// The CRC of a frame's values, in format order (for records this test builds by hand).
fn crc_over(l: &RecordLayout, v: &[String]) -> u32 {
    use crate::elf::Prim;
    let mut c = CrcFields::new();
    for ((name, prim), v) in l.fields.iter().zip(v).filter(|((n, _), _)| n != "crc") {
        let bad = || format!("{name} = {v}");
        c = match prim {
            Prim::U8 => c.u8(v.parse().unwrap_or_else(|_| panic!("{}", bad()))),
            Prim::U16 => c.u16(v.parse().unwrap_or_else(|_| panic!("{}", bad()))),
            Prim::U32 => c.u32(v.parse().unwrap_or_else(|_| panic!("{}", bad()))),
            Prim::I64 => c.i64(v.parse().unwrap_or_else(|_| panic!("{}", bad()))),
            Prim::F32 => c.f32(v.parse().unwrap_or_else(|_| panic!("{}", bad()))),
        };
    }
    c.finish()
}

#[test]
fn a_run_start_without_the_newer_calibration_fields_still_decodes() {
    let full = format_of("run_start");
    let mut old = full.clone();
    for name in [
        "tare_reference_n",
        "servo_min_us",
        "servo_max_us",
        "servo_max_deg",
        "amp_full_scale_v",
    ] {
        old = old.replace(&format!(" {name}={{=f32}}"), "");
    }
    assert_ne!(old, full);
    let l = layout(&old);
    let s = bench_settings();
    let start = RunStart {
        run: 1,
        protocol: s.protocol,
        calibration: s.calibration,
    };
    let mut v: Vec<String> = l
        .fields
        .iter()
        .map(|(n, _)| match n.as_str() {
            "crc" => String::new(),
            n => field(n, 2, &Record::RunStart(start)),
        })
        .collect();
    let crc_at = l.position("crc").unwrap();
    v[crc_at] = crc_over(&l, &v).to_string();
    let Ok(Event::Record {
        record: Record::RunStart(got),
        ..
    }) = record_from_values(&l, &v)
    else {
        panic!("not decoded");
    };
    assert_eq!(got.protocol, s.protocol);
    assert_eq!(got.calibration.t1, s.calibration.t1);
    assert_eq!(got.calibration.amp.amp_gain, s.calibration.amp.amp_gain);
    // Not sent: the firmware's defaults (not NaN, so records still compare equal).
    let d = Calibration::default();
    assert_eq!(got.calibration.tare_reference_n, d.tare_reference_n);
    assert_eq!(got.calibration.servo, d.servo);
    assert_eq!(got.calibration.amp.full_scale_v, d.amp.full_scale_v);
}

#[test]
fn a_setup_record_lacking_a_field_or_of_another_type_is_refused_when_the_elf_loads() {
    let settings = format_of("settings");
    let short = settings.replace(" servo_max_deg={=f32}", "");
    let e = record_layout(&short).unwrap().unwrap_err().to_string();
    assert!(e.contains("no field `servo_max_deg`"), "{e}");
    let live = format_of("live").replace(" crc={=u32}", "");
    let e = record_layout(&live).unwrap().unwrap_err().to_string();
    assert!(e.contains("no field `crc`"), "{e}");
    let run_start = format_of("run_start").replace("servo_min_us={=f32}", "servo_min_us={=u32}");
    let e = record_layout(&run_start).unwrap().unwrap_err().to_string();
    assert!(
        e.contains("field `servo_min_us` is U32, expected F32"),
        "{e}"
    );
}
