//! The negative cases of the rig's safety (issue 24): each must fail safe.

use super::*;
use crate::command::{Command, CommandError, CommandKind, Key};
use crate::hal::Channel;
use crate::record::{Fault, Reply};
use crate::safe_state::SafeDuties;

/// One sample at `t` (µs) with both channels at `counts`, the button at `pressed`, and `cmd`.
fn one(
    rig: &mut Rig,
    sink: &mut VecSink,
    t: u64,
    counts: [u16; 2],
    pressed: bool,
    cmd: Option<Command>,
) -> Outputs {
    rig.step(
        &Inputs {
            now_us: t,
            counts: [Ok(counts[0]), Ok(counts[1])],
            button_pressed: pressed,
            command: cmd.map(Ok),
        },
        sink,
    )
}

fn faults(sink: &VecSink) -> Vec<Fault> {
    sink.0
        .iter()
        .filter_map(|(_, r)| match r {
            Record::Fault(f) => Some(*f),
            _ => None,
        })
        .collect()
}

fn replies(sink: &VecSink) -> Vec<Reply> {
    sink.0
        .iter()
        .filter_map(|(_, r)| match r {
            Record::Reply(x) => Some(*x),
            _ => None,
        })
        .collect()
}

/// At rest with the cord at its 0.1 N preload, through the default calibration: counts.
fn rest_counts() -> [u16; 2] {
    let c = Calibration::default();
    [c.t1.counts(0.1) as u16, c.t2.counts(0.1) as u16]
}

/// A thesis rig driven sample by sample (1 ms apart) with host commands; its records kept.
struct Bench {
    rig: Rig,
    sink: VecSink,
    t: u64,
}

impl Bench {
    fn new() -> Self {
        Bench {
            rig: thesis_rig(),
            sink: VecSink::default(),
            t: 0,
        }
    }

    /// `samples` samples reading `counts`, `cmd` sent with the first.
    fn step(&mut self, counts: [u16; 2], cmd: Option<Command>, samples: usize) {
        for k in 0..samples {
            self.t += 1000;
            let cmd = if k == 0 { cmd } else { None };
            one(&mut self.rig, &mut self.sink, self.t, counts, false, cmd);
        }
    }

    /// Every reply so far: its command and error.
    fn replies(&self) -> Vec<(CommandKind, Option<CommandError>)> {
        replies(&self.sink)
            .iter()
            .map(|r| (r.command, r.error))
            .collect()
    }
}

#[test]
fn a_tare_under_load_refuses_the_run_before_the_drive_is_on() {
    // 8 N hangs on both sensors during the tare (the reproduction), then a 50 N snag.
    let cal = Calibration::default();
    for load_n in [8.0, 1.2, -2.0] {
        let mut rig = thesis_rig();
        let shift = load_n / cal.t1.n_per_count;
        let tr = drive(
            &mut rig,
            &move |_, o| (plant_counts(o, &cal, shift), false),
            None,
        );
        let (_, end) = tr.end.expect("the run ends");
        assert_eq!(end.fault, Some(FaultKind::TareLoad), "{load_n} N");
        let f = faults(&tr.sink)[0];
        assert_eq!(f.channel, Some(Channel::T1));
        assert!((f.value - load_n).abs() < 0.02, "{f:?}");
        // Refused at the end of the tare: the amplifier never on, no trigger, no step.
        assert!(tr
            .outputs
            .iter()
            .all(|(_, o)| o.amp_control_v == 0.0 && !o.trigger && o.servo_deg == 125.0));
        assert_eq!(rig.latched_fault(), Some(FaultKind::TareLoad));
        // The stored zeros are untouched by the refused tare.
        assert_eq!(rig.calibration().t1.zero_counts, 400.0);
    }
    // A reading 4 N below zero does not wait for a press: latched while idle (a reversed
    // sensor or a wrong zero), and the press only acknowledges it.
    let mut rig = thesis_rig();
    let shift = -4.0 / cal.t1.n_per_count;
    let tr = drive(
        &mut rig,
        &move |_, o| (plant_counts(o, &cal, shift), false),
        None,
    );
    assert!(tr.end.is_none() && !rig.is_running());
    assert_eq!(faults(&tr.sink)[0].kind, FaultKind::NegativeForce);
    // Within the bound (0.9 N of drift) the tare takes it, for that run only.
    let mut rig = thesis_rig();
    let shift = 0.9 / cal.t1.n_per_count;
    let tr = drive(
        &mut rig,
        &move |_, o| (plant_counts(o, &cal, shift), false),
        None,
    );
    assert_eq!(tr.end.unwrap().1.fault, None);
    assert_eq!(rig.calibration().t1.zero_counts, 400.0);
}

#[test]
fn a_sensitivity_that_would_blind_the_check_is_refused_wherever_it_comes_in() {
    let mut rig = thesis_rig();
    let mut sink = VecSink::default();
    let rest = rest_counts();
    let lines = [
        // Typed ten times low: out of the plausible range.
        (
            Command::Set(Key::T1NPerCount, 0.00125),
            CommandError::Invalid,
        ),
        // The hardware chapter's 0.01253 N/count with zero 400: 45 N reads at 3991 counts.
        (Command::Set(Key::T2NPerCount, 0.01253), CommandError::Blind),
        // A zero far too high: 45 N would read at 4000 counts.
        (Command::Set(Key::T1Zero, 1000.0), CommandError::Blind),
        // A sign: a reversed sensor.
        (
            Command::Set(Key::T1NPerCount, -0.015),
            CommandError::Invalid,
        ),
    ];
    for (k, (cmd, _)) in lines.iter().enumerate() {
        one(
            &mut rig,
            &mut sink,
            k as u64 * 1000,
            rest,
            false,
            Some(*cmd),
        );
    }
    let got: Vec<_> = replies(&sink).iter().map(|r| r.error).collect();
    let want: Vec<_> = lines.iter().map(|(_, e)| Some(*e)).collect();
    assert_eq!(got, want);
    assert_eq!(*rig.calibration(), Calibration::default().typed());
    // From flash (or anywhere else) the same rule: use_settings refuses it.
    let mut s = rig.settings();
    s.calibration.t2.n_per_count = 0.01253;
    assert_eq!(
        rig.use_settings(s),
        Err(crate::settings::SettingsError::Blind)
    );
    assert_eq!(
        rig.use_stored_settings(s),
        Err(crate::settings::SettingsError::Blind)
    );
}

#[test]
fn a_built_in_calibration_that_is_blind_never_runs() {
    // No check on the way in (the firmware's own defaults): the run's tare refuses it.
    let cal = Calibration {
        t2: crate::calib::ChannelCal::placeholder(400.0, 0.01253),
        ..Calibration::default()
    }
    .typed();
    let mut rig = Rig::new(Protocol::default(), cal, super::limits()).unwrap();
    let tr = drive(
        &mut rig,
        &move |_, o| (plant_counts(o, &cal, 0.0), false),
        None,
    );
    assert_eq!(tr.end.unwrap().1.fault, Some(FaultKind::Blind));
    let f = faults(&tr.sink)[0];
    assert_eq!(f.channel, Some(Channel::T2));
    assert!(tr.outputs.iter().all(|(_, o)| o.amp_control_v == 0.0));
}

#[test]
fn a_weight_that_lowers_the_reading_or_a_negative_weight_is_refused() {
    let mut rig = thesis_rig();
    let mut sink = VecSink::default();
    let rest = rest_counts();
    let mut t = 0;
    let mut step = |rig: &mut Rig, counts, cmd| {
        t += 1000;
        one(rig, &mut sink, t, counts, false, cmd)
    };
    step(&mut rig, rest, Some(Command::Setup));
    step(&mut rig, rest, Some(Command::Zero));
    for _ in 0..600 {
        step(&mut rig, rest, None);
    }
    step(&mut rig, rest, Some(Command::Weigh(Channel::T1, -9.8)));
    // A reversed T1 sensor: a 2 N weight takes 133 counts off its reading. (A heavier one
    // reads below -3 N: a `negative_force` fault, which interrupts the measurement.)
    let hung = [rest[0] - 133, rest[1]];
    step(&mut rig, hung, Some(Command::Weigh(Channel::T1, 2.0)));
    for _ in 0..600 {
        step(&mut rig, hung, None);
    }
    let errors: Vec<_> = replies(&sink)
        .iter()
        .map(|r| (r.command, r.error))
        .collect();
    assert_eq!(
        errors,
        [
            (CommandKind::Setup, None),
            (CommandKind::Zero, None),
            (CommandKind::Weigh, Some(CommandError::Invalid)),
            (CommandKind::Weigh, Some(CommandError::Reversed)),
        ]
    );
    // The zero was taken; the sensitivity is unchanged.
    assert_eq!(
        rig.calibration().t1.n_per_count,
        Calibration::default().t1.n_per_count
    );
}

#[test]
fn a_weigh_needs_a_zero_measured_in_the_same_setup_session() {
    // The stored zero may be days old or the firmware's default: a weight measured from it
    // gives a wrong sensitivity (a zero 200 counts low makes a 1 kg weight's N/count 23 %
    // small at 0.015 N/count, and every force then reads low, the over-force check's too).
    let mut b = Bench::new();
    let rest = rest_counts();
    // 1 kg on T1 at 0.015 N/count: 654 counts above the zero.
    let hung = [rest[0] + 654, rest[1]];
    let weigh_t1 = Some(Command::Weigh(Channel::T1, 9.80665));
    b.step(rest, Some(Command::Setup), 1);
    // Before any zero: refused at once, nothing measured.
    b.step(hung, weigh_t1, 1);
    b.step(rest, Some(Command::Zero), 600);
    // A zero typed over the measured one (or `defaults`) is not this session's zero either.
    b.step(rest, Some(Command::Set(Key::T1Zero, 380.0)), 1);
    b.step(hung, weigh_t1, 1);
    // ... T2's is still this session's: it weighs (1 kg on T2 now).
    let hung_t2 = [rest[0], rest[1] + 654];
    b.step(hung_t2, Some(Command::Weigh(Channel::T2, 9.80665)), 600);
    b.step(rest, Some(Command::Zero), 600);
    // The servo jogged since the zero: the cord's pull would add to the weight.
    b.step(rest, Some(Command::Jog(2.0)), 200);
    b.step(hung, weigh_t1, 1);
    b.step(rest, Some(Command::Jog(-2.0)), 200);
    b.step(hung, weigh_t1, 600);
    let weighed = b.rig.calibration().t1.n_per_count;
    // Leaving setup mode forgets the zero: the next session must zero again.
    b.step(rest, Some(Command::Leave), 3000);
    b.step(rest, Some(Command::Setup), 1);
    b.step(hung, Some(Command::Weigh(Channel::T2, 9.80665)), 1);
    assert_eq!(
        b.replies(),
        [
            (CommandKind::Setup, None),
            (CommandKind::Weigh, Some(CommandError::NotZeroed)),
            (CommandKind::Zero, None),
            (CommandKind::Set, None),
            (CommandKind::Weigh, Some(CommandError::NotZeroed)),
            (CommandKind::Weigh, None),
            (CommandKind::Zero, None),
            (CommandKind::Jog, None),
            (CommandKind::Weigh, Some(CommandError::NotZeroed)),
            (CommandKind::Jog, None),
            (CommandKind::Weigh, None),
            (CommandKind::Leave, None),
            (CommandKind::Setup, None),
            (CommandKind::Weigh, Some(CommandError::NotZeroed)),
        ]
    );
    assert!((weighed - 9.80665 / 654.0).abs() < 1e-6, "{weighed}");
    let t2 = b.rig.calibration().t2.n_per_count;
    assert!((t2 - 9.80665 / 654.0).abs() < 1e-6, "{t2}");
}

#[test]
fn a_zero_under_a_load_is_refused() {
    // 2.5 N hanging on T1 (167 counts at 0.015 N/count) while zeroing: taken as zero, it would
    // hide 2.5 N of every force from the over-force check in setup mode.
    let mut b = Bench::new();
    let rest = rest_counts();
    let loaded = [rest[0] + 167, rest[1]];
    b.step(rest, Some(Command::Setup), 1);
    b.step(loaded, Some(Command::Zero), 600);
    let after_refusal = *b.rig.calibration();
    // Nothing hanging (0.1 N from the stored zero): taken.
    b.step(rest, Some(Command::Zero), 600);
    assert_eq!(
        b.replies(),
        [
            (CommandKind::Setup, None),
            (CommandKind::Zero, Some(CommandError::ZeroMoved)),
            (CommandKind::Zero, None),
        ]
    );
    assert_eq!(after_refusal, Calibration::default().typed());
    assert_eq!(
        b.rig.calibration().zeros(),
        [rest[0] as f32, rest[1] as f32]
    );
}

#[test]
fn a_button_held_from_power_up_starts_nothing_until_released_and_pressed_again() {
    let mut rig = thesis_rig();
    let mut sink = VecSink::default();
    let rest = rest_counts();
    // Held (or stuck) for 5 s from the first sample.
    for k in 0..5_000 {
        let out = one(&mut rig, &mut sink, k * 1000, rest, true, None);
        assert!(out.amp_control_v == 0.0 && !out.trigger);
    }
    assert!(!rig.is_running());
    for k in 5_000..5_020 {
        one(&mut rig, &mut sink, k * 1000, rest, false, None);
    }
    assert!(!rig.is_running());
    for k in 5_020..5_040 {
        one(&mut rig, &mut sink, k * 1000, rest, true, None);
    }
    assert!(rig.is_running(), "a press after a release starts a run");
}

#[test]
fn a_fault_while_idle_is_latched_and_recorded_once() {
    let cal = Calibration::default();
    let mut rig = thesis_rig();
    let mut sink = VecSink::default();
    let rest = rest_counts();
    let over = [rest[0], cal.t2.counts(50.0) as u16];
    let mut t = 0;
    for _ in 0..10 {
        one(&mut rig, &mut sink, t, rest, false, None);
        t += 1000;
    }
    // 50 N on T2 with nothing running (someone hangs a load, a sensor fails high).
    let mut first = None;
    for _ in 0..200 {
        let out = one(&mut rig, &mut sink, t, over, false, None);
        assert!(out.amp_control_v == 0.0 && !out.trigger && out.servo_deg == 125.0);
        if first.is_none() && rig.latched_fault().is_some() {
            first = Some(t);
        }
        t += 1000;
    }
    assert_eq!(first, Some(12_000), "three samples over the limit");
    let f = faults(&sink);
    assert_eq!(f.len(), 1, "recorded once while it persists: {f:?}");
    assert_eq!(
        (f[0].kind, f[0].channel),
        (FaultKind::OverForce, Some(Channel::T2))
    );
    // A press (and its release) acknowledges it; still there, it latches again.
    for k in 0..60 {
        one(&mut rig, &mut sink, t, over, (10..30).contains(&k), None);
        t += 1000;
    }
    assert_eq!(rig.latched_fault(), Some(FaultKind::OverForce));
    assert_eq!(faults(&sink).len(), 2);
    assert!(!rig.is_running());
}

#[test]
fn homing_is_supervised_and_a_latched_fault_stops_it() {
    let cal = Calibration::default();
    let mut rig = thesis_rig();
    let mut sink = VecSink::default();
    let rest = rest_counts();
    // Setup mode left at 95°: the servo homes to rest at 10°/s.
    rig.home_from(95.0);
    let mut t = 0;
    for _ in 0..1_000 {
        one(&mut rig, &mut sink, t, rest, false, None);
        t += 1000;
    }
    let at = rig.idle_outputs().servo_deg;
    assert!((at - 105.0).abs() < 0.05, "{at}");
    // A sensor goes to its rail: latched; the servo goes to rest at once (toward release).
    for _ in 0..10 {
        one(&mut rig, &mut sink, t, [rest[0], 4_000], false, None);
        t += 1000;
    }
    assert_eq!(rig.latched_fault(), Some(FaultKind::SensorRail));
    assert_eq!(rig.idle_outputs().servo_deg, 125.0);
    // Homing from the release side (jogged to 145°) pulls toward rest: a fault freezes it.
    let mut rig = thesis_rig();
    rig.home_from(145.0);
    for _ in 0..500 {
        one(&mut rig, &mut sink, t, rest, false, None);
        t += 1000;
    }
    let before = rig.idle_outputs().servo_deg;
    let over = [cal.t1.counts(46.0) as u16, rest[1]];
    for _ in 0..2_000 {
        let out = one(&mut rig, &mut sink, t, over, false, None);
        // (Three samples to confirm the fault, at 0.01° each.)
        assert!(
            out.servo_deg >= before - 0.031,
            "moved toward tension while latched"
        );
        t += 1000;
    }
    assert_eq!(rig.latched_fault(), Some(FaultKind::OverForce));
    assert!(rig.is_homing());
}

#[test]
fn after_a_reset_the_servo_gets_no_pulse_until_a_person_acknowledges() {
    let mut rig = thesis_rig();
    let mut sink = VecSink::default();
    let rest = rest_counts();
    rig.boot_latched(FaultKind::Watchdog, &mut sink);
    assert_eq!(faults(&sink)[0].kind, FaultKind::Watchdog);
    assert!(!rig.idle_outputs().servo_pulses);
    // The panic path too: no pulses while limp.
    assert_eq!(
        SafeDuties::for_rig(&rig, 62_500),
        SafeDuties::NO_SERVO_PULSES
    );
    let mut t = 0;
    // The host cannot start a run, nor setup mode.
    for cmd in [Command::Run, Command::Setup, Command::Store] {
        let out = one(&mut rig, &mut sink, t, rest, false, Some(cmd));
        assert!(!out.servo_pulses && out.amp_control_v == 0.0);
        t += 1000;
    }
    let errors: Vec<_> = replies(&sink).iter().map(|r| r.error).collect();
    assert_eq!(
        errors,
        [
            Some(CommandError::FaultLatched),
            Some(CommandError::FaultLatched),
            Some(CommandError::NotAtRest)
        ]
    );
    // Seconds pass: still nothing.
    for _ in 0..3_000 {
        let out = one(&mut rig, &mut sink, t, rest, false, None);
        assert!(!out.servo_pulses);
        t += 1000;
    }
    // A press: acknowledged; the first pulse is the rest pulse, and no run starts.
    let mut first_pulse = None;
    for k in 0..100 {
        let out = one(&mut rig, &mut sink, t, rest, (10..40).contains(&k), None);
        if out.servo_pulses && first_pulse.is_none() {
            first_pulse = Some(out.servo_deg);
            assert!(out.settings_changed, "the board re-arms its panic path");
        }
        t += 1000;
    }
    assert_eq!(first_pulse, Some(125.0));
    assert!(!rig.is_running() && rig.latched_fault().is_none());
    assert_ne!(
        SafeDuties::for_rig(&rig, 62_500),
        SafeDuties::NO_SERVO_PULSES
    );
    // The host's `ack` cannot clear a latch a reset left: only a press at the rig.
    let mut rig = thesis_rig();
    let mut sink = VecSink::default();
    rig.boot_latched(FaultKind::Panic, &mut sink);
    one(&mut rig, &mut sink, t, rest, false, Some(Command::Ack));
    assert_eq!(replies(&sink)[0].error, Some(CommandError::NeedsPress));
    assert!(!rig.idle_outputs().servo_pulses);
    for k in 0..60 {
        one(&mut rig, &mut sink, t, rest, (10..40).contains(&k), None);
        t += 1000;
    }
    assert!(rig.idle_outputs().servo_pulses);
    // Then `run` arms a run, which only a press starts.
    one(&mut rig, &mut sink, t, rest, false, Some(Command::Run));
    assert!(!rig.is_running() && rig.is_armed());
    assert_eq!(replies(&sink)[1].error, None);
    for k in 0..20 {
        one(&mut rig, &mut sink, t + 1000 * (k + 1), rest, k >= 5, None);
    }
    assert!(rig.is_running());
}

#[test]
fn store_is_refused_unless_the_servo_is_at_rest() {
    let mut rig = thesis_rig();
    let mut sink = VecSink::default();
    let rest = rest_counts();
    let mut t = 0;
    let mut send = |rig: &mut Rig, cmd| {
        t += 1000;
        one(rig, &mut sink, t, rest, false, cmd)
    };
    send(&mut rig, Some(Command::Setup));
    send(&mut rig, Some(Command::Jog(-20.0)));
    for _ in 0..900 {
        send(&mut rig, None);
    }
    let out = send(&mut rig, Some(Command::Store));
    assert!(out.store.is_none(), "no flash write with the servo at 105°");
    send(&mut rig, Some(Command::Servo(125.0)));
    for _ in 0..900 {
        send(&mut rig, None);
    }
    let out = send(&mut rig, Some(Command::Store));
    assert!(out.store.is_some(), "at rest: written");
    let errors: Vec<_> = replies(&sink)
        .iter()
        .filter(|r| r.command == CommandKind::Store)
        .map(|r| r.error)
        .collect();
    assert_eq!(errors, [Some(CommandError::NotAtRest)]);
}

#[test]
fn a_fault_in_setup_mode_never_pulls_the_servo_toward_tension() {
    let cal = Calibration::default();
    let mut rig = thesis_rig();
    let mut sink = VecSink::default();
    let rest = rest_counts();
    let mut t = 0;
    one(&mut rig, &mut sink, t, rest, false, Some(Command::Setup));
    one(
        &mut rig,
        &mut sink,
        1000,
        rest,
        false,
        Some(Command::Jog(15.0)),
    );
    t += 2000;
    for _ in 0..1_000 {
        one(&mut rig, &mut sink, t, rest, false, None);
        t += 1000;
    }
    // Jogged to 140° (the release side of rest); a 50 N reading: latched, the servo stays.
    let over = [rest[0], cal.t2.counts(50.0) as u16];
    let mut outs = Vec::new();
    for _ in 0..10 {
        outs.push(one(&mut rig, &mut sink, t, over, false, None));
        t += 1000;
    }
    assert_eq!(rig.latched_fault(), Some(FaultKind::OverForce));
    assert!(outs.iter().all(|o| o.servo_deg >= 139.99), "{outs:?}");
    // Jogged toward tension (110°) instead: the fault sends it to rest (release).
    let mut rig = thesis_rig();
    one(&mut rig, &mut sink, t, rest, false, Some(Command::Setup));
    one(
        &mut rig,
        &mut sink,
        t + 1000,
        rest,
        false,
        Some(Command::Jog(-15.0)),
    );
    t += 2000;
    for _ in 0..1_000 {
        one(&mut rig, &mut sink, t, rest, false, None);
        t += 1000;
    }
    for _ in 0..10 {
        one(&mut rig, &mut sink, t, over, false, None);
        t += 1000;
    }
    assert_eq!(rig.idle_outputs().servo_deg, 125.0);
}

#[test]
fn a_weigh_whose_sensitivity_would_blind_the_over_force_check_is_refused() {
    // "weigh t1 2" with 3 N hanging: 200 counts for 2 N is 0.01 N/count, under which 45 N
    // would read above the rail check (the over-force check could never trip).
    let mut b = Bench::new();
    let rest = rest_counts();
    let hung = [rest[0] + 200, rest[1]];
    b.step(rest, Some(Command::Setup), 1);
    b.step(rest, Some(Command::Zero), 600);
    b.step(hung, Some(Command::Weigh(Channel::T1, 2.0)), 600);
    assert_eq!(
        b.replies(),
        [
            (CommandKind::Setup, None),
            (CommandKind::Zero, None),
            (CommandKind::Weigh, Some(CommandError::Blind)),
        ]
    );
    assert_eq!(
        b.rig.calibration().t1.n_per_count,
        Calibration::default().t1.n_per_count
    );
}
