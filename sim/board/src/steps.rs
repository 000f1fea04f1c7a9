//! The bench's steps as text: the journal (`journal.txt`, one step a line) and the bench
//! actions of `capstan rig --sim DIR bench ...`, which a person does by hand at a real rig.

use crate::{BenchError, SimError};
use capstan_rig::hal::Channel;
use capstan_sim::plant::InjectionKind;
use capstan_sim::session::Step;
use std::path::Path;

/// How long a weight is left to stop swinging after it is hung or taken off, ms.
pub const SETTLE_MS: u32 = 1_000;
/// A press of the button, ms.
pub const PRESS_MS: u32 = 200;

/// The usage of `bench`.
pub const BENCH_USAGE: &str = "bench load t1|t2 NEWTONS | bench unload | bench press [MS] | \
                               bench wait SECONDS | bench power-cycle";

fn channel(word: &str) -> Option<Channel> {
    match word.to_ascii_lowercase().as_str() {
        "t1" => Some(Channel::T1),
        "t2" => Some(Channel::T2),
        _ => None,
    }
}

fn ch_word(c: Channel) -> &'static str {
    match c {
        Channel::T1 => "t1",
        Channel::T2 => "t2",
    }
}

/// One journal line.
pub fn step_line(s: &Step) -> String {
    match s {
        Step::Send(l) => format!("send {l}"),
        Step::Wait(ms) => format!("wait {ms}"),
        Step::Hang(c, n) => format!("hang {} {n:?}", ch_word(*c)),
        Step::Press(ms) => format!("press {ms}"),
        Step::PressIfArmed(ms) => format!("press-if-armed {ms}"),
        Step::UntilRunEnd => "until-run-end".into(),
        Step::Reset => "reset".into(),
        Step::Freeze => "freeze".into(),
        Step::HoldButton(ms) => format!("hold {ms}"),
        Step::ReverseSensor(c) => format!("reverse {}", ch_word(*c)),
        Step::ScaleSensor(c, f) => format!("scale {} {f:?}", ch_word(*c)),
        Step::RunPin => "reset-pin".into(),
        Step::Panic => "panic".into(),
        Step::Inject(k) => format!("inject {}", injection_word(*k)),
    }
}

/// An injection's name in the journal (the plant's, with the channel where it has one).
fn injection_word(k: InjectionKind) -> &'static str {
    match k {
        InjectionKind::SensorUnplugged(Channel::T1) => "sensor_unplugged_t1",
        InjectionKind::Frozen(Channel::T1) => "sensor_frozen_t1",
        k => k.name(),
    }
}

/// The journal's text.
pub fn journal_text(steps: &[Step]) -> String {
    steps.iter().map(|s| step_line(s) + "\n").collect()
}

fn parse_line(line: &str) -> Option<Step> {
    let (word, rest) = line.split_once(' ').unwrap_or((line, ""));
    let num = |s: &str| s.trim().parse::<u32>().ok();
    let two = || {
        let (c, v) = rest.split_once(' ')?;
        Some((
            channel(c)?,
            v.trim().parse::<f64>().ok().filter(|v| v.is_finite())?,
        ))
    };
    Some(match word {
        "send" => Step::Send(rest.to_string()),
        "wait" => Step::Wait(num(rest)?),
        "hang" => {
            let (c, n) = two()?;
            Step::Hang(c, n)
        }
        "press" => Step::Press(num(rest)?),
        "press-if-armed" => Step::PressIfArmed(num(rest)?),
        "until-run-end" => Step::UntilRunEnd,
        "reset" => Step::Reset,
        "freeze" => Step::Freeze,
        "hold" => Step::HoldButton(num(rest)?),
        "reverse" => Step::ReverseSensor(channel(rest.trim())?),
        "scale" => {
            let (c, f) = two()?;
            Step::ScaleSensor(c, f)
        }
        "reset-pin" => Step::RunPin,
        "panic" => Step::Panic,
        "inject" => Step::Inject(InjectionKind::from_name(rest.trim())?),
        _ => return None,
    })
}

/// Read a journal; a line that is not a step is an error naming the file and line.
pub fn parse_journal(text: &str, path: &Path) -> crate::Result<Vec<Step>> {
    let mut steps = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if line.is_empty() {
            continue;
        }
        match parse_line(line) {
            Some(s) => steps.push(s),
            None => {
                return Err(SimError::Journal {
                    path: path.to_path_buf(),
                    line: i + 1,
                    text: line.to_string(),
                })
            }
        }
    }
    Ok(steps)
}

/// A bench action (the words after `bench`): its steps and a sentence saying what was done.
pub fn bench(words: &[String]) -> Result<(Vec<Step>, String), BenchError> {
    let w: Vec<&str> = words.iter().map(String::as_str).collect();
    let newtons = |s: &str| {
        s.parse::<f64>()
            .ok()
            .filter(|v| v.is_finite() && (0.0..=200.0).contains(v))
            .ok_or_else(|| BenchError::Weight(s.to_string()))
    };
    match w.as_slice() {
        ["load", c, n] => {
            let ch = channel(c).ok_or_else(|| BenchError::Channel(c.to_string()))?;
            let n = newtons(n)?;
            Ok((
                vec![Step::Hang(ch, n), Step::Wait(SETTLE_MS)],
                format!(
                    "bench: {n} N hangs on {} (left {} s to stop swinging)",
                    c.to_uppercase(),
                    SETTLE_MS as f64 / 1e3
                ),
            ))
        }
        ["unload"] => Ok((
            vec![
                Step::Hang(Channel::T1, 0.0),
                Step::Hang(Channel::T2, 0.0),
                Step::Wait(SETTLE_MS),
            ],
            "bench: nothing hangs on either sensor".into(),
        )),
        ["press"] | ["press", _] => {
            let ms = match w.get(1) {
                None => PRESS_MS,
                Some(s) => s
                    .parse::<u32>()
                    .ok()
                    .filter(|&m| (1..=60_000).contains(&m))
                    .ok_or_else(|| BenchError::Press(s.to_string()))?,
            };
            Ok((
                vec![Step::Press(ms)],
                format!("bench: the button pressed for {ms} ms"),
            ))
        }
        ["wait", s] => {
            let secs = s
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite() && *v > 0.0 && *v <= 3600.0)
                .ok_or_else(|| BenchError::Wait(s.to_string()))?;
            let ms = (secs * 1e3).round() as u32;
            Ok((vec![Step::Wait(ms)], format!("bench: {secs} s passed")))
        }
        ["power-cycle"] => Ok((
            vec![Step::Reset],
            "bench: the board was power cycled (it booted again)".into(),
        )),
        _ => Err(BenchError::Usage),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn journal_lines_round_trip() {
        let steps = vec![
            Step::Send("weigh t1 9.80665".into()),
            Step::Wait(2000),
            Step::Hang(Channel::T2, 9.80665),
            Step::Press(200),
            Step::PressIfArmed(200),
            Step::UntilRunEnd,
            Step::Reset,
            Step::ScaleSensor(Channel::T1, 1.0375),
            Step::RunPin,
            Step::Panic,
            Step::Inject(InjectionKind::Frozen(Channel::T1)),
            Step::Inject(InjectionKind::Frozen(Channel::T2)),
            Step::Inject(InjectionKind::SensorUnplugged(Channel::T1)),
            Step::Inject(InjectionKind::CordBreak),
        ];
        let text = journal_text(&steps);
        assert_eq!(parse_journal(&text, Path::new("j")).unwrap(), steps);
        let e = parse_journal("wait 10\nfly away\n", Path::new("j")).unwrap_err();
        assert!(e.to_string().starts_with("j:2:1:"), "{e}");
    }

    #[test]
    fn bench_words() {
        let w = |s: &str| s.split(' ').map(String::from).collect::<Vec<_>>();
        assert_eq!(
            bench(&w("load t1 9.80665")).unwrap().0[0],
            Step::Hang(Channel::T1, 9.80665)
        );
        for bad in [
            "load t3 1",
            "load t1 -1",
            "load t1 inf",
            "wait 0",
            "press x",
            "fly",
        ] {
            assert!(bench(&w(bad)).is_err(), "{bad}");
        }
    }
}
