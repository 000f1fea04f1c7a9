//! The host's commands as the wire knows them: one text line each, the command words, and the
//! codes and messages of the `reply` record.
//!
//! ```text
//! setup | leave | jog DEG | servo DEG | zero | weigh t1|t2 NEWTONS
//! set KEY VALUE | show | store | defaults | run | abort | ack
//! ```

/// Longest command line, bytes (without the newline).
pub const MAX_LINE: usize = 64;

/// The kind of a command, as the `reply` record names it (its `command` code).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CommandKind {
    /// A line that did not parse.
    Unparsed = 0,
    /// Enter setup mode (from idle).
    Setup,
    /// Leave setup mode (the servo homes to rest).
    Leave,
    /// Move the servo command by DEG degrees (setup mode).
    Jog,
    /// Move the servo command to DEG (setup mode).
    Servo,
    /// Zero both channels (setup mode).
    Zero,
    /// A known force hangs on a channel: its sensitivity (setup mode).
    Weigh,
    /// Set one value of the settings (idle or setup).
    Set,
    /// Report the settings in force.
    Show,
    /// Keep the settings in force in flash.
    Store,
    /// Go back to the firmware's built-in settings.
    Defaults,
    /// Arm a run: the next press of the rig's button (within the firmware's arm window) starts
    /// it. The host never starts the drive by itself.
    Run,
    /// Stop the run, as the button does (or leave setup mode).
    Abort,
    /// Acknowledge a latched fault, as the button does (not one a reset latched: those only a
    /// press at the rig clears).
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
        WORDS[self as usize]
    }

    /// The kind of a command word (as bytes: the board's parser has no `str`).
    pub fn from_word(word: &[u8]) -> Option<CommandKind> {
        let i = WORDS.iter().skip(1).position(|w| w.as_bytes() == word)?;
        CommandKind::ALL.get(i + 1).copied()
    }
}

/// The command words, by code.
const WORDS: [&str; 14] = [
    "?", "setup", "leave", "jog", "servo", "zero", "weigh", "set", "show", "store", "defaults",
    "run", "abort", "ack",
];

/// Why a command was refused (the `reply` record's `error` code; 0 is success).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
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
    /// `weigh` measures from the zero in force: it must be one measured in this setup session,
    /// with the servo where it was then.
    NotZeroed = 19,
    /// A zero that would move the zero in force by more than a tare may (1 N): something hangs
    /// on a hook, or the cord pulls.
    ZeroMoved = 20,
    /// A force channel's sensitivity is the built-in placeholder (nobody weighed or typed it):
    /// no run until it is.
    Uncalibrated = 21,
    /// The latched fault came from a reset (watchdog, panic, reset): only a press at the rig
    /// clears it, where a person can see the rig.
    NeedsPress = 22,
}

impl CommandError {
    /// Every error, by code.
    pub const ALL: [CommandError; 22] = [
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
        CommandError::NotZeroed,
        CommandError::ZeroMoved,
        CommandError::Uncalibrated,
        CommandError::NeedsPress,
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
            CommandError::Argument => "an argument is missing or wrong (jog DEG, servo DEG, weigh t1|t2 NEWTONS, set KEY VALUE) or the line has too much on it",
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
            CommandError::Blind => "with that calibration the over-force limit would read above the high rail check, or the -3 N limit below the low one (a zero too near the ADC's floor, where an unplugged sensor reads), so a check could never trip (the sensor's range or offset, or the value, is wrong); nothing changed",
            CommandError::NotAtRest => "store only with the servo at rest: the flash write holds the safety loop (send servo <rest> and wait, or leave setup mode and let it home)",
            CommandError::NotZeroed => "weigh measures from the zero taken in this setup session, with the servo where it was then, and this is not that (no zero yet, a set or defaults replaced it, or the servo moved since): take the weight off, send zero, then hang the weight and weigh without moving the servo; nothing changed",
            CommandError::ZeroMoved => "the readings are more than 1 N from the zero in force: take off anything hanging on either hook, slacken the cord, and zero again (a new or re-wired sensor whose zero really moved: set t1_zero or t2_zero to the counts rig live shows, then zero, then weigh it again: a zero that moved more than 1 N from the one its sensitivity was measured at leaves that sensitivity unmeasured); nothing changed",
            CommandError::Uncalibrated => "a force sensor's sensitivity was never measured (the built-in placeholder: a fresh board, defaults, a damaged or older stored record, or a zero moved more than 1 N since the weigh): weigh it in setup mode (weigh t1|t2 NEWTONS) or type it (set t1_n_per_count / t2_n_per_count), then store; nothing runs until then",
            CommandError::NeedsPress => "this fault was latched by a reset (watchdog, panic or reset): only a press of the rig's button clears it, by a person who can see the rig",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_and_words_round_trip() {
        for (i, k) in CommandKind::ALL.into_iter().enumerate() {
            assert_eq!(k.code() as usize, i);
            assert_eq!(CommandKind::from_code(k.code()), Some(k));
            if k != CommandKind::Unparsed {
                assert_eq!(CommandKind::from_word(k.word().as_bytes()), Some(k));
                // The refusal of an unknown word lists every word.
                assert!(CommandError::Unknown.message().contains(k.word()));
            }
        }
        assert_eq!(CommandKind::from_word(b"?"), None);
        for e in CommandError::ALL {
            assert_eq!(CommandError::from_code(e.code()), Some(e));
        }
        assert!(CommandError::TooLong
            .message()
            .contains(&format!("{MAX_LINE} bytes")));
    }
}
