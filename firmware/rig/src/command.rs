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
//! is a few hundred bytes of flash. The words, the keys, the step orders' and channels' names
//! and the reply's codes are the wire schema's (`capstan-wire`), which the host builds from too.

use capstan_wire::{Channel, Value};

pub use capstan_wire::{CommandError, CommandKind, Key, MAX_LINE};

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
        let given = [a, b].iter().filter(|w| !w.is_empty()).count();
        let arity = |n: usize| (given == n).then_some(()).ok_or(CommandError::Argument);
        let kind = CommandKind::from_word(word).ok_or(CommandError::Unknown)?;
        let simple = |cmd: Command| arity(0).map(|()| cmd);
        match kind {
            CommandKind::Setup => simple(Command::Setup),
            CommandKind::Leave => simple(Command::Leave),
            CommandKind::Zero => simple(Command::Zero),
            CommandKind::Show => simple(Command::Show),
            CommandKind::Store => simple(Command::Store),
            CommandKind::Defaults => simple(Command::Defaults),
            CommandKind::Run => simple(Command::Run),
            CommandKind::Abort => simple(Command::Abort),
            CommandKind::Ack => simple(Command::Ack),
            CommandKind::Jog => arity(1).and_then(|()| number(a)).map(Command::Jog),
            CommandKind::Servo => arity(1).and_then(|()| number(a)).map(Command::Servo),
            CommandKind::Weigh => {
                let ch = Channel::from_name(a).ok_or(CommandError::Argument)?;
                Ok(Command::Weigh(ch, number(b)?))
            }
            CommandKind::Set => {
                let key = Key::ALL
                    .into_iter()
                    .find(|k| k.name().as_bytes() == a)
                    .ok_or(if a.is_empty() {
                        CommandError::Argument
                    } else {
                        CommandError::UnknownKey
                    })?;
                // A code (the order, the mode, the force profile) by its name.
                let value = match key.setting().value() {
                    Value::Code => {
                        let code = key.setting().code_of_name(b);
                        code.ok_or(CommandError::Argument)? as f32
                    }
                    _ => number(b)?,
                };
                Ok(Command::Set(key, value))
            }
            CommandKind::Unparsed => Err(CommandError::Unknown),
        }
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
/// into a 128 KiB budget. Exact for what a person types: the digits form an exact integer and
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
        assert_eq!(
            Command::parse("set mode force"),
            Ok(Command::Set(Key::Mode, 1.0))
        );
        assert_eq!(
            Command::parse("set force_profile sine"),
            Ok(Command::Set(Key::ForceProfile, 2.0))
        );
        assert_eq!(
            Command::parse("set model_t2_offset_n -0.82"),
            Ok(Command::Set(Key::ModelT2OffsetN, -0.82))
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
        assert_eq!(Command::parse("set mode 1"), Err(CommandError::Argument));
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
