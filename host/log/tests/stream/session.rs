//! A whole session's files from a damaged stream, and from one joined mid-run.

use crate::log_support::{firmware, fresh_dir, split, stream};
use crate::record_seq;
use capstan_link::seq::Gap;
use capstan_link::{decode_all, Event};
use capstan_log::{LogError, LogOptions, Logger, Note, SetupFlags, Stop};
use capstan_rig::record::Record;
use std::cell::RefCell;
use std::rc::Rc;

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
    let dir = fresh_dir("test", "gap-files");
    let opts = LogOptions {
        out_dir: dir.clone(),
        overwrite: false,
        save_stream: true,
        setup: SetupFlags::default(),
        progress: true,
        allow_empty: true,
        kept_after_failure: |_| {},
    };
    // The session's progress comes back as notes, in order, as the records arrive.
    let notes = Rc::new(RefCell::new(Vec::new()));
    let said = Rc::clone(&notes);
    let mut logger = Logger::create(
        &fw,
        opts.clone(),
        "test",
        Box::new(move |n| said.borrow_mut().push(n)),
    )
    .unwrap();
    for chunk in damaged.chunks(37) {
        logger.feed(chunk).unwrap();
    }
    let summary = logger.finish(&Stop::EndOfStream).unwrap();
    assert_eq!(summary.missing_records, 1);
    assert_eq!(
        summary.gaps,
        [Gap {
            after_seq: record_seq(pair) - 1,
            missing: 1,
            resumed_at_seq: record_seq(pair) + 1,
            frame: pair.frame,
            byte_offset: pair.byte_offset,
        }]
    );
    assert!(!summary.is_clean());
    assert_eq!(summary.runs.len(), 2);
    assert_eq!(summary.runs[0].pairs, 2);
    assert_eq!(summary.runs[0].pairs_reported, Some(3));
    let human = summary.human(&dir).join("\n");
    assert!(
        human.contains(&format!(
            "LOST 1 record(s) in 1 gap(s): 1 after seq {}",
            record_seq(pair) - 1
        )),
        "{human}"
    );
    let pairs = capstan_data::load_pairs(&dir.join("pairs.csv")).unwrap();
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
    let notes: Vec<String> = (notes.borrow().iter())
        .map(|n| match n {
            Note::Session(s) => s.clone(),
            Note::Recovered(r) => panic!("nothing to recover in a fresh directory: {r}"),
        })
        .collect();
    let lost = format!(
        "LOST 1 record(s) after seq {} (byte {})",
        record_seq(pair) - 1,
        pair.byte_offset
    );
    let at = |line: &str| notes.iter().position(|n| n.starts_with(line));
    let (started, lost_at, ended) = (at("run 1 started"), at(&lost), at("run 1 ended"));
    assert!(
        started < lost_at && lost_at < ended && started.is_some(),
        "{notes:#?}"
    );
    let steps = notes.iter().filter(|n| n.contains(" step ")).count();
    assert_eq!(
        steps as u64, summary.records.pair,
        "one note per pair received"
    );
    assert!(
        notes.iter().any(|n| n.starts_with("FAULT over_force at")),
        "{notes:#?}"
    );
    // A second session into the same directory is refused, not mixed in.
    let err = Logger::create(&fw, opts, "test", Box::new(|_| {}))
        .err()
        .unwrap();
    assert!(
        matches!(&err, LogError::AlreadyLogged { existing, .. } if existing.contains(&"pairs.csv"))
    );
    assert!(
        err.to_string().contains("already holds a logged session"),
        "{err}"
    );
}

#[test]
fn joining_mid_run_keeps_the_records_without_their_run_start() {
    // Attaching to a running board: the stream starts mid-frame and mid-run.
    let fw = firmware();
    let bytes = stream();
    let late = &bytes[1001..];
    let dir = fresh_dir("test", "late");
    let opts = LogOptions {
        out_dir: dir.clone(),
        overwrite: false,
        save_stream: false,
        setup: SetupFlags {
            wrap_deg: Some(360.0),
            ..SetupFlags::default()
        },
        progress: false,
        allow_empty: true,
        kept_after_failure: |_| {},
    };
    let mut logger = Logger::create(&fw, opts, "late", Box::new(|_| {})).unwrap();
    logger.feed(late).unwrap();
    let summary = logger.finish(&Stop::EndOfStream).unwrap();
    assert_eq!(summary.bad_frames, 1, "the frame cut by joining");
    assert!(summary.first_seq.unwrap() > 0);
    assert_eq!(summary.runs[0].run, None);
    assert!(summary
        .human(&dir)
        .join("\n")
        .contains("joins the board at seq"));
    // Run 1's pairs have no run number (nor the record's diameter and drive voltage): they are
    // kept apart; run 2's are complete and go to pairs.csv, which `capstan analyze` reads.
    assert_eq!(summary.pairs_incomplete, summary.runs[0].pairs);
    assert!(summary.pairs_incomplete > 0);
    assert!(summary
        .human(&dir)
        .join("\n")
        .contains("pairs-incomplete.csv"));
    let incomplete = std::fs::read_to_string(dir.join("pairs-incomplete.csv")).unwrap();
    let first = incomplete.lines().nth(1).unwrap();
    assert!(first.starts_with(",360,,,"), "{first}");
    let pairs = capstan_data::load_pairs(&dir.join("pairs.csv")).unwrap();
    assert!(pairs.pairs.iter().all(|p| p.run == Some(2.0)));
    assert_eq!(pairs.pairs.len(), summary.runs[1].pairs as usize);
}
