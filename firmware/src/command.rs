//! The commands a host sends the rig, one text line each (`capstan rig ...` writes them into
//! the RTT down channel; the simulated rig takes the same lines), their parser, and the
//! replies' error codes with their messages.
//!
//! ```text
//! setup | leave | jog DEG | servo DEG | zero | weigh t1|t2 NEWTONS
//! set KEY VALUE | show | store | defaults | run | abort | ack
//! ```
//!
//! Text rather than a binary frame: a person can type it in any RTT terminal, and the parser
//! is a few hundred bytes of flash.

use crate::hal::Channel;
use crate::protocol::StepOrder;

/// Longest command line, bytes (without the newline).
pub const MAX_LINE: usize = 64;

/// A parsed command.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Command {
    /// Enter setup mode (from idle).
    Setup,
    /// Leave setup mode (the servo homes to rest).
    Leave,
    /// Move the servo command by this many degrees (setup mode).
    Jog(f32),
    /// Move the servo command to this angle, deg (setup mode).
    Servo(f32),
    /// Zero both channels on the mean of the next [`crate::setup::MEASURE_MS`] (setup mode).
    Zero,
    /// A known force hangs on a channel: its sensitivity from the mean reading (setup mode).
    Weigh(Channel, f32),
    /// Set one value of the settings (idle or setup).
    Set(Key, f32),
    /// Report the settings in force.
    Show,
    /// Keep the settings in force in flash (idle or setup).
    Store,
    /// Go back to the firmware's built-in settings (in RAM; `store` keeps them).
    Defaults,
    /// Start a run, as the button does (idle).
    Run,
    /// Stop the run, as the button does (or leave setup mode).
    Abort,
    /// Acknowledge a latched fault, as the button does.
    Ack,
}

/// The settings a host may set by name, with their units in the name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[allow(missing_docs)]
pub enum Key {
    RestDeg,
    StepDeg,
    FinalDeg,
    Order,
    DwellMs,
    PreTriggerMs,
    TriggerMs,
    TareMs,
    AmpControlV,
    WindowAfterMs,
    WindowBeforeMs,
    DiameterMm,
    WrapDeg,
    T1Zero,
    T1NPerCount,
    T2Zero,
    T2NPerCount,
    TareReferenceN,
    ServoMinUs,
    ServoMaxUs,
    ServoMaxDeg,
    AmpFullScaleV,
    AmpGain,
}

impl Key {
    /// Every key, in the order `capstan rig` lists them.
    pub const ALL: [Key; 23] = [
        Key::RestDeg,
        Key::StepDeg,
        Key::FinalDeg,
        Key::Order,
        Key::DwellMs,
        Key::PreTriggerMs,
        Key::TriggerMs,
        Key::TareMs,
        Key::AmpControlV,
        Key::WindowAfterMs,
        Key::WindowBeforeMs,
        Key::DiameterMm,
        Key::WrapDeg,
        Key::T1Zero,
        Key::T1NPerCount,
        Key::T2Zero,
        Key::T2NPerCount,
        Key::TareReferenceN,
        Key::ServoMinUs,
        Key::ServoMaxUs,
        Key::ServoMaxDeg,
        Key::AmpFullScaleV,
        Key::AmpGain,
    ];

    /// The name on the command line (the field names of the `settings` record).
    pub const fn name(self) -> &'static str {
        match self {
            Key::RestDeg => "rest_deg",
            Key::StepDeg => "step_deg",
            Key::FinalDeg => "final_deg",
            Key::Order => "order",
            Key::DwellMs => "dwell_ms",
            Key::PreTriggerMs => "pre_trigger_ms",
            Key::TriggerMs => "trigger_ms",
            Key::TareMs => "tare_ms",
            Key::AmpControlV => "amp_control_v",
            Key::WindowAfterMs => "window_after_ms",
            Key::WindowBeforeMs => "window_before_ms",
            Key::DiameterMm => "diameter_mm",
            Key::WrapDeg => "wrap_deg",
            Key::T1Zero => "t1_zero",
            Key::T1NPerCount => "t1_n_per_count",
            Key::T2Zero => "t2_zero",
            Key::T2NPerCount => "t2_n_per_count",
            Key::TareReferenceN => "tare_reference_n",
            Key::ServoMinUs => "servo_min_us",
            Key::ServoMaxUs => "servo_max_us",
            Key::ServoMaxDeg => "servo_max_deg",
            Key::AmpFullScaleV => "amp_full_scale_v",
            Key::AmpGain => "amp_gain",
        }
    }

    /// Wire code in the `reply` record.
    pub fn code(self) -> u8 {
        Key::ALL.iter().position(|&k| k == self).unwrap_or(0) as u8
    }

    /// The key of a name.
    pub fn from_name(name: &str) -> Option<Key> {
        Key::ALL.into_iter().find(|k| k.name() == name)
    }
}

/// Why a command was refused (the `reply` record's `error` code; 0 is success).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub enum CommandError {
    /// Not a command word.
    Unknown = 1,
    /// A number is missing, not a number, or there is too much on the line.
    Argument = 2,
    /// Not a settings name.
    UnknownKey = 3,
    /// The line is longer than [`MAX_LINE`].
    TooLong = 4,
    /// A run is in progress: only `abort` and `show` are taken.
    Running = 5,
    /// This command works in setup mode only.
    NotInSetup = 6,
    /// A fault is latched: acknowledge it first (button or `ack`).
    FaultLatched = 7,
    /// The servo is still homing to rest.
    Homing = 8,
    /// A zero or weigh is still being measured.
    Measuring = 9,
    /// The value would make the settings invalid (the settings are unchanged).
    Invalid = 10,
    /// The known weight barely moved the reading: is it on that channel?
    NoLoad = 11,
    /// Writing the flash failed; the stored settings are unchanged.
    StoreFailed = 12,
    /// Nothing to do in this state (e.g. `ack` with no fault, `leave` outside setup).
    NotApplicable = 13,
    /// The readings scattered too much to measure: something moved.
    Unsteady = 14,
}

impl CommandError {
    /// Every error.
    pub const ALL: [CommandError; 14] = [
        CommandError::Unknown,
        CommandError::Argument,
        CommandError::UnknownKey,
        CommandError::TooLong,
        CommandError::Running,
        CommandError::NotInSetup,
        CommandError::FaultLatched,
        CommandError::Homing,
        CommandError::Measuring,
        CommandError::Invalid,
        CommandError::NoLoad,
        CommandError::StoreFailed,
        CommandError::NotApplicable,
        CommandError::Unsteady,
    ];

    /// Wire code (never 0).
    pub const fn code(self) -> u8 {
        self as u8
    }

    /// Inverse of [`CommandError::code`].
    pub fn from_code(code: u8) -> Option<CommandError> {
        CommandError::ALL.into_iter().find(|e| e.code() == code)
    }

    /// What went wrong, for a person.
    pub const fn message(self) -> &'static str {
        match self {
            CommandError::Unknown => "not a command (setup, leave, jog, servo, zero, weigh, set, show, store, defaults, run, abort, ack)",
            CommandError::Argument => "a number is missing or is not a number, or the line has too much on it",
            CommandError::UnknownKey => "not the name of a setting",
            CommandError::TooLong => "the line is longer than 64 bytes",
            CommandError::Running => "a run is in progress: only abort and show are taken",
            CommandError::NotInSetup => "this works in setup mode only (send setup first)",
            CommandError::FaultLatched => "a fault is latched: press the button once or send ack",
            CommandError::Homing => "the servo is still on its way to rest: try again in a few seconds",
            CommandError::Measuring => "a zero or weigh is still being measured",
            CommandError::Invalid => "that value would make the settings invalid; nothing changed",
            CommandError::NoLoad => "the reading moved less than 20 counts: is the weight hanging on that channel?",
            CommandError::StoreFailed => "writing the flash failed; the stored settings are unchanged",
            CommandError::NotApplicable => "not in this state (run: from idle; leave: from setup mode; ack: with a fault latched)",
            CommandError::Unsteady => "the reading was not steady (something moved): let the servo and the weight settle, then repeat",
        }
    }
}

/// The kind of a command, as the `reply` record names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[allow(missing_docs)]
pub enum CommandKind {
    Unparsed = 0,
    Setup,
    Leave,
    Jog,
    Servo,
    Zero,
    Weigh,
    Set,
    Show,
    Store,
    Defaults,
    Run,
    Abort,
    Ack,
}

impl CommandKind {
    /// Every kind, by code.
    pub const ALL: [CommandKind; 14] = [
        CommandKind::Unparsed,
        CommandKind::Setup,
        CommandKind::Leave,
        CommandKind::Jog,
        CommandKind::Servo,
        CommandKind::Zero,
        CommandKind::Weigh,
        CommandKind::Set,
        CommandKind::Show,
        CommandKind::Store,
        CommandKind::Defaults,
        CommandKind::Run,
        CommandKind::Abort,
        CommandKind::Ack,
    ];

    /// Wire code.
    pub const fn code(self) -> u8 {
        self as u8
    }

    /// Inverse of [`CommandKind::code`].
    pub fn from_code(code: u8) -> Option<CommandKind> {
        CommandKind::ALL.get(code as usize).copied()
    }

    /// The command word (`"?"` for a line that did not parse).
    pub const fn word(self) -> &'static str {
        match self {
            CommandKind::Unparsed => "?",
            CommandKind::Setup => "setup",
            CommandKind::Leave => "leave",
            CommandKind::Jog => "jog",
            CommandKind::Servo => "servo",
            CommandKind::Zero => "zero",
            CommandKind::Weigh => "weigh",
            CommandKind::Set => "set",
            CommandKind::Show => "show",
            CommandKind::Store => "store",
            CommandKind::Defaults => "defaults",
            CommandKind::Run => "run",
            CommandKind::Abort => "abort",
            CommandKind::Ack => "ack",
        }
    }
}

impl Command {
    /// Its kind.
    pub const fn kind(&self) -> CommandKind {
        match self {
            Command::Setup => CommandKind::Setup,
            Command::Leave => CommandKind::Leave,
            Command::Jog(_) => CommandKind::Jog,
            Command::Servo(_) => CommandKind::Servo,
            Command::Zero => CommandKind::Zero,
            Command::Weigh(..) => CommandKind::Weigh,
            Command::Set(..) => CommandKind::Set,
            Command::Show => CommandKind::Show,
            Command::Store => CommandKind::Store,
            Command::Defaults => CommandKind::Defaults,
            Command::Run => CommandKind::Run,
            Command::Abort => CommandKind::Abort,
            Command::Ack => CommandKind::Ack,
        }
    }

    /// Parse one line (surrounding blanks ignored, words separated by blanks).
    pub fn parse(line: &str) -> Result<Command, CommandError> {
        let mut words = line.split_ascii_whitespace();
        let word = words.next().ok_or(CommandError::Unknown)?;
        let cmd = match word {
            "setup" => Command::Setup,
            "leave" => Command::Leave,
            "jog" => Command::Jog(number(&mut words)?),
            "servo" => Command::Servo(number(&mut words)?),
            "zero" => Command::Zero,
            "weigh" => {
                let ch = match words.next() {
                    Some("t1") => Channel::T1,
                    Some("t2") => Channel::T2,
                    _ => return Err(CommandError::Argument),
                };
                Command::Weigh(ch, number(&mut words)?)
            }
            "set" => {
                let key = words.next().ok_or(CommandError::Argument)?;
                let key = Key::from_name(key).ok_or(CommandError::UnknownKey)?;
                if key == Key::Order {
                    let order = match words.next() {
                        Some("monotone") => StepOrder::Monotone,
                        Some("updown") => StepOrder::UpDown,
                        Some("pulse") => StepOrder::Pulse,
                        _ => return Err(CommandError::Argument),
                    };
                    Command::Set(key, order.code() as f32)
                } else {
                    Command::Set(key, number(&mut words)?)
                }
            }
            "show" => Command::Show,
            "store" => Command::Store,
            "defaults" => Command::Defaults,
            "run" => Command::Run,
            "abort" => Command::Abort,
            "ack" => Command::Ack,
            _ => return Err(CommandError::Unknown),
        };
        if words.next().is_some() {
            return Err(CommandError::Argument);
        }
        Ok(cmd)
    }
}

/// The next word as a finite number.
fn number<'a>(words: &mut impl Iterator<Item = &'a str>) -> Result<f32, CommandError> {
    let v: f32 = words
        .next()
        .ok_or(CommandError::Argument)?
        .parse()
        .map_err(|_| CommandError::Argument)?;
    v.is_finite().then_some(v).ok_or(CommandError::Argument)
}

/// Gathers the bytes a host sends into lines. A line longer than [`MAX_LINE`] is dropped whole
/// (and reported once, at its newline), never cut into two commands.
#[derive(Clone, Debug)]
pub struct LineBuffer {
    buf: [u8; MAX_LINE],
    len: usize,
    overflow: bool,
}

impl Default for LineBuffer {
    fn default() -> Self {
        LineBuffer {
            buf: [0; MAX_LINE],
            len: 0,
            overflow: false,
        }
    }
}

impl LineBuffer {
    /// Take one byte; at a newline, the command of the line ended (`None` for a blank line).
    pub fn push(&mut self, byte: u8) -> Option<Result<Command, CommandError>> {
        if byte != b'\n' {
            if self.len < MAX_LINE {
                self.buf[self.len] = byte;
                self.len += 1;
            } else {
                self.overflow = true;
            }
            return None;
        }
        let line = &self.buf[..self.len];
        let result = if self.overflow {
            Some(Err(CommandError::TooLong))
        } else {
            match core::str::from_utf8(line) {
                Ok(s) if s.trim().is_empty() => None,
                Ok(s) => Some(Command::parse(s)),
                Err(_) => Some(Err(CommandError::Unknown)),
            }
        };
        self.len = 0;
        self.overflow = false;
        result
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_command_parses() {
        assert_eq!(Command::parse("setup"), Ok(Command::Setup));
        assert_eq!(Command::parse(" jog -2.5 "), Ok(Command::Jog(-2.5)));
        assert_eq!(Command::parse("servo 90"), Ok(Command::Servo(90.0)));
        assert_eq!(
            Command::parse("weigh t2 9.80665"),
            Ok(Command::Weigh(Channel::T2, 9.80665))
        );
        assert_eq!(
            Command::parse("set t1_n_per_count 0.0121"),
            Ok(Command::Set(Key::T1NPerCount, 0.0121))
        );
        assert_eq!(
            Command::parse("set order updown"),
            Ok(Command::Set(Key::Order, 1.0))
        );
        for k in Key::ALL {
            assert_eq!(Key::from_name(k.name()), Some(k));
        }
    }

    #[test]
    fn bad_lines_are_refused_with_the_reason() {
        assert_eq!(Command::parse("jump"), Err(CommandError::Unknown));
        assert_eq!(Command::parse("jog"), Err(CommandError::Argument));
        assert_eq!(Command::parse("jog ten"), Err(CommandError::Argument));
        assert_eq!(Command::parse("jog inf"), Err(CommandError::Argument));
        assert_eq!(Command::parse("jog 1 2"), Err(CommandError::Argument));
        assert_eq!(Command::parse("weigh t3 1"), Err(CommandError::Argument));
        assert_eq!(Command::parse("set speed 3"), Err(CommandError::UnknownKey));
        assert_eq!(Command::parse("set order up"), Err(CommandError::Argument));
    }

    #[test]
    fn lines_are_split_at_newlines_and_overlong_lines_dropped_whole() {
        let mut lb = LineBuffer::default();
        let mut got = [None, None, None];
        let mut i = 0;
        for b in b"\nzero\njog 5\n".iter() {
            if let Some(r) = lb.push(*b) {
                got[i] = Some(r);
                i += 1;
            }
        }
        assert_eq!(got[0], Some(Ok(Command::Zero)));
        assert_eq!(got[1], Some(Ok(Command::Jog(5.0))));
        let long = [b'x'; 100];
        assert!(long.iter().all(|&b| lb.push(b).is_none()));
        assert_eq!(lb.push(b'\n'), Some(Err(CommandError::TooLong)));
        assert_eq!(lb.push(b'\n'), None);
        for b in b"show" {
            assert_eq!(lb.push(*b), None);
        }
        assert_eq!(lb.push(b'\n'), Some(Ok(Command::Show)));
    }
}
