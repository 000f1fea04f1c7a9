//! Issue 38's hazards on the simulated board, each with the time from the event to the drive
//! off (below 1 % of its 10 V, from the plant's truth every ms): sensors, cords, buttons and
//! hosts that fail the way real parts do. Each of these tests failed on the firmware before
//! issue 38 (the drive ran on, or started).
//!
//! 1. T2 frozen at a plausible value, then a 50 N snag: off within 5 s of the snag.
//! 2. A cord that parts at a held level, from any preload: off within 2 s.
//! 3. Sensitivities nobody measured (a fresh board, `defaults`, a damaged record): no run; one
//!    a person typed runs.
//! 4. A host's `run` with nobody at the rig: no drive.
//! 5. A button held (or shorted) for 100 s: no drive.
//! 6. An unplugged sensor on a low zero (a 0-5 V sensor at 0 V reads the ADC's floor): off
//!    within 2 s.

use capstan_plant::{AdcConfig, Injection, InjectionKind};
use capstan_rig::command::CommandError;
use capstan_rig::hal::Channel;
use capstan_rig::record::{Fault, Record, Reply};
use capstan_rig::{Calibration, FaultKind, Protocol};
use capstan_sim::flash::RamFlash;
use capstan_sim::session::{run_session, SessionOutput, SessionSpec, Step, FLASH_PAGES};

const MS: u64 = 1_000;
const S: u64 = 1_000_000;

fn send(line: &str) -> Step {
    Step::Send(line.to_string())
}

/// A bench whose person typed both sensitivities, its ADC the RP2040's (an offset of 15
/// counts, a count of noise), the plant traced every ms.
fn bench(injections: Vec<Injection>) -> SessionSpec {
    let mut spec = SessionSpec {
        trace_every_ms: 1,
        calibration: Calibration::default().typed(),
        injections,
        ..SessionSpec::default()
    };
    spec.plant.adc = AdcConfig::RP2040;
    spec
}

fn at(kind: InjectionKind, after_trigger_us: u64) -> Injection {
    Injection {
        kind,
        cord: 0,
        after_trigger_us,
    }
}

fn session(spec: &SessionSpec, steps: &[Step]) -> SessionOutput {
    let out = run_session(spec, RamFlash::new(FLASH_PAGES), steps).expect("the session runs");
    assert!(out.unanswered.is_empty(), "{:?}", out.unanswered);
    out
}

/// A press at the rig 50 ms after boot, then `ms` of the run.
fn press_and_run(ms: u32) -> Vec<Step> {
    vec![Step::Press(200), Step::Wait(ms)]
}

fn faults(out: &SessionOutput) -> Vec<Fault> {
    out.records(|r| match r {
        Record::Fault(f) => Some(*f),
        _ => None,
    })
}

fn replies(out: &SessionOutput) -> Vec<Reply> {
    out.records(|r| match r {
        Record::Reply(x) => Some(*x),
        _ => None,
    })
}

/// The last instant the drive was above 1 % of the run's 10 V, µs.
fn last_driven_us(out: &SessionOutput) -> Option<u64> {
    out.trace
        .iter()
        .rev()
        .find(|s| s.drive_v > 0.1)
        .map(|s| s.t_us)
}

/// When injection `k` struck, plant µs.
fn struck(out: &SessionOutput, k: usize) -> u64 {
    out.plant.injections()[k]
        .at_us
        .expect("the injection struck")
}

/// µs after the trigger at which step `k` of the thesis protocol starts.
fn step_us(k: u32) -> u64 {
    let p = Protocol::default();
    (p.step_start_ms(k) - p.trigger_at_ms()) as u64 * MS
}

#[test]
fn a_frozen_t2_and_a_snag_stop_the_drive_within_5_s_of_the_snag() {
    // The reproduction: T2 frozen at 15 s (0.5 s into level 1's dwell... at its
    // plausible value), a 50 N snag on T2 at 20 s. With the ADC's own noise on the frozen
    // reading, the answer to the next servo step (level 2 at 20.5 s) tells it; with an ADC
    // that has none, the reading holding one count for 0.5 s.
    for (adc, what) in [
        (AdcConfig::RP2040, "the RP2040's ADC noise"),
        (AdcConfig::IDEAL, "no ADC noise"),
    ] {
        let mut spec = bench(vec![
            at(InjectionKind::Frozen(Channel::T2), 15 * S),
            at(InjectionKind::OverForce, 20 * S),
        ]);
        spec.plant.adc = adc;
        let out = session(&spec, &press_and_run(30_000));
        let (frozen, snag) = (struck(&out, 0), struck(&out, 1));
        let off = last_driven_us(&out).expect("the run drove");
        assert!(
            off < snag + 5 * S,
            "{what}: driven {} ms after the snag",
            (off - snag) / MS
        );
        let f = faults(&out);
        assert_eq!(
            (f[0].kind, f[0].channel),
            (FaultKind::SensorFrozen, Some(Channel::T2)),
            "{what}: {f:?}"
        );
        eprintln!(
            "frozen T2 + snag ({what}): fault {} s after the trigger ({:.2} s after the freeze); \
             drive below 1 % {:.2} s after the snag",
            f[0].t_us as f64 / 1e6,
            (off as f64 - frozen as f64) / 1e6,
            (off as f64 - snag as f64) / 1e6
        );
    }
}

#[test]
fn a_cord_parting_at_a_held_level_stops_the_drive_within_2_s_from_any_preload() {
    // The tare reads the preload as 0.1 N whatever it is: 0.005 N (a slack cord), 0.02 N (the
    // issue's case: 129 s of drive before issue 38), the reference, 0.5 N.
    for preload in [0.005, 0.02, 0.1, 0.5] {
        let mut spec = bench(vec![at(InjectionKind::CordBreak, step_us(3) + 3 * S)]);
        spec.plant.cord.preload_n = preload;
        let out = session(&spec, &press_and_run(38_000));
        let parted = struck(&out, 0);
        let off = last_driven_us(&out).expect("the run drove");
        assert!(
            off < parted + 2 * S,
            "{preload} N: driven {} ms on",
            (off - parted) / MS
        );
        let f = faults(&out);
        assert_eq!(f[0].kind, FaultKind::CordBreak, "{preload} N: {f:?}");
        eprintln!(
            "cord parted at level 3, preload {preload} N: drive below 1 % {:.1} ms after",
            (off - parted) as f64 / 1e3
        );
    }
}

#[test]
fn a_cord_parting_in_step_0_is_caught_at_rest_or_at_the_first_level() {
    // At rest with the drive on the cord carries ~1.8 × its preload on the two sensors: from
    // 0.1 N a break drops their sum by ~0.18 N, caught from the drop; from 0.02 N by ~0.035 N,
    // below what the drop check takes (0.05 N): caught when the first level should load it.
    for (preload, within_us) in [(0.1, 2 * S), (0.02, step_us(1) - 3 * S + 300 * MS)] {
        let mut spec = bench(vec![at(InjectionKind::CordBreak, 3 * S)]);
        spec.plant.cord.preload_n = preload;
        let out = session(&spec, &press_and_run(14_000));
        let parted = struck(&out, 0);
        let off = last_driven_us(&out).expect("the run drove");
        assert!(
            off < parted + within_us,
            "{preload} N: {} ms",
            (off - parted) / MS
        );
        assert_eq!(faults(&out)[0].kind, FaultKind::CordBreak);
        eprintln!(
            "cord parted in step 0, preload {preload} N: drive below 1 % {:.2} s after",
            (off - parted) as f64 / 1e6
        );
    }
}

#[test]
fn sensitivities_nobody_measured_never_run_and_typed_ones_do() {
    // A fresh board: its sensitivities are the built-in placeholder.
    let fresh = SessionSpec {
        calibration: Calibration::default(),
        ..bench(Vec::new())
    };
    let out = session(&fresh, &[send("run"), Step::Press(200), Step::Wait(3_000)]);
    assert_eq!(replies(&out)[0].error, Some(CommandError::Uncalibrated));
    assert_eq!(last_driven_us(&out), None, "a placeholder drove");
    // Typed, then `defaults`; a damaged stored record: the placeholder again.
    let out = session(
        &fresh,
        &[
            send("set t1_n_per_count 0.0151"),
            send("set t2_n_per_count 0.0149"),
            send("defaults"),
            Step::Press(200),
            Step::Wait(3_000),
        ],
    );
    assert_eq!(last_driven_us(&out), None, "defaults drove");
    let stored = run_session(
        &fresh,
        RamFlash::new(FLASH_PAGES),
        &[
            send("set t1_n_per_count 0.0151"),
            send("set t2_n_per_count 0.0149"),
            send("store"),
        ],
    )
    .unwrap();
    let mut damaged = stored.flash.clone();
    let at = damaged
        .bytes()
        .iter()
        .position(|&b| b == 2)
        .expect("the version byte");
    damaged.flip(at + 9, 0x10);
    let out = run_session(&fresh, damaged, &press_and_run(3_000)).unwrap();
    let boot = out.settings_at_boot(1).unwrap();
    assert!(boot.settings.calibration.unmeasured().is_some(), "{boot:?}");
    assert_eq!(last_driven_us(&out), None, "a damaged record drove");
    // The same record undamaged: typed by a person, it runs.
    let out = run_session(&fresh, stored.flash, &press_and_run(3_000)).unwrap();
    assert!(
        last_driven_us(&out).is_some(),
        "typed sensitivities did not run"
    );
    eprintln!("placeholder sensitivities: no run (fresh, defaults, damaged record); typed: runs");
}

#[test]
fn a_host_run_without_a_press_never_drives() {
    let out = session(&bench(Vec::new()), &[send("run"), Step::Wait(60_000)]);
    assert_eq!(replies(&out)[0].error, None, "armed");
    assert_eq!(last_driven_us(&out), None);
    assert!(out
        .records(|r| matches!(r, Record::RunStart(_)).then_some(()))
        .is_empty());
    // Armed, a press starts it (the tare, then the drive once the button is released).
    let out = session(
        &bench(Vec::new()),
        &[
            send("run"),
            Step::Wait(5_000),
            Step::Press(200),
            Step::Wait(3_000),
        ],
    );
    assert!(last_driven_us(&out).is_some());
}

#[test]
fn a_button_held_for_100_s_never_drives_and_is_reported() {
    let out = session(
        &bench(Vec::new()),
        &[Step::HoldButton(100_000), Step::Wait(101_000)],
    );
    assert_eq!(last_driven_us(&out), None, "the held button drove");
    let f: Vec<(u64, Fault)> = out
        .events
        .iter()
        .filter_map(|e| match e.record {
            Record::Fault(f) => Some((e.t_us, f)),
            _ => None,
        })
        .collect();
    assert_eq!(f.len(), 1, "{f:?}");
    assert_eq!(f[0].1.kind, FaultKind::ButtonHeld);
    // Reported 2 s into the hold (held from 50 ms: the press debounced 10 ms later); the
    // press began a run's tare (nothing moves), cancelled then.
    assert!(f[0].0.abs_diff(2_059_000) <= 1_000, "{f:?}");
    // A button that sticks during a run stops it at once (the abort at its pressed edge).
    let out = session(
        &bench(Vec::new()),
        &[
            Step::Press(200),
            Step::Wait(15_000),
            Step::HoldButton(100_000),
            Step::Wait(5_000),
        ],
    );
    let stuck = 50 * MS + 200 * MS + 15_000 * MS;
    let off = last_driven_us(&out).unwrap();
    assert!(off < stuck + 40 * MS, "{} ms", (off - stuck) / MS);
    assert_eq!(faults(&out)[0].kind, FaultKind::Abort);
    eprintln!(
        "button held 100 s from idle: no drive, `button_held` at {:.3} s; stuck during a run: \
         drive below 1 % {:.1} ms after",
        f[0].0 as f64 / 1e6,
        (off - stuck) as f64 / 1e3
    );
}

#[test]
fn an_unplugged_sensor_on_a_low_zero_stops_the_drive_within_2_s() {
    // 0-5 V sensors at 0 V with no load: through the ADC's 15-count offset both read ~15
    // counts, where an unplugged one reads too. The person types their zeros and
    // sensitivities, presses (acknowledging what the boot latched) and presses again; T1 is
    // unplugged at level 1. (Before issue 38 the zeros were taken, the run ran, and the unplug
    // read as 0 N on T1: no fault.)
    let mut spec = bench(vec![at(
        InjectionKind::SensorUnplugged(Channel::T1),
        step_us(1) + 500 * MS,
    )]);
    spec.calibration = Calibration::default();
    spec.plant.sensor.zero_counts = 0.0;
    spec.plant.sensor.zero_spread_counts = 0.0;
    let steps = [
        send("set t1_zero 15"),
        send("set t2_zero 15"),
        send("set t1_n_per_count 0.015"),
        send("set t2_n_per_count 0.015"),
        Step::Press(200),
        Step::Wait(500),
        Step::Press(200),
        Step::Wait(25_000),
    ];
    let out = session(&spec, &steps);
    let unplugged = out.plant.injections()[0].at_us;
    let off = last_driven_us(&out);
    // Not driven 2 s after the unplug (here: never, the zero refused, the floor latched).
    let late = |t: u64| unplugged.is_none_or(|u| t >= u + 2 * S);
    assert!(
        !off.is_some_and(late),
        "driven at {off:?}, unplugged at {unplugged:?}"
    );
    let zeros: Vec<_> = replies(&out).iter().take(2).map(|r| r.error).collect();
    assert_eq!(zeros, [Some(CommandError::Blind); 2]);
    assert_eq!(faults(&out)[0].kind, FaultKind::SensorRail);
    // A zero clear of the floor (400 counts): the unplug is the rail fault within 5 ms.
    let mut spec = bench(vec![at(
        InjectionKind::SensorUnplugged(Channel::T1),
        step_us(1) + 500 * MS,
    )]);
    spec.plant.sensor.zero_counts = 400.0;
    let out = session(&spec, &press_and_run(14_000));
    let unplugged = struck(&out, 0);
    let off = last_driven_us(&out).unwrap();
    assert!(off < unplugged + 40 * MS, "{} ms", (off - unplugged) / MS);
    assert_eq!(faults(&out)[0].kind, FaultKind::SensorRail);
    eprintln!(
        "unplugged on a low zero: refused, never driven; unplugged on a 400-count zero: drive \
         below 1 % {:.1} ms after",
        (off - unplugged) as f64 / 1e3
    );
}
