//! The rig as `capstan rig` talks to it: a [`RigLink`] takes command lines and gives back the
//! records and messages the firmware logs, whatever carries them (RTT through a debug probe,
//! or a scripted rig in the tests); [`exchange`] sends one command and waits for the record answering it.

use crate::frame::Event;
use capstan_rig::command::{Command, CommandKind};
use capstan_rig::record::{Record, Reply, RunEnd, SettingsReport};
use std::time::{Duration, Instant};

/// A connection to the rig's command line and its log.
pub trait RigLink {
    /// Send one command line (without its newline; the link adds it).
    fn send_line(&mut self, line: &str) -> Result<(), LinkError>;

    /// What the rig logged since the last call: records (with their sequence numbers) and
    /// text messages, in order. Waits up to `timeout` for the first; returns as soon as there
    /// is something (an empty list: nothing within `timeout`). An error is a link that broke.
    fn poll(&mut self, timeout: Duration) -> Result<Vec<Event>, LinkError>;
}

/// Why an exchange with the rig failed.
#[derive(Debug, thiserror::Error)]
pub enum LinkError {
    /// The link broke: its carrier's error (a probe that went away, a simulated board that
    /// stalled), with its causes.
    #[error(transparent)]
    Broken(Box<dyn std::error::Error + Send + Sync>),
    /// No answer came in time.
    #[error(transparent)]
    NoReply(#[from] NoReply),
}

impl LinkError {
    /// A broken link, from the carrier's error or message.
    pub fn broken(e: impl Into<Box<dyn std::error::Error + Send + Sync>>) -> Self {
        LinkError::Broken(e.into())
    }
}

/// How long to wait for the answer to a command: a zero or weigh measures for 0.5 s, a store
/// writes the flash (up to ~2 s).
pub fn timeout_for(cmd: &Command) -> Duration {
    match cmd {
        Command::Store => Duration::from_secs(5),
        _ => Duration::from_secs(3),
    }
}

/// No answer came.
#[derive(Clone, Debug, PartialEq)]
pub struct NoReply {
    /// The command word.
    pub word: &'static str,
    /// How long we waited.
    pub waited: Duration,
}

impl std::fmt::Display for NoReply {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "no reply to `{}` from the board within {:.0} s: is the firmware of this repository \
             running, and is no other `capstan rig` or `capstan log` reading its RTT channel?",
            self.word,
            self.waited.as_secs_f64()
        )
    }
}

impl std::error::Error for NoReply {}

/// What answered a command.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Answer {
    /// The reply record answering it.
    pub reply: Option<Reply>,
    /// The last settings report that arrived while waiting (`show`, `store`, `defaults` send
    /// one before their reply).
    pub settings: Option<SettingsReport>,
    /// The end of the run an `abort` stopped (it comes with the reply, or after it).
    pub run_end: Option<RunEnd>,
}

/// Whether `reply` answers `cmd` (a line the board could not parse is answered as such).
fn answers(reply: &Reply, cmd: &Command) -> bool {
    reply.command == cmd.kind() || reply.command == CommandKind::Unparsed
}

/// Take one event while waiting for the answer to `cmd`; true once it is complete. Faults,
/// messages and replies to other commands go to `note` (one line each, for stderr).
pub fn take(
    event: Event,
    cmd: &Command,
    answer: &mut Answer,
    note: &mut dyn FnMut(String),
) -> bool {
    let record = match event {
        Event::Message { level, text } => {
            note(format!("{level} {text}").trim_start().to_string());
            return false;
        }
        Event::Record { record, .. } => record,
    };
    match record {
        Record::Reply(r) if answer.reply.is_none() && answers(&r, cmd) => {
            answer.reply = Some(r);
            return true;
        }
        Record::Reply(r) => note(format!(
            "note: a reply to another command: {}",
            crate::words::reply_line(&r, None)
        )),
        Record::Settings(s) => answer.settings = Some(s),
        Record::Fault(f) => note(crate::words::fault_line(&f)),
        Record::RunEnd(e) if *cmd == Command::Abort => {
            answer.run_end = Some(e);
            return true;
        }
        _ => {}
    }
    false
}

/// Send `line` (the text of `cmd`) and wait for its answer, up to [`timeout_for`] `cmd`.
/// Faults and firmware messages that arrive meanwhile go to `note` as they come.
pub fn exchange(
    link: &mut dyn RigLink,
    line: &str,
    cmd: &Command,
    note: &mut dyn FnMut(String),
) -> Result<Answer, LinkError> {
    exchange_within(link, line, cmd, timeout_for(cmd), note)
}

/// [`exchange`], waiting up to `waited` ([`NoReply`] after that).
pub fn exchange_within(
    link: &mut dyn RigLink,
    line: &str,
    cmd: &Command,
    waited: Duration,
    note: &mut dyn FnMut(String),
) -> Result<Answer, LinkError> {
    link.send_line(line)?;
    let deadline = Instant::now() + waited;
    let mut answer = Answer::default();
    let mut done = false;
    while !done {
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() {
            let word = cmd.kind().word();
            return Err(NoReply { word, waited }.into());
        }
        for event in link.poll(left.min(Duration::from_millis(100)))? {
            // The whole batch is taken: a fault right after the reply is still said.
            done |= take(event, cmd, &mut answer, note);
        }
    }
    Ok(answer)
}
