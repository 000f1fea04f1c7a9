//! Issue 38's hazards on the emulated release image (`capstan_emu_bench::hazards`): each must leave
//! the amplifier's pin off (static low) within the time, or never switch it, and say
//! why in the log. The drive's voltage follows the pin through the RC filter: below 1 % 22 ms
//! later (`MotorConfig::amp_filter_tau_s`, 4.7 ms), which the times below leave room for.

use super::{case, common, f, ready, selected, MS, REASON_TIMER};
use crate::pins::{segments, Segment};
use crate::setup::emulate;
use capstan_emu_bench::hazards::{HELD_US, PARTED_AT_US};

/// The RC filter's time to 1 %, ms.
const FILTER_MS: f64 = 22.0;

/// When the amplifier's pin last stopped switching (its last segment static low), ns; None if
/// it never switched.
fn amp_off(amp: &[Segment]) -> Option<f64> {
    let last_on = amp.iter().rposition(|s| s.switching())?;
    let off = amp[last_on + 1..].iter().find(|s| s.static_low())?;
    Some(off.t_ns)
}

fn never_driven(amp: &[Segment]) -> bool {
    amp.iter().all(|s| s.static_low())
}

#[test]
fn a_frozen_t2_and_a_snag_on_the_emulated_board_stop_the_drive_within_5_s() {
    let Some(setup) = ready() else { return };
    let c = case("frozen_snag");
    if !selected(&c) {
        return;
    }
    let e = emulate(setup, c);
    common(&e);
    let b = e.bench();
    let snag = f(&b["injections"][1]["at_ns"]);
    let off = amp_off(&segments(&b["amp"])).expect("the run drove, then stopped");
    let drive_off_s = (off - snag) / 1e9 + FILTER_MS / 1e3;
    assert!(
        drive_off_s <= 5.0,
        "drive off {drive_off_s} s after the snag"
    );
    assert_eq!(e.faults[0].2, "sensor_frozen", "{:?}", e.faults);
    eprintln!(
        "emulated board, frozen_snag: fault {} s after the trigger, amplifier pin low {:.2} s \
         after the snag (drive below 1 % {:.2} s)",
        e.faults[0].1,
        (off - snag) / 1e9,
        drive_off_s
    );
}

#[test]
fn a_cord_parting_from_a_low_preload_on_the_emulated_board_stops_the_drive_within_2_s() {
    let Some(setup) = ready() else { return };
    let c = case("parted_low_preload");
    if !selected(&c) {
        return;
    }
    let e = emulate(setup, c);
    common(&e);
    let b = e.bench();
    let parted = f(&b["injections"][0]["at_ns"]);
    let off = amp_off(&segments(&b["amp"])).expect("the run drove, then stopped");
    let drive_off_ms = (off - parted) / MS + FILTER_MS;
    assert!(drive_off_ms <= 2_000.0, "{drive_off_ms} ms");
    assert_eq!(e.faults[0].2, "cord_break", "{:?}", e.faults);
    assert!(
        (e.faults[0].1 - PARTED_AT_US as f64 / 1e6) < 0.1,
        "{:?}",
        e.faults
    );
    eprintln!(
        "emulated board, parted_low_preload (0.02 N, tare reference 0.1 N): amplifier pin low \
         {:.1} ms after the cord parted (drive below 1 % {drive_off_ms:.1} ms)",
        (off - parted) / MS
    );
}

#[test]
fn a_board_as_flashed_never_runs_on_its_placeholder_sensitivities() {
    let Some(setup) = ready() else { return };
    let c = case("placeholder");
    if !selected(&c) {
        return;
    }
    let e = emulate(setup, c);
    common(&e);
    let b = e.bench();
    assert!(never_driven(&segments(&b["amp"])));
    assert!(b["trigger"].as_array().unwrap().is_empty());
    assert!(
        e.messages.contains("a sensitivity was never measured"),
        "{}",
        e.messages
    );
    assert!(e.log["runs"].as_array().unwrap().is_empty(), "{}", e.log);
}

#[test]
fn a_host_run_without_a_press_never_drives_the_emulated_board() {
    let Some(setup) = ready() else { return };
    let c = case("host_run");
    if !selected(&c) {
        return;
    }
    let e = emulate(setup, c);
    common(&e);
    let b = e.bench();
    assert!(never_driven(&segments(&b["amp"])));
    assert!(b["trigger"].as_array().unwrap().is_empty());
    assert!(e.messages.contains("run armed"), "{}", e.messages);
    assert!(e.log["runs"].as_array().unwrap().is_empty(), "{}", e.log);
}

#[test]
fn a_button_held_100_s_never_drives_the_emulated_board() {
    let Some(setup) = ready() else { return };
    let c = case("held_100s");
    if !selected(&c) {
        return;
    }
    let e = emulate(setup, c);
    common(&e);
    let b = e.bench();
    assert!(never_driven(&segments(&b["amp"])));
    assert!(b["trigger"].as_array().unwrap().is_empty());
    let held: Vec<_> = e.faults.iter().map(|x| x.2.as_str()).collect();
    assert_eq!(held, ["button_held"]);
    let press = f(&b["button"][0][0]);
    assert!((press / 1e3 - HELD_US.0 as f64).abs() < 1.0, "{press}");
    eprintln!(
        "emulated board, held_100s: the button held {} s: no drive, `button_held` reported",
        HELD_US.1 / 1_000_000
    );
}

#[test]
fn sensors_at_the_adcs_floor_never_drive_the_emulated_board() {
    let Some(setup) = ready() else { return };
    let c = case("unplugged_low_zero");
    if !selected(&c) {
        return;
    }
    let e = emulate(setup, c);
    common(&e);
    let b = e.bench();
    // Not driven 2 s after the unplug (here: never, the zeros refused, the floor latched).
    let amp = segments(&b["amp"]);
    let unplugged = b["injections"][0]["at_ns"].as_f64();
    let late = amp
        .iter()
        .filter(|s| s.switching())
        .any(|s| unplugged.is_none_or(|u| s.t_ns >= u + 2e9));
    assert!(
        !late && never_driven(&amp),
        "{amp:?}, unplugged at {unplugged:?}"
    );
    assert!(
        e.faults.iter().any(|x| x.2 == "sensor_unplugged"),
        "{:?}",
        e.faults
    );
    assert!(
        e.messages.matches("-3 N limit below the low one").count() >= 2,
        "both zeros refused: {}",
        e.messages
    );
}

#[test]
fn the_watchdog_a_debugger_disabled_is_enabled_again_and_resets_a_hung_loop() {
    let Some(setup) = ready() else { return };
    let c = case("debugger_watchdog");
    if !selected(&c) {
        return;
    }
    let e = emulate(setup, c);
    common(&e);
    let em = &e.emulation;
    let wrote = &em["debugger_watchdog"];
    // The debugger's write took: disabled (bit 30 clear), paused on halt (bits 24-26).
    let after = wrote["ctrl_after"].as_u64().unwrap();
    assert_eq!((after >> 30) & 1, 0, "{wrote}");
    let resets = em["resets"].as_array().unwrap();
    assert_eq!(resets.len(), 1, "the hung loop was reset: {resets:?}");
    assert_eq!(resets[0]["reason"], REASON_TIMER);
    let hung = f(&e.bench()["core_fault"]["struck_ns"]);
    let bite_ms = (f(&resets[0]["t_ns"]) - hung) / MS;
    assert!(
        (9.0..=10.0).contains(&bite_ms),
        "reset {bite_ms} ms after the hang"
    );
    eprintln!(
        "emulated board, debugger_watchdog: the watchdog disabled at {:.4} s, the loop hung \
         5 ms later, the chip reset {bite_ms:.3} ms after the hang",
        f(&wrote["t_ns"]) / 1e9
    );
}
