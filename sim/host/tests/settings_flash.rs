//! A damaged settings record is never used: flip bits all over the stored flash and boot the
//! simulated board on it. It must come up with exactly the newest stored settings, or with
//! its built-in defaults and a `settings` record that says why; never with an older or a
//! damaged calibration.

use capstan_rig::record::{Record, SettingsReport, SettingsSource};
use capstan_rig::settings::Settings;
use capstan_rig::Rig;
use capstan_sim::flash::{RamFlash, ERASE_BYTES};
use capstan_sim::session::{run_session, SessionSpec, Step, FLASH_PAGES};

fn send(line: &str) -> Step {
    Step::Send(line.to_string())
}

fn boot_report(spec: &SessionSpec, flash: RamFlash) -> SettingsReport {
    let out = run_session(spec, flash, &[]).expect("the session runs");
    out.events
        .iter()
        .find_map(|e| match e.record {
            Record::Settings(s) => Some(s),
            _ => None,
        })
        .expect("the board reports its settings at boot")
}

/// A flash holding two saves: an older calibration (dwell 8 s) and the newest (dwell 9 s).
fn two_saves(spec: &SessionSpec) -> (RamFlash, Settings) {
    let steps = [
        send("set dwell_ms 8000"),
        send("store"),
        send("set dwell_ms 9000"),
        send("set t1_n_per_count 0.0161"),
        send("store"),
    ];
    let out = run_session(spec, RamFlash::new(FLASH_PAGES), &steps).unwrap();
    assert!(out.unanswered.is_empty());
    let newest = out
        .records(|r| match r {
            Record::Settings(s) if s.source == SettingsSource::Stored => Some(s.settings),
            _ => None,
        })
        .pop()
        .unwrap();
    assert_eq!(newest.protocol.dwell_ms, 9000);
    (out.flash, newest)
}

fn find(haystack: &[u8], needle: &[u8]) -> Option<usize> {
    haystack.windows(needle.len()).position(|w| w == needle)
}

#[test]
fn the_stored_settings_survive_a_reset() {
    let spec = SessionSpec::default();
    let (flash, newest) = two_saves(&spec);
    let r = boot_report(&spec, flash);
    assert_eq!(r.source, SettingsSource::Loaded);
    assert_eq!(r.settings, newest);
}

#[test]
fn no_flipped_bit_anywhere_brings_up_an_old_or_damaged_record() {
    let spec = SessionSpec::default();
    let defaults = Rig::new(spec.protocol, spec.calibration, spec.limits)
        .unwrap()
        .settings();
    let (flash, newest) = two_saves(&spec);
    let record_at = find(flash.bytes(), &newest.encode(2)).expect("the newest record is in flash");

    // Every byte of the first page (where the records are) and the head and tail of each
    // other page (their state markers), each with its lowest and highest bit flipped.
    let mut offsets: Vec<usize> = (0..ERASE_BYTES).collect();
    for page in 1..FLASH_PAGES {
        let base = page * ERASE_BYTES;
        offsets.extend(base..base + 16);
        offsets.extend(base + ERASE_BYTES - 16..base + ERASE_BYTES);
    }
    let mut fell_back = 0;
    for &at in &offsets {
        for mask in [0x01, 0x80] {
            let mut damaged = flash.clone();
            damaged.flip(at, mask);
            let r = boot_report(&spec, damaged);
            let ok = match r.source {
                SettingsSource::Loaded => r.settings == newest,
                SettingsSource::DefaultsNoRecord
                | SettingsSource::DefaultsCorrupt
                | SettingsSource::DefaultsInvalid
                | SettingsSource::DefaultsFlashError => r.settings == defaults,
                _ => false,
            };
            assert!(
                ok,
                "byte {at} ^ {mask:#04x}: {:?} {:?}",
                r.source, r.settings
            );
            if r.source != SettingsSource::Loaded {
                fell_back += 1;
            }
            // Damage inside the newest record itself is always caught.
            if (record_at..record_at + newest.encode(2).len()).contains(&at) {
                assert_eq!(r.source, SettingsSource::DefaultsCorrupt, "byte {at}");
            }
        }
    }
    assert!(
        fell_back >= 2 * 102,
        "only {fell_back} flips fell back to the defaults"
    );
}

#[test]
fn after_an_unreadable_flash_the_first_store_starts_afresh() {
    // The flash held generations 1 and 2 (dwell 8 s, then 9 s); at this boot it cannot be
    // read. The store that follows must not write "generation 1" beside the old generation 2:
    // were the new record then damaged, the old one would be loaded as if current. The range
    // is erased first instead.
    let spec = SessionSpec::default();
    let (mut flash, old) = two_saves(&spec);
    flash.failing_reads = 1;
    let steps = [send("set dwell_ms 7000"), send("store"), Step::Reset];
    let out = run_session(&spec, flash, &steps).unwrap();
    let at_boot = |boot: u32| out.settings_at_boot(boot).unwrap();
    assert_eq!(at_boot(1).source, SettingsSource::DefaultsFlashError);
    let stored = at_boot(2);
    assert_eq!(stored.source, SettingsSource::Loaded);
    assert_eq!(stored.settings.protocol.dwell_ms, 7000);

    // Damage the new record: the board must fall back to its defaults, never to dwell 9 s.
    let mut damaged = out.flash.clone();
    let at = find(damaged.bytes(), &stored.settings.encode(1)).expect("the new record");
    damaged.flip(at + 20, 0x01);
    let r = boot_report(&spec, damaged);
    assert_ne!(r.settings, old, "the old calibration came back");
    assert_eq!(r.source, SettingsSource::DefaultsCorrupt);
}
