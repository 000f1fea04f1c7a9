//! `capstan log`'s decoder on a recorded stream (a QEMU run of the rig firmware, kept in
//! tests/data with the ELF that made it): clean decoding, records dropped from the stream
//! (sequence gaps counted and located), truncation, corruption, a wrong ELF and a stream from
//! another firmware.

mod log_support;

use capstan::log::output::{LogOptions, Logger, SetupFlags, Stop};
use capstan::log::seq::Gap;
use capstan::log::{decode_all, Event, Firmware};
use firmware::record::Record;
use log_support::{firmware, rzcobs_decode, rzcobs_encode, split, stream};

fn seqs(fw: &Firmware, bytes: &[u8]) -> Vec<u32> {
    decode_all(fw, bytes)
        .0
        .into_iter()
        .filter_map(|l| match l.event {
            Event::Record { seq, .. } => Some(seq),
            _ => None,
        })
        .collect()
}

#[test]
fn the_recorded_stream_decodes_completely() {
    let fw = firmware();
    let bytes = stream();
    let (events, d) = decode_all(&fw, &bytes);
    assert_eq!(d.bad_frames, 0, "{:?}", d.bad_examples);
    assert_eq!(d.frames_seen, 217);
    assert_eq!((d.records, d.messages), (211, 6));
    assert!(d.seq.gaps.is_empty() && d.seq.restarts.is_empty());
    assert_eq!((d.seq.first_seq, d.seq.last_seq), (Some(0), Some(210)));
    let mut kinds = [0; 5];
    let mut pairs = Vec::new();
    for e in &events {
        if let Event::Record { record, .. } = &e.event {
            let k = match record {
                Record::RunStart(s) => {
                    assert_eq!(s.protocol, qemu_fw::protocol());
                    0
                }
                Record::Raw(_) => 1,
                Record::Pair(p) => {
                    pairs.push(*p);
                    2
                }
                Record::Fault(f) => {
                    assert_eq!(f.kind.name(), "over_force");
                    3
                }
                Record::RunEnd(_) => 4,
            };
            kinds[k] += 1;
        }
    }
    assert_eq!(kinds, [2, 202, 4, 1, 2]);
    // Euler-Eytelwein at mu 0.115 over 360°: T2/T1 = e^(0.115·2π) = 2.06.
    for p in &pairs {
        let amp = p.t2.mean_n / p.t1.mean_n;
        assert!((amp - 2.06).abs() < 0.1, "{p:?}");
    }
    let messages: Vec<&str> = events
        .iter()
        .filter_map(|e| match &e.event {
            Event::Message { text, .. } => Some(text.as_str()),
            _ => None,
        })
        .collect();
    // The banner: a byte string, a slice and a nested struct, as defmt-decoder renders them.
    assert!(
        messages[0].starts_with(
            "qemu-fw b\"capstan\": 2 runs, plant seeds [7161128523671891462, \
             7161128523671891463], protocol Protocol { rest_deg: 125.0,"
        ),
        "{}",
        messages[0]
    );
    assert_eq!(messages[1], "run 1: button pressed, taring");
}

#[test]
fn re_encoding_the_decoded_frames_gives_back_the_recorded_bytes() {
    // Checks the tests' rzCOBS encoder against defmt's own output, frame by frame.
    let frames = split(&stream());
    for (offset, f) in &frames.frames {
        let body = &f[..f.len() - 1];
        assert_eq!(
            rzcobs_encode(&rzcobs_decode(body)),
            body,
            "frame at byte {offset}"
        );
    }
}

#[test]
fn dropped_frames_are_counted_and_located() {
    let fw = firmware();
    let frames = split(&stream());
    let original = seqs(&fw, &frames.without(&[]));
    // Frame numbers of some records: a single raw sample, a run of five, and the run-end of
    // run 1 together with the run-start of run 2 (the frame between them is a text message).
    let at = |seq: u32| {
        let (events, _) = decode_all(&fw, &frames.without(&[]));
        events
            .iter()
            .find(|e| matches!(e.event, Event::Record { seq: s, .. } if s == seq))
            .map(|e| e.frame as usize)
            .unwrap()
    };
    let single = at(40);
    let run: Vec<usize> = (100..105).map(at).collect();
    let end_of_run_1 = decode_all(&fw, &stream())
        .0
        .iter()
        .find_map(|e| match e.event {
            Event::Record {
                seq,
                record: Record::RunEnd(_),
            } => Some(seq),
            _ => None,
        })
        .unwrap();
    assert_eq!(original.len(), 211);
    let mut drop = vec![single];
    drop.extend(&run);
    drop.push(at(end_of_run_1));
    drop.push(at(end_of_run_1 + 1));
    let damaged = frames.without(&drop);
    let (events, d) = decode_all(&fw, &damaged);
    assert_eq!(d.bad_frames, 0);
    assert_eq!(d.records, 211 - 8);
    assert_eq!(d.seq.missing_records, 8);
    let gaps: Vec<(u32, u32, u32)> = d
        .seq
        .gaps
        .iter()
        .map(|g| (g.after_seq, g.missing, g.resumed_at_seq))
        .collect();
    assert_eq!(
        gaps,
        [
            (39, 1, 41),
            (99, 5, 105),
            (end_of_run_1 - 1, 2, end_of_run_1 + 2)
        ]
    );
    // Each gap points at the frame and the byte where the stream resumed.
    for g in &d.seq.gaps {
        let e = events
            .iter()
            .find(|e| matches!(e.event, Event::Record { seq, .. } if seq == g.resumed_at_seq))
            .unwrap();
        assert_eq!((g.frame, g.byte_offset), (e.frame, e.byte_offset));
        assert_eq!(damaged[g.byte_offset as usize - 1], 0, "{g:?}");
    }
}

#[test]
fn the_log_files_keep_everything_that_arrived_and_the_summary_says_what_did_not() {
    let fw = firmware();
    let frames = split(&stream());
    // Drop the first pair of run 1 (a record) and feed the rest in odd-sized chunks.
    let (events, _) = decode_all(&fw, &stream());
    let pair = events
        .iter()
        .find(|e| {
            matches!(
                e.event,
                Event::Record {
                    record: Record::Pair(_),
                    ..
                }
            )
        })
        .unwrap();
    let damaged = frames.without(&[pair.frame as usize]);
    let dir = tempdir("gap-files");
    let opts = LogOptions {
        out_dir: dir.clone(),
        overwrite: false,
        save_stream: true,
        setup: SetupFlags::default(),
        progress: false,
    };
    let mut logger = Logger::create(&fw, opts.clone(), "test").unwrap();
    for chunk in damaged.chunks(37) {
        logger.feed(chunk).unwrap();
    }
    let summary = logger.finish(&Stop::EndOfStream).unwrap();
    assert_eq!(summary.missing_records, 1);
    assert_eq!(
        summary.gaps,
        [Gap {
            after_seq: pair_seq(pair) - 1,
            missing: 1,
            resumed_at_seq: pair_seq(pair) + 1,
            frame: pair.frame,
            byte_offset: pair.byte_offset,
        }]
    );
    assert!(!summary.is_clean());
    assert_eq!(summary.runs.len(), 2);
    assert_eq!(summary.runs[0].pairs, 2);
    assert_eq!(summary.runs[0].pairs_reported, Some(3));
    let human = summary.human(&dir);
    assert!(
        human.contains(&format!(
            "LOST 1 record(s) in 1 gap(s): 1 after seq {}",
            pair_seq(pair) - 1
        )),
        "{human}"
    );
    let pairs = capstan::data::load_pairs(&dir.join("pairs.csv")).unwrap();
    assert_eq!(pairs.pairs.len(), 3);
    assert_eq!(pairs.pairs[0].step, Some(2.0));
    assert_eq!(pairs.pairs[0].wrap_deg, 360.0);
    assert_eq!(pairs.pairs[0].capstan_diameter_mm, Some(12.7));
    assert_eq!(pairs.pairs[0].drive_v, Some(10.0));
    let raw = std::fs::read_to_string(dir.join("raw.csv")).unwrap();
    assert_eq!(raw.lines().count(), 1 + 202);
    let faults = std::fs::read_to_string(dir.join("faults.csv")).unwrap();
    assert_eq!(
        faults.lines().nth(1).unwrap().split(',').nth(3),
        Some("over_force")
    );
    assert_eq!(std::fs::read(dir.join("stream.defmt")).unwrap(), damaged);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(json["missing_records"], 1);
    assert_eq!(json["gaps"][0]["missing"], 1);
    // A second session into the same directory is refused, not mixed in.
    let err = Logger::create(&fw, opts, "test").err().unwrap().to_string();
    assert!(err.contains("already holds a logged session"), "{err}");
}

fn pair_seq(l: &capstan::log::Located) -> u32 {
    match l.event {
        Event::Record { seq, .. } => seq,
        _ => unreachable!(),
    }
}

fn tempdir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("capstan-log-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

#[test]
fn a_truncated_stream_keeps_every_whole_frame_and_reports_the_rest() {
    let fw = firmware();
    let bytes = stream();
    let frames = split(&bytes);
    let mut last = 0;
    // Cut points: every byte of the first and last frames, either side of every separator,
    // and every 13th byte. Nothing panics, records only ever grow, and the unfinished frame
    // is reported with its offset.
    let mut cuts: Vec<usize> = (0..=bytes.len()).step_by(13).collect();
    cuts.extend(0..120);
    cuts.extend(bytes.len() - 120..=bytes.len());
    for (o, f) in &frames.frames {
        cuts.extend([o + f.len() - 1, o + f.len(), o + f.len() + 1]);
    }
    cuts.retain(|&c| c <= bytes.len());
    cuts.sort();
    cuts.dedup();
    for cut in cuts {
        let (_, mut d) = decode_all(&fw, &bytes[..cut]);
        assert!(d.records >= last, "cut {cut}");
        last = d.records;
        assert_eq!(d.bad_frames, 0, "cut {cut}: {:?}", d.bad_examples);
        let tail = d.finish();
        let inside = frames
            .frames
            .iter()
            .find(|(o, f)| cut > *o && cut < o + f.len());
        assert_eq!(
            tail,
            inside.map(|(o, _)| (*o as u64, (cut - o) as u64)),
            "cut {cut}"
        );
    }
    assert_eq!(last, 211);
}

#[test]
fn corrupted_bytes_cost_frames_not_the_stream() {
    let fw = firmware();
    let frames = split(&stream());
    // Every single-byte corruption of every frame (the byte set to 0x00, to 0xff, and
    // flipped), decoded with two frames either side: the decoder resynchronises at the next
    // separator, so at most the two frames the byte can touch are lost, and every lost record
    // is visible as a bad frame or a sequence gap.
    let mut worst = 0;
    let mut cases = 0;
    for k in 0..frames.frames.len() {
        let window: Vec<usize> = (k.saturating_sub(2)..(k + 3).min(frames.frames.len())).collect();
        let mut clean = frames.lead.clone();
        for &w in &window {
            clean.extend_from_slice(&frames.frames[w].1);
        }
        let base = decode_all(&fw, &clean).1.records;
        let start = frames.lead.len()
            + window
                .iter()
                .take_while(|&&w| w < k)
                .map(|&w| frames.frames[w].1.len())
                .sum::<usize>();
        for i in start..start + frames.frames[k].1.len() {
            for v in [0x00, 0xff, clean[i] ^ 0x5a] {
                if v == clean[i] {
                    continue;
                }
                let mut b = clean.clone();
                b[i] = v;
                let (_, d) = decode_all(&fw, &b);
                let lost = base.saturating_sub(d.records);
                worst = worst.max(lost);
                cases += 1;
                assert!(
                    lost <= 2,
                    "frame {k}, byte {i} := {v:#x}: {lost} records lost"
                );
                if lost > 0 {
                    assert!(
                        d.bad_frames > 0 || d.seq.missing_records > 0,
                        "frame {k}, byte {i} := {v:#x}: a record vanished without trace"
                    );
                }
            }
        }
    }
    assert!(cases > 10_000, "{cases}");
    assert!(worst >= 1);
}

#[test]
fn a_wrong_elf_is_refused_with_the_reason() {
    let not_elf = log_support::data("qemu-run.defmt");
    let e = format!("{:#}", Firmware::load(&not_elf).err().unwrap());
    assert!(e.contains("qemu-run.defmt"), "{e}");
    // The test binary itself: an ELF, but no defmt in it.
    let host = std::env::current_exe().unwrap();
    let e = format!("{:#}", Firmware::load(&host).err().unwrap());
    assert!(e.contains("has no defmt table"), "{e}");
    let e = format!(
        "{:#}",
        Firmware::load(std::path::Path::new("/nonexistent/fw.elf"))
            .err()
            .unwrap()
    );
    assert!(
        e.contains("cannot read the firmware ELF /nonexistent/fw.elf"),
        "{e}"
    );
    // A truncated ELF: every cut of the first 4 KiB is refused (or loads), never a panic.
    let elf = std::fs::read(log_support::elf_path()).unwrap();
    for cut in (0..4096).step_by(7) {
        let _ = Firmware::from_elf_bytes(&elf[..cut], "cut.elf");
    }
}

/// What decoding a stream with the wrong table looks like: another build of the firmware
/// numbers its format strings differently (any string added or removed shifts them). Shift
/// every frame's format index and decode with the recorded ELF.
#[test]
fn a_stream_from_another_firmware_is_not_taken_for_rig_records() {
    let fw = firmware();
    let frames = split(&stream());
    for shift in [1u16, 2, 3, 5, 8] {
        let mut other = frames.lead.clone();
        for (_, f) in &frames.frames {
            let mut body = rzcobs_decode(&f[..f.len() - 1]);
            let index = u16::from_le_bytes([body[0], body[1]]).wrapping_add(shift);
            body[..2].copy_from_slice(&index.to_le_bytes());
            other.extend(rzcobs_encode(&body));
            other.push(0);
        }
        let (_, d) = decode_all(&fw, &other);
        assert!(
            d.bad_frames as f64 >= 0.9 * d.frames_seen as f64,
            "shift {shift}: only {} of {} frames refused",
            d.bad_frames,
            d.frames_seen
        );
    }
}

#[test]
fn a_board_restart_is_told_from_a_gap() {
    // Two sessions back to back, as when the board resets while logging: numbering starts
    // again at 0. That is a restart, not 4 billion lost records.
    let fw = firmware();
    let mut bytes = stream();
    bytes.extend(stream());
    let (_, d) = decode_all(&fw, &bytes);
    assert_eq!(d.records, 422);
    assert!(d.seq.gaps.is_empty());
    assert_eq!(d.seq.restarts.len(), 1);
    assert_eq!(d.seq.restarts[0].after_seq, 210);
    assert_eq!(d.bad_frames, 0);
}

#[test]
fn joining_mid_run_keeps_the_records_without_their_run_start() {
    // Attaching to a running board: the stream starts mid-frame and mid-run.
    let fw = firmware();
    let bytes = stream();
    let late = &bytes[1001..];
    let dir = tempdir("late");
    let opts = LogOptions {
        out_dir: dir.clone(),
        overwrite: false,
        save_stream: false,
        setup: SetupFlags {
            wrap_deg: Some(360.0),
            ..SetupFlags::default()
        },
        progress: false,
    };
    let mut logger = Logger::create(&fw, opts, "late").unwrap();
    logger.feed(late).unwrap();
    let summary = logger.finish(&Stop::EndOfStream).unwrap();
    assert_eq!(summary.bad_frames, 1, "the frame cut by joining");
    assert!(summary.first_seq.unwrap() > 0);
    assert_eq!(summary.runs[0].run, None);
    assert!(summary.human(&dir).contains("joins the board at seq"));
    // Run 1's pairs have no run number (nor the record's diameter and drive voltage): they are
    // kept apart; run 2's are complete and go to pairs.csv, which `capstan analyze` reads.
    assert_eq!(summary.pairs_incomplete, summary.runs[0].pairs);
    assert!(summary.pairs_incomplete > 0);
    assert!(summary.human(&dir).contains("pairs-incomplete.csv"));
    let incomplete = std::fs::read_to_string(dir.join("pairs-incomplete.csv")).unwrap();
    let first = incomplete.lines().nth(1).unwrap();
    assert!(first.starts_with(",360,,,"), "{first}");
    let pairs = capstan::data::load_pairs(&dir.join("pairs.csv")).unwrap();
    assert!(pairs.pairs.iter().all(|p| p.run == Some(2.0)));
    assert_eq!(pairs.pairs.len(), summary.runs[1].pairs as usize);
}
