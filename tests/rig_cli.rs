//! `capstan rig` without a board: its help, the keys, the refusals before anything is sent
//! (exit status 2), and the conversation with a rig played by a scripted [`RigLink`] (answers,
//! refusals, faults, no reply, live values).

use capstan::cli::rig::{answer_lines, send, watch_live, NotInSetup, Refused};
use capstan_link::rig::{command_line, exchange, exchange_within, CheckError, LinkError, RigLink};
use capstan_link::Event;
use capstan_rig::command::{Command, CommandError, CommandKind, Key};
use capstan_rig::hal::Channel;
use capstan_rig::record::{
    Fault, FaultKind, Live, Record, Reply, RunEnd, SettingsReport, SettingsSource,
};
use capstan_rig::{Calibration, Protocol, Settings, SettingsError};
use std::collections::VecDeque;
use std::process::{Command as Process, Output, Stdio};
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

fn capstan(args: &[&str]) -> Output {
    Process::new(env!("CARGO_BIN_EXE_capstan"))
        .args(args)
        .stdin(Stdio::null())
        .output()
        .expect("capstan runs")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

#[test]
fn help_gives_the_bench_sequence_and_the_log_caveat() {
    let o = capstan(&["rig", "--help"]);
    assert!(o.status.success());
    let help = text(&o.stdout);
    for needle in [
        "--chip RP2040",
        "setup",
        "live 10",
        "jog 5",
        "zero",
        "weigh t1 9.80665",
        "weigh t2",
        "servo 125",
        "set diameter_mm",
        "wrap_deg",
        "store",
        "leave",
        "run",
        "never flashes or resets",
        "sequence gap",
        "Exit status",
    ] {
        assert!(
            help.contains(needle),
            "`capstan rig --help` lacks {needle:?}:\n{help}"
        );
    }
    let top = text(&capstan(&["--help"]).stdout);
    assert!(top.contains("Set up the rig from the host"), "{top}");
}

#[test]
fn keys_are_listed_with_their_units_without_a_board() {
    let o = capstan(&["rig", "keys"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let list = text(&o.stdout);
    assert_eq!(list.lines().count(), Key::ALL.len());
    for k in Key::ALL {
        assert!(list.contains(k.name()), "{}", k.name());
    }
    assert!(list.contains("t1_n_per_count     N/count"), "{list}");
    assert!(list.contains("dwell_ms           ms"), "{list}");
}

#[test]
fn typos_are_refused_here_with_the_firmware_reason_and_status_2() {
    for (words, why) in [
        (&["jgo", "5"][..], CommandError::Unknown),
        (&["jog", "five"], CommandError::Argument),
        (&["weigh", "t3", "9.8"], CommandError::Argument),
        (&["set", "dwel_ms", "8000"], CommandError::UnknownKey),
    ] {
        // No probe here: the refusal comes before any attempt to reach one.
        let mut args = vec!["rig", "--chip", "RP2040", "--elf", "/nonexistent/fw.elf"];
        args.extend(words);
        let o = capstan(&args);
        assert_eq!(o.status.code(), Some(2), "{words:?}: {}", text(&o.stderr));
        let err = text(&o.stderr);
        assert!(err.contains(why.message()), "{words:?}: {err}");
        assert!(!err.contains("probe"), "{words:?}: {err}");
    }
    let o = capstan(&["rig", "live", "ten"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("not a positive number of seconds"));
}

#[test]
fn a_command_needs_a_board() {
    let o = capstan(&["rig", "zero"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        text(&o.stderr).contains("say which board"),
        "{}",
        text(&o.stderr)
    );
    let o = capstan(&["rig", "--chip", "RP2040", "show"]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "--chip needs --elf: {}",
        text(&o.stderr)
    );
}

/// A rig played from a script: each line sent is answered by the events `answer` gives for
/// it, delivered on the next poll.
struct Scripted<F: FnMut(&str) -> Vec<Event>> {
    answer: F,
    sent: Vec<String>,
    queue: VecDeque<Vec<Event>>,
    /// Delivered with every poll whatever was sent (live values in setup mode).
    stream: Option<Record>,
}

impl<F: FnMut(&str) -> Vec<Event>> RigLink for Scripted<F> {
    fn send_line(&mut self, line: &str) -> Result<(), LinkError> {
        self.sent.push(line.to_string());
        let events = (self.answer)(line);
        self.queue.push_back(events);
        Ok(())
    }

    fn poll(&mut self, timeout: Duration) -> Result<Vec<Event>, LinkError> {
        if let Some(batch) = self.queue.pop_front() {
            return Ok(batch);
        }
        std::thread::sleep(timeout.min(Duration::from_millis(20)));
        Ok(self.stream.iter().map(|&r| rec(r)).collect())
    }
}

fn scripted<F: FnMut(&str) -> Vec<Event>>(answer: F) -> Scripted<F> {
    Scripted {
        answer,
        sent: Vec::new(),
        queue: VecDeque::new(),
        stream: None,
    }
}

fn rec(record: Record) -> Event {
    Event::Record { seq: 0, record }
}

fn reply(command: CommandKind, error: Option<CommandError>, values: [f32; 2]) -> Event {
    rec(Record::Reply(Reply {
        command,
        error,
        values,
    }))
}

fn live(servo_deg: f32) -> Record {
    Record::Live(Live {
        t_ms: 4200,
        counts: [412, 1012],
        force_n: [0.01, 9.81],
        servo_deg,
    })
}

fn settings() -> Settings {
    Settings {
        protocol: Protocol::default(),
        calibration: Calibration::default(),
    }
}

fn words(line: &str) -> Vec<String> {
    line.split(' ').map(String::from).collect()
}

#[test]
fn the_answer_is_the_reply_to_the_command_and_faults_on_the_way_are_said() {
    let mut rig = scripted(|_| {
        vec![
            rec(live(90.0)),
            reply(CommandKind::Zero, None, [400.0, 401.0]),
            rec(Record::Fault(Fault {
                kind: FaultKind::OverForce,
                channel: Some(Channel::T2),
                value: 61.0,
                t_us: 5,
            })),
            Event::Message {
                level: "WARN".into(),
                text: "fault over_force in setup mode: outputs safe".into(),
            },
            reply(CommandKind::Jog, None, [95.0, 0.0]),
        ]
    });
    let (line, cmd) = command_line(&words("jog 5")).unwrap();
    let mut notes = Vec::new();
    let answer = exchange(&mut rig, &line, &cmd, &mut |n| notes.push(n)).unwrap();
    assert_eq!(rig.sent, ["jog 5"]);
    assert_eq!(
        answer_lines(&answer, &cmd).unwrap(),
        ["jog: servo at 95.0°"]
    );
    assert!(notes[0].starts_with("note: a reply to another command: zero: T1 zero 400.0"));
    assert!(
        notes[1].starts_with("FAULT over_force on T2 (value 61)"),
        "{notes:?}"
    );
    assert_eq!(
        notes[2],
        "WARN fault over_force in setup mode: outputs safe"
    );
}

#[test]
fn a_refusal_is_said_in_the_firmware_words() {
    let mut rig = scripted(|_| {
        vec![reply(
            CommandKind::Zero,
            Some(CommandError::NotInSetup),
            [0.0; 2],
        )]
    });
    let (line, cmd) = command_line(&words("zero")).unwrap();
    let answer = exchange(&mut rig, &line, &cmd, &mut |_| {}).unwrap();
    let Refused(why) = answer_lines(&answer, &cmd).unwrap_err();
    assert_eq!(
        why,
        format!("refused: {}", CommandError::NotInSetup.message())
    );
}

#[test]
fn show_prints_the_settings_record_and_weigh_names_its_channel() {
    let report = SettingsReport {
        source: SettingsSource::Current,
        settings: settings(),
    };
    let mut rig = scripted(|line| match line {
        "show" => vec![
            rec(Record::Settings(report)),
            reply(CommandKind::Show, None, [0.0; 2]),
        ],
        _ => vec![reply(CommandKind::Weigh, None, [0.01226, 1212.0])],
    });
    let mut out = Vec::new();
    let (line, cmd) = command_line(&words("show")).unwrap();
    send(&mut rig, &line, &cmd, &mut |l| out.push(l), &mut |_| {}).unwrap();
    assert_eq!(
        out[0],
        format!("settings: {}", SettingsSource::Current.message())
    );
    // Every setting, and a line for each sensitivity nobody measured (the built-in ones).
    assert_eq!(out.len(), 1 + capstan_wire::settings::SETTINGS + 2);
    assert!(
        out.contains(&format!("  {:<18} 10000 ms", "dwell_ms")),
        "{out:#?}"
    );
    assert!(
        out[out.len() - 2].starts_with("UNMEASURED: T1's sensitivity"),
        "{out:#?}"
    );
    out.clear();
    let (line, cmd) = command_line(&words("weigh t2 9.80665")).unwrap();
    send(&mut rig, &line, &cmd, &mut |l| out.push(l), &mut |_| {}).unwrap();
    assert_eq!(out, ["weigh t2: 0.01226 N/count (mean 1212.0 counts; measured from the zero taken in this setup session with nothing hanging)"]);
}

#[test]
fn a_set_is_checked_against_the_rig_settings_and_not_sent_if_invalid() {
    let report = SettingsReport {
        source: SettingsSource::Current,
        settings: settings(),
    };
    let mut rig = scripted(|line| match line {
        "show" => vec![
            rec(Record::Settings(report)),
            reply(CommandKind::Show, None, [0.0; 2]),
        ],
        _ => vec![reply(
            CommandKind::Set,
            None,
            [Key::DwellMs.code() as f32, 8000.0],
        )],
    });
    let (line, cmd) = command_line(&words("set step_deg 7")).unwrap();
    let e = send(&mut rig, &line, &cmd, &mut |_| {}, &mut |_| {}).unwrap_err();
    let check = e.downcast_ref::<CheckError>().expect("refused here");
    assert!(matches!(
        check,
        CheckError::Setting("step_deg", SettingsError::Protocol(_))
    ));
    assert_eq!(rig.sent, ["show"], "the set never reached the rig");
    let mut out = Vec::new();
    let (line, cmd) = command_line(&words("set dwell_ms 8000")).unwrap();
    send(&mut rig, &line, &cmd, &mut |l| out.push(l), &mut |_| {}).unwrap();
    assert_eq!(rig.sent, ["show", "show", "set dwell_ms 8000"]);
    assert_eq!(out, ["set dwell_ms = 8000 ms"]);
}

#[test]
fn an_abort_during_a_run_is_answered_by_its_end_and_silence_is_an_error() {
    let mut rig = scripted(|_| {
        vec![
            rec(Record::Fault(Fault {
                kind: FaultKind::Abort,
                channel: None,
                value: 0.0,
                t_us: 21_000_000,
            })),
            rec(Record::RunEnd(RunEnd {
                t_us: 21_000_000,
                pairs: 1,
                fault: Some(FaultKind::Abort),
            })),
        ]
    });
    let (line, cmd) = command_line(&words("abort")).unwrap();
    let answer = exchange(&mut rig, &line, &cmd, &mut |_| {}).unwrap();
    assert_eq!(
        answer_lines(&answer, &cmd).unwrap(),
        ["abort: the run stopped at 21.0 s after 1 pair(s) (abort)"]
    );
    let mut silent = scripted(|_| Vec::new());
    let t = Instant::now();
    let e = exchange_within(
        &mut silent,
        "zero",
        &Command::Zero,
        Duration::from_millis(200),
        &mut |_| {},
    )
    .unwrap_err();
    assert!(t.elapsed() < Duration::from_secs(2));
    let LinkError::NoReply(no) = &e else {
        panic!("no reply expected: {e}")
    };
    assert_eq!(no.word, "zero");
    assert!(e.to_string().contains("no reply to `zero`"), "{e}");
}

#[test]
fn live_values_are_printed_in_setup_mode_and_their_absence_is_explained() {
    let stop = AtomicBool::new(false);
    let mut rig = scripted(|_| Vec::new());
    rig.stream = Some(live(95.0));
    let mut rows = Vec::new();
    let n = watch_live(
        &mut rig,
        Some(Duration::from_millis(300)),
        &stop,
        &mut |l| rows.push(l),
        &mut |_| {},
    )
    .unwrap();
    assert!(n >= 3, "{n}");
    assert!(rows[0].contains("T1_N") && rows[0].contains("servo_deg"));
    assert!(
        rows[1].contains("9.810") && rows[1].contains("95.0"),
        "{}",
        rows[1]
    );
    let mut idle = scripted(|_| Vec::new());
    let e = watch_live(&mut idle, None, &stop, &mut |_| {}, &mut |_| {}).unwrap_err();
    assert!(e.downcast_ref::<NotInSetup>().is_some(), "{e}");
    assert!(e.to_string().contains("setup mode only"), "{e}");
}
