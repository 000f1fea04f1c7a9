//! Issue 24's negative cases on the emulated board, where the pins matter: a tare under load,
//! a button held from power-up, a stack overflow, a host that stops reading the log. Each must
//! be safe at the pins; each prints its measured times (the hardware chapter's table, docs/book/src/hardware.md).

use super::{
    case, common, drive_times, f, is_rest, press_after, ready, selected, MS, REASON_TIMER,
};
// (`MS` is used by every case's timing.)
use crate::pins::{at, segments, widths_after};
use crate::setup::emulate;

#[test]
fn a_tare_under_load_on_the_emulated_board_never_drives() {
    let Some(setup) = ready() else { return };
    let c = case("tare_under_load");
    if !selected(&c) {
        return;
    }
    let e = emulate(setup, c);
    common(&e);
    let b = e.bench();
    // The run is refused at the end of its tare: `tare_load` on T1 (the first channel
    // checked), ~7.9 N, the run ended by it, the fault latched.
    assert_eq!(e.faults.len(), 1, "{:?}", e.faults);
    assert_eq!(e.faults[0].2, "tare_load");
    assert_eq!(e.log["runs"][0]["ended_by_fault"], "tare_load");
    assert!(e.messages.contains("fault latched"), "{}", e.messages);
    // The amplifier's pin never switched, the trigger never rose, the servo stayed at rest.
    let amp = segments(&b["amp"]);
    assert!(amp.iter().all(|s| s.static_low()), "{amp:?}");
    assert!(b["trigger"].as_array().unwrap().is_empty());
    let servo = segments(&b["servo"]);
    assert!(servo
        .iter()
        .filter(|s| s.switching())
        .all(|s| is_rest(s.high_ns)));
    eprintln!(
        "emulated board, tare_under_load: 8 N on both sensors; the run refused at its tare's \
         end ({} s from the trigger it never raised); the amplifier never on",
        e.faults[0].1
    );
}

#[test]
fn a_button_held_from_power_up_starts_nothing_on_the_emulated_board() {
    let Some(setup) = ready() else { return };
    let c = case("held_button");
    if !selected(&c) {
        return;
    }
    let held_ns = c.held_from_power_up_us as f64 * 1e3;
    let e = emulate(setup, c);
    common(&e);
    let b = e.bench();
    // Held from power-up to 5 s: no trigger, no drive, no run.
    let trigger = b["trigger"].as_array().unwrap();
    assert!(
        trigger.iter().all(|t| f(&t[0]) > held_ns + 1_000.0 * MS),
        "{trigger:?}"
    );
    let amp = segments(&b["amp"]);
    assert!(
        at(&amp, held_ns).static_low() && amp.iter().all(|s| s.t_ns > held_ns || s.static_low())
    );
    // Released, then pressed at 6 s: that press starts a run (trigger 1 s later).
    let rise = f(&trigger[0][0]);
    let press = press_after(b, held_ns).expect("the press after the release");
    assert!((rise - press - 1_009.0 * MS).abs() < MS, "{rise} {press}");
    eprintln!(
        "emulated board, held_button: held {:.1} s from power-up, nothing ran; the press after \
         the release started a run ({:.3} s to the trigger)",
        held_ns / 1e9,
        (rise - press) / 1e9
    );
}

#[test]
fn a_stack_overflow_on_the_emulated_board_locks_up_and_the_watchdog_resets_within_10_ms() {
    let Some(setup) = ready() else { return };
    // The layout: the stack at the bottom of SRAM, the statics above it.
    let (top, bottom, sdata) = setup.image.stack;
    assert_eq!((bottom, top), (0x2000_0000, 0x2001_0000));
    assert!(sdata >= top, "statics at {sdata:#x}, above the stack");
    let c = case("stack_overflow");
    if !selected(&c) {
        return;
    }
    let e = emulate(setup, c);
    common(&e);
    let b = e.bench();
    let em = &e.emulation;
    let struck = f(&em["stack_overflow"]["t_ns"]);
    let lockup = &em["lockup"];
    assert!(!lockup.is_null(), "the core locked up");
    let addr = lockup["address"].as_u64().unwrap();
    assert!((0x1fff_0000..0x2000_0000).contains(&addr), "{lockup}");
    let resets = em["resets"].as_array().unwrap();
    assert_eq!(resets.len(), 1, "{resets:?}");
    assert_eq!(resets[0]["reason"], REASON_TIMER);
    let reset = f(&resets[0]["t_ns"]);
    let ms = (reset - struck) / MS;
    assert!(ms <= 10.0, "reset {ms} ms after the overflow");
    // Until the reset the outputs stayed as they were (a locked-up core drives nothing new);
    // then every pin is released; after the boot, latched: no pulse until the press.
    let amp = segments(&b["amp"]);
    assert!(at(&amp, reset).static_low());
    let servo = segments(&b["servo"]);
    let press = press_after(b, reset).expect("the press after the reset");
    assert!(servo
        .iter()
        .filter(|s| s.t_ns >= reset && s.t_ns < press)
        .all(|s| s.static_low()));
    let after = widths_after(&servo, press);
    assert!(!after.is_empty() && after.iter().all(|w| is_rest(w.1)));
    assert!(e.messages.contains("latched at boot"), "{}", e.messages);
    let drive = drive_times(b, struck);
    // No fault but loss of power leaves the drive on for more than 50 ms (to 1 %).
    assert!(drive.1 <= 50.0, "drive above 1 % for {:.1} ms", drive.1);
    eprintln!(
        "emulated board, stack_overflow: lockup at {addr:#x} {:.3} ms after SP reached the \
         bottom of SRAM; watchdog reset {ms:.3} ms after it (pins safe); drive below the motor's \
         friction {:.1} ms, below 1 % {:.1} ms after it; no servo pulse until the press",
        (f(&lockup["t_ns"]) - struck) / MS,
        drive.0,
        drive.1
    );
}

#[test]
fn a_host_that_stops_reading_never_stalls_the_loop_on_the_emulated_board() {
    let Some(setup) = ready() else { return };
    let c = case("rtt_full");
    if !selected(&c) {
        return;
    }
    let e = emulate(setup, c);
    common(&e);
    let b = e.bench();
    let em = &e.emulation;
    // The host set the log channel to block and read nothing for 2 s; the firmware put it back
    // to non-blocking at its next sample, never stalled (no watchdog reset), and the snag in
    // the middle of the stall was safe at the pins within 20 ms.
    let stall = &em["rtt_stall"];
    let restored = f(&stall["mode_restored_ns"]) - f(&stall["blocking_set_ns"]);
    assert!(
        restored <= 1.1 * MS,
        "non-blocking again after {restored} ns"
    );
    assert!(em["resets"].as_array().unwrap().is_empty());
    let inj = f(&b["injections"][0]["at_ns"]);
    assert!(inj > f(&stall["from_ns"]) && inj < f(&stall["to_ns"]));
    let deadline = inj + 20.0 * MS;
    let amp = segments(&b["amp"]);
    let off = at(&amp, deadline);
    assert!(off.static_low(), "{amp:?}");
    let servo = segments(&b["servo"]);
    assert!(widths_after(&servo, deadline).iter().all(|w| is_rest(w.1)));
    // What did not fit was dropped, and the log says how much (`seq` gaps).
    let missing = e.log["missing_records"].as_u64().unwrap();
    assert!(missing > 0, "{}", e.log);
    let budget = &b["budget"]["run"];
    eprintln!(
        "emulated board, rtt_full: log channel non-blocking again {:.3} ms after the host set it \
         to block; over-force during the stall safe at the pins after {:.2} ms; {missing} \
         records dropped and reported; loop budget max {} cycles",
        restored / MS,
        (off.t_ns - inj) / MS,
        budget["max"]
    );
}
