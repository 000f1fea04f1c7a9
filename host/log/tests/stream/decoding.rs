//! Decoding the recorded stream as it is; the framing; ELFs and tables that do not fit.

use crate::log_support::{self, firmware, rzcobs_decode, rzcobs_encode, split, stream};
use capstan_link::elf::MAX_PADDING;
use capstan_link::{decode_all, Event, Firmware};
use capstan_rig::record::Record;

#[test]
fn the_recorded_stream_decodes_completely() {
    let fw = firmware();
    let bytes = stream();
    let (events, d) = decode_all(&fw, &bytes);
    assert_eq!(d.bad_frames, 0, "{:?}", d.bad_examples);
    assert_eq!(d.frames_seen, 218);
    assert_eq!((d.records, d.messages), (211, 7));
    assert!(d.seq.gaps.is_empty() && d.seq.restarts.is_empty());
    assert_eq!((d.seq.first_seq, d.seq.last_seq), (Some(0), Some(210)));
    let mut kinds = [0; 5];
    let mut pairs = Vec::new();
    for e in &events {
        if let Event::Record { record, .. } = &e.event {
            let k = match record {
                Record::RunStart(s) => {
                    assert_eq!(s.protocol, capstan_qemu_fw::protocol());
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
                Record::Settings(_) | Record::Live(_) | Record::Reply(_) => {
                    panic!("the recorded runs have no setup-mode records: {record:?}")
                }
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
fn rzcobs_round_trips_up_to_padding() {
    let cases: Vec<Vec<u8>> = vec![
        vec![],
        vec![0],
        vec![1],
        vec![1, 0],
        vec![0, 1],
        vec![0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77],
        vec![0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x00],
        (1..=255).collect(),
        (0..600).map(|i| (i % 7) as u8).collect(),
        vec![5; 300],
    ];
    for data in cases {
        let enc = rzcobs_encode(&data);
        assert!(!enc.contains(&0), "{data:?}");
        let dec = capstan_link::stream::rzcobs_decode(&enc).unwrap();
        assert!(dec.len() >= data.len(), "{data:?}");
        assert_eq!(&dec[..data.len()], &data[..]);
        assert!(dec[data.len()..].iter().all(|&b| b == 0));
        assert!(dec.len() - data.len() <= MAX_PADDING);
    }
    assert!(capstan_link::stream::rzcobs_decode(&[0x11, 0x00]).is_err());
    assert!(capstan_link::stream::rzcobs_decode(&[0x01]).is_err());
    assert!(capstan_link::stream::rzcobs_decode(&[0x85]).is_err());
}

#[test]
fn a_wrong_elf_is_refused_with_the_reason() {
    let not_elf = log_support::data("qemu-run.defmt");
    let e = format!("{:#}", Firmware::load(&not_elf).err().unwrap());
    assert!(e.contains("qemu-run.defmt"), "{e}");
    // A host ELF, with no defmt in it: a small one (the test binary itself is one too, but a
    // release build with its debug information can pass the 256 MiB size limit).
    let host = ["/bin/true", "/usr/bin/true"]
        .into_iter()
        .map(std::path::PathBuf::from)
        .find(|p| p.exists())
        .unwrap_or_else(|| std::env::current_exe().unwrap());
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
