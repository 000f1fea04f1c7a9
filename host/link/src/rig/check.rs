//! What `capstan rig` checks before anything reaches the board: the words make one command
//! line the firmware's own parser (`capstan_rig::Command::parse`) takes, short enough for its
//! line buffer, and a `set` keeps the settings valid (`capstan_rig::Settings::with`). A typo is
//! refused here with the firmware's own reason, and never sent.

use capstan_rig::command::{Command, CommandError, MAX_LINE};
use capstan_rig::{Settings, SettingsError};

/// Why a command line is refused before it is sent.
#[derive(Clone, Debug, PartialEq)]
pub enum CheckError {
    /// No words.
    Empty,
    /// The firmware refuses the line (its message).
    Command(CommandError),
    /// The value would make the board's settings invalid (the firmware's reason).
    Setting(&'static str, SettingsError),
    /// A host verb (`live`, `keys`) used wrongly: what is wrong.
    Usage(String),
    /// A value outside the physical range the data reader takes (`data::ranges`): what
    /// `capstan log` would write from it could not be analysed.
    Range(&'static str, f32, capstan_data::ranges::RangeError),
}

impl std::fmt::Display for CheckError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CheckError::Empty => f.write_str(
                "no command: give one of setup, leave, jog, servo, zero, weigh, set, show, \
                 store, defaults, run, abort, ack (or the host verbs live, keys)",
            ),
            CheckError::Command(e) => write!(f, "not sent: {}", e.message()),
            CheckError::Setting(key, e) => write!(f, "not sent: set {key}: {}", e.message()),
            CheckError::Usage(why) => f.write_str(why),
            CheckError::Range(key, v, why) => write!(
                f,
                "not sent: set {key} {v}: {why} (0 = not given); pairs.csv carries it, and \
                 capstan analyze reads only values in that range"
            ),
        }
    }
}

impl std::error::Error for CheckError {}

/// The command line the words make (joined by single spaces), and the command the firmware
/// will read from it.
pub fn command_line(words: &[String]) -> Result<(String, Command), CheckError> {
    if words.is_empty() {
        return Err(CheckError::Empty);
    }
    let line = words.join(" ");
    if line.contains('\n') || line.contains('\r') {
        return Err(CheckError::Command(CommandError::Argument));
    }
    if line.len() > MAX_LINE {
        return Err(CheckError::Command(CommandError::TooLong));
    }
    let cmd = Command::parse(&line).map_err(CheckError::Command)?;
    if let Command::Weigh(_, n) = cmd {
        // The board would refuse it as "settings invalid": say what is wrong instead.
        if !(n.is_finite() && n > 0.0) {
            return Err(CheckError::Usage(format!(
                "not sent: {line}: a weight must be above 0 N (the known mass hung on the \
                 sensor, as its weight: 1 kg is 9.80665 N)"
            )));
        }
    }
    Ok((line, cmd))
}

/// A `set` against the settings the board reports: refused, with the reason, if the value
/// would make them invalid. Other commands pass.
pub fn check_set(cmd: &Command, current: &Settings) -> Result<(), CheckError> {
    use capstan_data::ranges;
    use capstan_rig::command::Key;
    match cmd {
        Command::Set(key @ (Key::DiameterMm | Key::WrapDeg), value) if *value != 0.0 => {
            let range = if *key == Key::DiameterMm {
                &ranges::DIAMETER_MM
            } else {
                &ranges::WRAP_DEG
            };
            range
                .check(f64::from(*value))
                .map_err(|why| CheckError::Range(key.name(), *value, why))?;
            current
                .with(*key, *value)
                .map(|_| ())
                .map_err(|e| CheckError::Setting(key.name(), e))
        }
        Command::Set(key, value) => current
            .with(*key, *value)
            .map(|_| ())
            .map_err(|e| CheckError::Setting(key.name(), e)),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use capstan_rig::command::Key;
    use capstan_rig::hal::Channel;
    use capstan_rig::{Calibration, Protocol};

    fn words(line: &str) -> Vec<String> {
        line.split(' ').map(String::from).collect()
    }

    #[test]
    fn good_words_make_the_line_the_firmware_reads() {
        let (line, cmd) = command_line(&words("weigh t1 9.80665")).unwrap();
        assert_eq!(line, "weigh t1 9.80665");
        assert_eq!(cmd, Command::Weigh(Channel::T1, 9.80665));
        let (_, cmd) = command_line(&words("set order updown")).unwrap();
        assert_eq!(cmd, Command::Set(Key::Order, 1.0));
        assert_eq!(
            command_line(&["jog".into(), "-2.5".into()]).unwrap().1,
            Command::Jog(-2.5)
        );
    }

    #[test]
    fn typos_are_refused_with_the_firmware_message() {
        let refused = |l: &str| command_line(&words(l)).unwrap_err();
        assert_eq!(refused("jgo 5"), CheckError::Command(CommandError::Unknown));
        assert_eq!(
            refused("jog five"),
            CheckError::Command(CommandError::Argument)
        );
        assert_eq!(
            refused("weigh t3 1"),
            CheckError::Command(CommandError::Argument)
        );
        assert_eq!(
            refused("set speed 3"),
            CheckError::Command(CommandError::UnknownKey)
        );
        let e = refused("set dwel_ms 8000").to_string();
        assert_eq!(
            e,
            format!("not sent: {}", CommandError::UnknownKey.message())
        );
        let long = format!("set dwell_ms {}", "0".repeat(60));
        assert_eq!(refused(&long), CheckError::Command(CommandError::TooLong));
        assert_eq!(command_line(&[]).unwrap_err(), CheckError::Empty);
        let e = refused("weigh t1 -9.8").to_string();
        assert!(e.contains("a weight must be above 0 N"), "{e}");
        assert!(refused("weigh t2 0").to_string().contains("above 0 N"));
        let two_lines = vec!["zero\nrun".to_string()];
        assert!(command_line(&two_lines).is_err());
    }

    #[test]
    fn a_set_that_would_make_the_settings_invalid_is_refused_with_the_reason() {
        let s = Settings {
            protocol: Protocol::default(),
            calibration: Calibration::default(),
        };
        // The set-up values pairs.csv carries stay inside the reader's ranges.
        let (_, dia) = command_line(&words("set diameter_mm 2000")).unwrap();
        let e = check_set(&dia, &s).unwrap_err().to_string();
        assert!(
            e.starts_with("not sent: set diameter_mm 2000: must be greater than 0"),
            "{e}"
        );
        let (_, none) = command_line(&words("set diameter_mm 0")).unwrap();
        assert_eq!(check_set(&none, &s), Ok(()));
        let (_, ok) = command_line(&words("set dwell_ms 8000")).unwrap();
        assert_eq!(check_set(&ok, &s), Ok(()));
        let (_, half) = command_line(&words("set dwell_ms 8000.5")).unwrap();
        let e = check_set(&half, &s).unwrap_err();
        assert_eq!(e, CheckError::Setting("dwell_ms", SettingsError::NotWhole));
        assert_eq!(
            e.to_string(),
            format!(
                "not sent: set dwell_ms: {}",
                SettingsError::NotWhole.message()
            )
        );
        let (_, wrap) = command_line(&words("set wrap_deg 4000")).unwrap();
        assert!(matches!(
            check_set(&wrap, &s),
            Err(CheckError::Range("wrap_deg", 4000.0, _))
        ));
        assert_eq!(check_set(&Command::Zero, &s), Ok(()));
    }
}
