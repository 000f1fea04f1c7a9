//! Damaged streams: records dropped (gaps counted and located), truncation at any byte,
//! corruption of any byte, and a board restart told from a gap.

use crate::log_support::{firmware, split, stream, Frames};
use crate::seqs;
use capstan_link::{decode_all, Event};
use capstan_rig::record::Record;

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

/// Frame `k` with `side` frames either side (after the stream's lead), and where frame `k`'s
/// bytes are in it.
fn window(frames: &Frames, k: usize, side: usize) -> (Vec<u8>, std::ops::Range<usize>) {
    let mut bytes = frames.lead.clone();
    let mut at = 0..0;
    for w in k.saturating_sub(side)..(k + side + 1).min(frames.frames.len()) {
        if w == k {
            at = bytes.len()..bytes.len() + frames.frames[w].1.len();
        }
        bytes.extend_from_slice(&frames.frames[w].1);
    }
    (bytes, at)
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
        let (clean, bytes_of_k) = window(&frames, k, 2);
        let base = decode_all(&fw, &clean).1.records;
        for i in bytes_of_k {
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

/// The records of a decoded stream, with their sequence numbers.
fn records(fw: &capstan_link::Firmware, bytes: &[u8]) -> (Vec<(u32, Record)>, bool) {
    let (events, d) = decode_all(fw, bytes);
    let recs = events
        .into_iter()
        .filter_map(|e| match e.event {
            Event::Record { seq, record } => Some((seq, record)),
            _ => None,
        })
        .collect();
    (recs, d.bad_frames > 0 || d.seq.missing_records > 0)
}

#[test]
fn every_single_bit_flip_of_a_record_is_detected_or_harmless() {
    // Each record carries a CRC-32 of its fields: a flipped bit anywhere in the stream either
    // leaves the records as they were (a flip in a text message, or one rzCOBS absorbs) or is
    // seen (a bad frame or a sequence gap, which `--strict` fails on). Before the checksum,
    // 2,876 of 4,671 such flips changed the output silently (wrap_deg 360 -> 90).
    let fw = firmware();
    let frames = split(&stream());
    let (mut cases, mut seen) = (0, 0);
    for k in 0..frames.frames.len() {
        let (clean, bytes_of_k) = window(&frames, k, 1);
        let (base, damaged) = records(&fw, &clean);
        assert!(!damaged);
        for i in bytes_of_k {
            for bit in 0..8 {
                let mut b = clean.clone();
                b[i] ^= 1 << bit;
                let (got, detected) = records(&fw, &b);
                cases += 1;
                seen += usize::from(detected);
                assert!(
                    detected || got == base,
                    "frame {k}, byte {i}, bit {bit}: the records changed silently"
                );
            }
        }
    }
    assert!(cases > 40_000, "{cases}");
    assert!(seen > cases / 2, "{seen} of {cases}");
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
