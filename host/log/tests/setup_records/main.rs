//! What `capstan log` makes of a stream in which the rig was set up from the host (`capstan
//! rig`): the setup-mode records (`settings`, `live`, `reply`) decoded to the firmware's own
//! records, checked by their CRC, counted in the sequence numbers, written to their files, and
//! never taken for a run. The frames are made here from the firmware's format strings (the
//! wire schema's, as `firmware/rig/src/defmt_sink.rs` writes them) and its `record_crc`, for a
//! table without an ELF (`Firmware::from_formats`).

#[path = "../support/mod.rs"]
mod log_support;

mod frames;

use capstan_link::{decode_all, Firmware};
use capstan_log::{LogOptions, Logger, SetupFlags, Stop};
use capstan_rig::command::{CommandError, CommandKind};
use capstan_rig::condition::ChannelStats;
use capstan_rig::hal::Channel;
use capstan_rig::record::{
    Fault, FaultKind, Live, RawSample, Record, Reply, RunEnd, RunStart, SettingsReport,
    SettingsSource, StepPair,
};
use capstan_rig::{Calibration, Protocol, Settings};
use frames::{firmware, format_of, frame, frame_as, message_frame, WORDS};
use log_support::{fresh_dir, rzcobs_encode};

fn bench_settings() -> Settings {
    let mut s = Settings {
        protocol: Protocol::default(),
        calibration: Calibration::default(),
    };
    s.protocol.capstan_diameter_mm = 12.7;
    s.protocol.wrap_deg = 360.0;
    s.calibration.servo.max_deg = 175.0;
    s.calibration.amp.full_scale_v = 3.2;
    s.calibration.tare_reference_n = 0.12;
    s
}

fn reply(command: CommandKind, error: Option<CommandError>, values: [f32; 2]) -> Record {
    Record::Reply(Reply {
        command,
        error,
        values,
    })
}

fn live(t_ms: u32) -> Record {
    Record::Live(Live {
        t_ms,
        counts: [412, 1012],
        force_n: [0.01, 9.80665],
        servo_deg: 95.0,
    })
}

fn pair(step: u32) -> Record {
    let stats = |mean_n| ChannelStats {
        mean_n,
        std_n: 0.02,
        count: 7000,
    };
    Record::Pair(StepPair {
        step,
        level: step,
        angle_deg: 125.0 - 5.0 * step as f32,
        t_mid_ms: 5000 + 10_000 * step,
        t1: stats(2.0 * step as f32),
        t2: stats(4.1 * step as f32),
        t2_target_n: 0.0,
    })
}

/// A bench session: boot, setup mode with live values (one lost), a fault in setup mode, its
/// ack, a store, then a run with a `show` in the middle of it.
fn session() -> Vec<(u32, Record)> {
    let s = bench_settings();
    let report = |source| {
        Record::Settings(SettingsReport {
            source,
            settings: s,
        })
    };
    let rail = Record::Fault(Fault {
        kind: FaultKind::SensorRail,
        channel: Some(Channel::T1),
        value: 4095.0,
        t_us: 3_500_000,
    });
    let start = Record::RunStart(RunStart {
        run: 1,
        protocol: s.protocol,
        calibration: s.calibration,
    });
    let raw = Record::Raw(RawSample {
        t_us: 10_000,
        counts: [540, 680],
        force_n: [2.0, 4.1],
        t2_target_n: 0.0,
    });
    let end = Record::RunEnd(RunEnd {
        t_us: 60_000_000,
        pairs: 2,
        fault: None,
    });
    let records = vec![
        report(SettingsSource::Loaded),
        reply(CommandKind::Setup, None, [125.0, 0.0]),
        live(1000),
        live(1100),
        live(1200), // lost
        live(1300),
        rail,
        reply(CommandKind::Ack, None, [0.0; 2]),
        reply(CommandKind::Jog, Some(CommandError::NotInSetup), [0.0; 2]),
        report(SettingsSource::Stored),
        reply(CommandKind::Store, None, [0.0; 2]),
        reply(CommandKind::Run, None, [1.0, 30.0]),
        start,
        raw,
        pair(1),
        report(SettingsSource::Current),
        reply(CommandKind::Show, None, [0.0; 2]),
        pair(2),
        end,
    ];
    records
        .into_iter()
        .enumerate()
        .map(|(i, r)| (i as u32, r))
        .collect()
}

/// The stream of the session, without the records whose sequence numbers are in `lost`, and
/// with a text message after the first reply.
fn stream(lost: &[u32]) -> Vec<u8> {
    let mut bytes = vec![0];
    for (seq, r) in session() {
        if !lost.contains(&seq) {
            bytes.extend(frame(seq, &r));
        }
        if seq == 1 {
            bytes.extend(message_frame());
        }
    }
    bytes
}

#[test]
fn every_setup_record_decodes_to_what_the_firmware_sent() {
    let fw = firmware();
    let (events, d) = decode_all(&fw, &stream(&[]));
    assert_eq!(d.bad_frames, 0, "{:?}", d.bad_examples);
    let got: Vec<(u32, Record)> = events
        .iter()
        .filter_map(|e| e.event.record().map(|(s, r)| (s, *r)))
        .collect();
    assert_eq!(got, session());
    assert_eq!(d.messages, 1);
}

#[test]
fn a_corrupted_setup_record_is_refused_by_its_checksum() {
    let fw = firmware();
    let r = reply(CommandKind::Zero, None, [412.3, 388.1]);
    let good = frame(3, &r);
    // v1's first byte, in the frame before rzCOBS: index 2 + seq 4 + command 1 + error 1.
    let mut body = capstan_link::stream::rzcobs_decode(&good[..good.len() - 1]).unwrap();
    body[8] ^= 0x01;
    let mut bad = rzcobs_encode(&body);
    bad.push(0);
    let (_, d) = decode_all(&fw, &bad);
    assert_eq!(d.bad_frames, 1);
    assert!(
        d.bad_examples[0].reason.contains("checksum mismatch"),
        "{:?}",
        d.bad_examples
    );
}

#[test]
fn the_log_keeps_setup_records_apart_from_runs_and_counts_them_in_the_sequence() {
    let fw = firmware();
    let dir = fresh_dir("rig", "setup-session");
    let opts = LogOptions {
        out_dir: dir.clone(),
        overwrite: false,
        save_stream: false,
        setup: SetupFlags::default(),
        progress: false,
        allow_empty: true,
        kept_after_failure: |_| {},
    };
    let mut logger = Logger::create(&fw, opts, "test", Box::new(|_| {})).unwrap();
    for chunk in stream(&[4]).chunks(29) {
        logger.feed(chunk).unwrap();
    }
    let summary = logger.finish(&Stop::EndOfStream).unwrap();
    // The lost live reading is a gap like any other.
    assert_eq!(summary.missing_records, 1);
    assert_eq!((summary.gaps[0].after_seq, summary.gaps[0].missing), (3, 1));
    let r = &summary.records;
    assert_eq!((r.settings, r.live, r.reply), (3, 3, 6));
    assert_eq!((r.run_start, r.pair, r.fault, r.run_end), (1, 2, 1, 1));
    // One run, complete, from its run_start on: the setup fault and the show in the middle of
    // the run did not open or split one.
    assert_eq!(summary.runs.len(), 1);
    let run = &summary.runs[0];
    assert!(run.complete);
    assert_eq!(
        (run.run, run.first_seq, run.pairs, run.faults),
        (Some(1), 12, 2, 0)
    );
    let cal = run.calibration.as_ref().expect("from run_start");
    assert_eq!(cal.get("servo_max_deg"), Some(175.0));
    assert_eq!(cal.get("amp_full_scale_v"), Some(3.2));
    assert_eq!(cal.get("tare_reference_n"), Some(0.12));
    assert!(summary
        .human(&dir)
        .join("\n")
        .contains("setup mode: 3 settings report(s)"));
    let read = |name: &str| std::fs::read_to_string(dir.join(name)).unwrap();
    let settings = read("settings.csv");
    let lines: Vec<&str> = settings.lines().collect();
    assert_eq!(lines.len(), 4, "{settings}");
    assert!(
        lines[0].starts_with("seq,source,order,rest_deg,"),
        "{}",
        lines[0]
    );
    assert!(
        lines[0].contains(",servo_max_deg,amp_full_scale_v,mode,")
            && lines[0].ends_with(",model_exponent,t1_cal,t1_cal_zero,t2_cal,t2_cal_zero"),
        "{}",
        lines[0]
    );
    assert!(
        lines[1].starts_with("0,loaded,monotone,125,"),
        "{}",
        lines[1]
    );
    assert!(lines[2].starts_with("9,stored,") && lines[3].starts_with("15,changed,"));
    let live = read("live.csv");
    assert_eq!(live.lines().count(), 1 + 3);
    assert_eq!(live.lines().nth(1), Some("2,1,412,1012,0.01,9.80665,95"));
    let faults = read("faults.csv");
    assert_eq!(
        faults.lines().nth(1),
        Some(",6,3.5,sensor_unplugged,t1,4095")
    );
    let messages = read("messages.txt");
    for needle in [
        "REPLY seq=1 setup: in setup mode, servo at 125.0°",
        "INFO setup mode: amplifier at 0 V",
        "REPLY seq=8 jog: refused: this works in setup mode only",
        "REPLY seq=10 store: the settings are stored in flash",
        "REPLY seq=11 run: run 1 armed: press the rig's button within 30 s",
    ] {
        assert!(messages.contains(needle), "{needle:?} not in:\n{messages}");
    }
    let pairs = capstan_data::load_pairs(&dir.join("pairs.csv")).unwrap();
    assert_eq!(pairs.pairs.len(), 2);
    assert!(pairs.pairs.iter().all(|p| p.run == Some(1.0)));
}

#[test]
fn a_firmware_without_the_setup_records_still_loads_but_one_without_a_run_record_does_not() {
    let run_only: Vec<String> = WORDS[..5].iter().map(|w| format_of(w)).collect();
    let table: Vec<(u16, &str, &str)> = run_only
        .iter()
        .enumerate()
        .map(|(i, f)| (i as u16 + 1, "info", f.as_str()))
        .collect();
    assert!(Firmware::from_formats("old", &table).is_ok());
    let e = Firmware::from_formats("no-pair", &[table[0], table[1], table[3], table[4]])
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("lacks the rig record(s) pair"), "{e}");
}

#[test]
fn a_run_start_without_the_newer_calibration_fields_leaves_them_null_in_the_summary() {
    // A firmware built before setup mode: its run_start lacks the tare reference, servo map
    // and amplifier full scale.
    let mut old = format_of("run_start");
    for name in [
        "tare_reference_n",
        "servo_min_us",
        "servo_max_us",
        "servo_max_deg",
        "amp_full_scale_v",
    ] {
        old = old.replace(&format!(" {name}={{=f32}}"), "");
    }
    let run_words: Vec<String> = WORDS[1..5].iter().map(|w| format_of(w)).collect();
    let mut table: Vec<(u16, &str, &str)> = vec![(1, "info", old.as_str())];
    for (i, f) in run_words.iter().enumerate() {
        table.push((i as u16 + 2, "info", f.as_str()));
    }
    let fw = Firmware::from_formats("old", &table).unwrap();
    let s = bench_settings();
    let start = Record::RunStart(RunStart {
        run: 1,
        protocol: s.protocol,
        calibration: s.calibration,
    });
    let mut bytes = vec![0];
    bytes.extend(frame_as(&old, 1, 0, &start).0);
    let dir = fresh_dir("rig", "old-run-start");
    let opts = LogOptions {
        out_dir: dir.clone(),
        overwrite: false,
        save_stream: false,
        setup: SetupFlags::default(),
        progress: false,
        allow_empty: true,
        kept_after_failure: |_| {},
    };
    let mut logger = Logger::create(&fw, opts, "old", Box::new(|_| {})).unwrap();
    logger.feed(&bytes).unwrap();
    let summary = logger.finish(&Stop::EndOfStream).unwrap();
    assert_eq!(summary.bad_frames, 0, "{:?}", summary.bad_frame_examples);
    let cal = summary.runs[0]
        .calibration
        .as_ref()
        .expect("from run_start");
    assert_eq!(cal.get("t1_n_per_count"), Some(0.015));
    assert_eq!(cal.get("amp_gain"), Some(4.0));
    assert_eq!(cal.get("servo_max_deg"), None);
    assert_eq!(cal.get("tare_reference_n"), None);
    assert_eq!(cal.get("amp_full_scale_v"), None);
}
