//! `capstan rig live [SECONDS]`: the forces, counts and servo angle the rig reports in setup
//! mode (~10 a second), printed as they arrive, for SECONDS or until Ctrl-C.

use super::say::{live_line, LIVE_HEADER};
use capstan_link::frame::Event;
use capstan_link::rig::RigLink;
use capstan_link::words::fault_line;
use capstan_rig::record::Record;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// How long to wait for the first live reading before saying the rig is not in setup mode.
pub const FIRST_WITHIN: Duration = Duration::from_secs(1);

/// No live reading arrived.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NotInSetup;

impl std::fmt::Display for NotInSetup {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "no live values within {} s: the rig sends them in setup mode only (enter it with \
             `capstan rig ... setup`)",
            FIRST_WITHIN.as_secs()
        )
    }
}

impl std::error::Error for NotInSetup {}

/// The number of seconds of `live [SECONDS]`, if given.
pub fn seconds(words: &[String]) -> Result<Option<Duration>, String> {
    match words {
        [] => Ok(None),
        [s] => match s.parse::<f64>() {
            Ok(v) if v.is_finite() && v > 0.0 && v < 1e9 => Ok(Some(Duration::from_secs_f64(v))),
            _ => Err(format!(
                "live SECONDS: `{s}` is not a positive number of seconds"
            )),
        },
        _ => Err("live takes at most one word: the number of seconds".into()),
    }
}

/// Print live readings (stdout) until `how_long` has passed or `stop` is set; faults and
/// firmware messages go to `note`. Returns the number of readings printed.
pub fn watch(
    link: &mut dyn RigLink,
    how_long: Option<Duration>,
    stop: &AtomicBool,
    out: &mut dyn FnMut(String),
    note: &mut dyn FnMut(String),
) -> anyhow::Result<u64> {
    let started = Instant::now();
    let mut readings = 0u64;
    loop {
        if stop.load(Ordering::SeqCst) || how_long.is_some_and(|d| started.elapsed() >= d) {
            return Ok(readings);
        }
        if readings == 0 && started.elapsed() >= FIRST_WITHIN {
            return Err(NotInSetup.into());
        }
        for event in link.poll(Duration::from_millis(100))? {
            if take_live(event, &mut readings, out, note) {
                return Ok(readings);
            }
        }
    }
}

/// Print the live readings among `events` (a simulated board's, made in virtual time), as
/// [`watch`] prints them as they arrive; [`NotInSetup`] if there was none.
pub fn show(
    events: Vec<Event>,
    out: &mut dyn FnMut(String),
    note: &mut dyn FnMut(String),
) -> anyhow::Result<u64> {
    let mut readings = 0u64;
    for event in events {
        if take_live(event, &mut readings, out, note) {
            break;
        }
    }
    if readings == 0 {
        return Err(NotInSetup.into());
    }
    Ok(readings)
}

/// One event of the live view: a reading printed, a fault or message noted; true when setup
/// mode ended.
fn take_live(
    event: Event,
    readings: &mut u64,
    out: &mut dyn FnMut(String),
    note: &mut dyn FnMut(String),
) -> bool {
    match event {
        Event::Record {
            record: Record::Live(l),
            ..
        } => {
            if *readings == 0 {
                out(LIVE_HEADER.to_string());
            }
            *readings += 1;
            out(live_line(&l));
        }
        Event::Record {
            record: Record::Fault(f),
            ..
        } => {
            note(fault_line(&f));
            note("live: setup mode ended by the fault".into());
            return true;
        }
        Event::Record {
            record: Record::Reply(r),
            ..
        } if r.command == capstan_rig::command::CommandKind::Leave && r.error.is_none() => {
            note("live: setup mode was left (the button, or another rig command)".into());
            return true;
        }
        Event::Message { level, text } => note(format!("{level} {text}")),
        Event::Record { .. } => {}
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seconds_are_a_positive_number() {
        assert_eq!(seconds(&[]), Ok(None));
        assert_eq!(
            seconds(&["2.5".into()]),
            Ok(Some(Duration::from_millis(2500)))
        );
        for bad in ["0", "-1", "inf", "NaN", "ten"] {
            assert!(seconds(&[bad.into()]).is_err(), "{bad}");
        }
        assert!(seconds(&["1".into(), "2".into()]).is_err());
    }
}
