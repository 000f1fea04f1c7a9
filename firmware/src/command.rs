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
    /// Acknowledge a latched fault, as the button does (a host-started run after a fault
    /// needs it: `run` is refused while one is latched).
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

    /// Its index in [`crate::settings::Settings::fields`].
    pub const fn field(self) -> usize {
        match self {
            Key::Order => 0,
            Key::RestDeg => 1,
            Key::StepDeg => 2,
            Key::FinalDeg => 3,
            Key::DwellMs => 4,
            Key::PreTriggerMs => 5,
            Key::TriggerMs => 6,
            Key::TareMs => 7,
            Key::AmpControlV => 8,
            Key::WindowAfterMs => 11,
            Key::WindowBeforeMs => 12,
            Key::DiameterMm => 13,
            Key::WrapDeg => 14,
            Key::AmpGain => 15,
            Key::T1Zero => 16,
            Key::T1NPerCount => 17,
            Key::T2Zero => 18,
            Key::T2NPerCount => 19,
            Key::TareReferenceN => 20,
            Key::ServoMinUs => 21,
            Key::ServoMaxUs => 22,
            Key::ServoMaxDeg => 23,
            Key::AmpFullScaleV => 24,
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
    /// Writing the flash failed (the board uses, after a reset, the newest settings that were
    /// written whole).
    StoreFailed = 12,
    /// Nothing to do in this state (e.g. `ack` with no fault, `leave` outside setup).
    NotApplicable = 13,
    /// The readings scattered too much to measure: something moved.
    Unsteady = 14,
    /// Setup mode ended (a fault, the button, `leave`) before the measurement was done.
    Interrupted = 15,
    /// The reading fell under the weight: the sensor is reversed (a tension must raise it).
    Reversed = 16,
    /// With the result the over-force limit would read above the rail check: the check could
    /// never trip (nothing changed).
    Blind = 17,
    /// `store` holds the loop for the flash write: only with the servo at rest.
    NotAtRest = 18,
}

impl CommandError {
    /// Every error.
    pub const ALL: [CommandError; 18] = [
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
        CommandError::Interrupted,
        CommandError::Reversed,
        CommandError::Blind,
        CommandError::NotAtRest,
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
            CommandError::FaultLatched => "a fault is latched: press the button once (after releasing it) or send ack",
            CommandError::Homing => "the servo is still on its way to rest: try again in a few seconds",
            CommandError::Measuring => "a zero or weigh is still being measured",
            CommandError::Invalid => "that value would make the settings invalid; nothing changed",
            CommandError::NoLoad => "the reading moved less than 20 counts: is the weight hanging on that channel?",
            CommandError::StoreFailed => "writing the flash failed: send store again (after a reset the board uses the newest settings written whole, or its defaults, and says which)",
            CommandError::NotApplicable => "not in this state (run: from idle; leave: from setup mode; abort: in setup mode or a run; ack: with a fault latched)",
            CommandError::Unsteady => "the reading was not steady (something moved): let the servo and the weight settle, then repeat",
            CommandError::Interrupted => "setup mode ended (a fault, the button or leave) before the measurement was done",
            CommandError::Reversed => "the reading fell under the weight: the sensor is reversed or wired to the other input (a tension must raise the counts); nothing changed",
            CommandError::Blind => "with that calibration the over-force limit would read above the rail check, so it could never trip (the sensor's range, or the value, is wrong); nothing changed",
            CommandError::NotAtRest => "store only with the servo at rest: the flash write holds the safety loop (send servo <rest> and wait, or leave setup mode and let it home)",
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
        Command::parse_bytes(line.as_bytes())
    }

    /// [`Command::parse`] on the line's bytes. Bytes, not `str`: no UTF-8 check and no string
    /// slicing, whose panic paths link ~4 KiB of formatting into the board image.
    pub fn parse_bytes(line: &[u8]) -> Result<Command, CommandError> {
        let [word, a, b, extra] = words(line);
        if !extra.is_empty() {
            return Err(CommandError::Argument);
        }
        let arity = |n: usize| {
            let given = [a, b].iter().filter(|w| !w.is_empty()).count();
            (given == n).then_some(()).ok_or(CommandError::Argument)
        };
        if let Some((_, cmd)) = SIMPLE.iter().find(|(w, _)| *w == word) {
            arity(0)?;
            return Ok(*cmd);
        }
        let cmd = match word {
            b"jog" | b"servo" => {
                arity(1)?;
                let v = number(a)?;
                if word == b"jog" {
                    Command::Jog(v)
                } else {
                    Command::Servo(v)
                }
            }
            b"weigh" => {
                let ch = match a {
                    b"t1" => Channel::T1,
                    b"t2" => Channel::T2,
                    _ => return Err(CommandError::Argument),
                };
                Command::Weigh(ch, number(b)?)
            }
            b"set" => {
                let key = Key::ALL
                    .into_iter()
                    .find(|k| k.name().as_bytes() == a)
                    .ok_or(if a.is_empty() {
                        CommandError::Argument
                    } else {
                        CommandError::UnknownKey
                    })?;
                let value = match (key, b) {
                    (Key::Order, b"monotone") => StepOrder::Monotone.code() as f32,
                    (Key::Order, b"updown") => StepOrder::UpDown.code() as f32,
                    (Key::Order, b"pulse") => StepOrder::Pulse.code() as f32,
                    (Key::Order, _) => return Err(CommandError::Argument),
                    _ => number(b)?,
                };
                Command::Set(key, value)
            }
            _ => return Err(CommandError::Unknown),
        };
        Ok(cmd)
    }
}

/// The first three blank-separated words of a line and whatever follows them (empty where
/// there are fewer).
fn words(line: &[u8]) -> [&[u8]; 4] {
    let mut out: [&[u8]; 4] = [&[]; 4];
    let mut rest = line;
    for slot in out.iter_mut().take(3) {
        let start = rest.iter().position(|b| !b.is_ascii_whitespace());
        rest = start.and_then(|s| rest.get(s..)).unwrap_or(&[]);
        let end = rest
            .iter()
            .position(|b| b.is_ascii_whitespace())
            .unwrap_or(rest.len());
        let (word, tail) = rest.split_at(end);
        *slot = word;
        rest = tail;
    }
    out[3] = match rest.iter().position(|b| !b.is_ascii_whitespace()) {
        Some(s) => rest.get(s..).unwrap_or(&[]),
        None => &[],
    };
    out
}

/// The commands without arguments, by their word.
const SIMPLE: [(&[u8], Command); 9] = [
    (b"setup", Command::Setup),
    (b"leave", Command::Leave),
    (b"zero", Command::Zero),
    (b"show", Command::Show),
    (b"store", Command::Store),
    (b"defaults", Command::Defaults),
    (b"run", Command::Run),
    (b"abort", Command::Abort),
    (b"ack", Command::Ack),
];

/// A word as a number.
fn number(word: &[u8]) -> Result<f32, CommandError> {
    decimal_bytes(word).ok_or(CommandError::Argument)
}

/// Exact powers of ten in f32 (each literal rounds once, at compile time).
const POW10: [f32; 39] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22, 1e23, 1e24, 1e25, 1e26, 1e27, 1e28, 1e29, 1e30, 1e31, 1e32,
    1e33, 1e34, 1e35, 1e36, 1e37, 1e38,
];

/// A decimal number: `[+-]digits[.digits][e[+-]digits]`, at most 18 significant digits.
///
/// By hand because core's `f32::from_str` brings 16 KiB of flash (its power-of-five table)
/// into a 64 KiB budget. Exact for what a person types: the digits form an exact integer and
/// one multiplication or division by a power of ten rounds once more (within one ulp of the
/// correctly rounded value; the tests compare with core's parser).
pub fn decimal(word: &str) -> Option<f32> {
    decimal_bytes(word.as_bytes())
}

fn decimal_bytes(word: &[u8]) -> Option<f32> {
    let (negative, rest) = sign(word);
    let (mantissa, exp) = match rest.iter().position(|&b| b == b'e' || b == b'E') {
        Some(i) => (rest.get(..i)?, exponent(rest.get(i + 1..)?)?),
        None => (rest, 0),
    };
    let dot = mantissa.iter().position(|&b| b == b'.');
    let frac_len = dot.map_or(0, |d| mantissa.len() - d - 1);
    let mut digits: u64 = 0;
    let mut count = 0;
    for (i, &b) in mantissa.iter().enumerate() {
        if Some(i) == dot {
            continue;
        }
        if !b.is_ascii_digit() || count >= 18 {
            return None;
        }
        digits = digits * 10 + (b - b'0') as u64;
        count += 1;
    }
    if count == 0 {
        return None;
    }
    let scale = exp - frac_len as i32;
    let power = *POW10.get(scale.unsigned_abs() as usize)?;
    let magnitude = if scale >= 0 {
        digits as f32 * power
    } else {
        digits as f32 / power
    };
    let v = if negative { -magnitude } else { magnitude };
    v.is_finite().then_some(v)
}

/// A leading sign, and the rest.
fn sign(word: &[u8]) -> (bool, &[u8]) {
    match word.split_first() {
        Some((b'-', rest)) => (true, rest),
        Some((b'+', rest)) => (false, rest),
        _ => (false, word),
    }
}

fn exponent(s: &[u8]) -> Option<i32> {
    let (negative, digits) = sign(s);
    if digits.is_empty() || digits.len() > 3 || !digits.iter().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let e = digits.iter().fold(0i32, |e, b| e * 10 + (b - b'0') as i32);
    Some(if negative { -e } else { e })
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
            match self.buf.get_mut(self.len) {
                Some(slot) => {
                    *slot = byte;
                    self.len += 1;
                }
                None => self.overflow = true,
            }
            return None;
        }
        let line = self.buf.get(..self.len).unwrap_or(&[]);
        let result = if self.overflow {
            Some(Err(CommandError::TooLong))
        } else if line.iter().all(|b| b.is_ascii_whitespace()) {
            None
        } else {
            Some(Command::parse_bytes(line))
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
    fn numbers_read_as_the_standard_parser_reads_them() {
        for s in [
            "0",
            "-0",
            "5",
            "-2.5",
            "9.80665",
            "0.0163",
            "1833",
            "1e3",
            "2.5E-2",
            ".5",
            "5.",
            "+7",
            "125.000",
            "0.015",
            "1214.2",
            "3.3",
            "12.7",
            "-180",
            "0.000123456",
        ] {
            let want: f32 = s.parse().unwrap();
            let got = decimal(s).unwrap_or(f32::NAN);
            let ulps = (got.to_bits() as i64 - want.to_bits() as i64).abs();
            assert!(ulps <= 1, "{s}: {got} vs {want}");
        }
        for s in [
            "", "-", ".", "1.2.3", "1e", "1e999", "e5", "0x10", "nan", "inf", "1,5", "--1",
        ] {
            assert_eq!(decimal(s), None, "{s:?}");
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
