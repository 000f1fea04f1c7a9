//! What survives a reset, and what the rig does with it at boot.
//!
//! The RP2040's watchdog scratch registers keep their value through a watchdog or panic reset
//! (and a debugger's), not through a power cycle. The board keeps two words there, written
//! every sample ([`latch_word`]) and by every servo write ([`remembered_servo_word`]):
//!
//! * the fault latch and whether the rig was at rest (idle, servo commanded to rest, nothing
//!   latched): so a latch is never cleared by a reset, and a reset in the middle of anything
//!   is latched too ([`boot_latch`]);
//! * the servo's last command, for the boot's log line (where the horn was told to be).
//!
//! A reset that is not a clean power-up at rest boots latched ([`crate::Rig::boot_latched`]):
//! the servo gets no pulses (the cord can only back-drive it toward release) and nothing runs
//! until a person acknowledges the fault, with a press (after the button was seen released)
//! or `ack`. The first pulse then is the rest pulse. Before, such a boot re-sent the last
//! tension pulse and homed from it at once: a re-pull at the servo's full speed on a horn the
//! cord had pulled back while the chip was in reset.

use crate::record::{FaultKind, LogSink, NONE_CODE};
use crate::rig::Rig;

/// Why the chip last reset, as its watchdog tells it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub enum ResetCause {
    /// Neither watchdog bit: a power-up, or a reset from the RUN pin or a debugger.
    PowerUp,
    /// The watchdog timed out: the loop stopped (a hang, a lockup, a stack overflow).
    Watchdog,
    /// Software triggered the watchdog: the panic or HardFault handler.
    Forced,
}

/// Tag of a latch word (upper 16 bits).
const LATCH_TAG: u32 = 0xCA58_0000;
/// Bit of a latch word: the rig was at rest.
const AT_REST: u32 = 1;

/// The latch word for `rig` now: the latched fault's code (bits 8-15, [`NONE_CODE`] for none)
/// and whether the rig is at rest (bit 0).
pub fn latch_word(rig: &Rig) -> u32 {
    let code = rig.latched_fault().map_or(NONE_CODE, FaultKind::code) as u32;
    let rest = if rig.is_at_rest() && rig.latched_fault().is_none() {
        AT_REST
    } else {
        0
    };
    LATCH_TAG | code << 8 | rest
}

/// A latch word read back after a reset: (latched fault, at rest), `None` unless it is one of
/// ours (after a power cycle the register holds 0).
pub fn read_latch_word(word: u32) -> Option<(Option<FaultKind>, bool)> {
    if word & 0xFFFF_0000 != LATCH_TAG || word & 0xFE != 0 {
        return None;
    }
    let code = ((word >> 8) & 0xFF) as u8;
    let fault = match code {
        NONE_CODE => None,
        c => Some(FaultKind::from_code(c)?),
    };
    Some((fault, word & AT_REST != 0))
}

/// The fault to latch at boot, if any: after a watchdog or panic reset, always (the fault
/// latched before, or the reset's own kind); after any other reset, the fault latched before
/// it, or [`FaultKind::Reset`] if the rig was not at rest. Only a power-up with nothing kept,
/// or with the rig at rest and nothing latched, boots clean.
pub fn boot_latch(cause: ResetCause, word: u32) -> Option<FaultKind> {
    let kept = read_latch_word(word);
    let before = kept.and_then(|(f, _)| f);
    match cause {
        ResetCause::Watchdog => Some(before.unwrap_or(FaultKind::Watchdog)),
        ResetCause::Forced => Some(before.unwrap_or(FaultKind::Panic)),
        ResetCause::PowerUp => match kept {
            Some((Some(f), _)) => Some(f),
            Some((None, false)) => Some(FaultKind::Reset),
            _ => None,
        },
    }
}

/// At boot, after the settings are loaded: latch what [`boot_latch`] says (recorded, the servo
/// without pulses). Returns it.
pub fn boot(
    rig: &mut Rig,
    cause: ResetCause,
    word: u32,
    sink: &mut impl LogSink,
) -> Option<FaultKind> {
    let kind = boot_latch(cause, word)?;
    rig.boot_latched(kind, sink);
    Some(kind)
}

/// Tag of a servo duty kept across a reset (upper 16 bits of the word).
const SERVO_WORD_TAG: u32 = 0xCA57_0000;

/// The word that keeps a servo duty across a reset (e.g. in the RP2040's watchdog scratch
/// register, which survives a watchdog reset but not a power cycle).
pub const fn remembered_servo_word(duty: u16) -> u32 {
    SERVO_WORD_TAG | duty as u32
}

/// The servo duty a word kept across a reset holds, if it is one of ours and a pulse within
/// the PWM's range (`None` after a power cycle, or for anything else).
pub const fn recall_servo_duty(word: u32, max_duty: u16) -> Option<u16> {
    let duty = (word & 0xFFFF) as u16;
    if word & 0xFFFF_0000 == SERVO_WORD_TAG && duty > 0 && duty <= max_duty {
        Some(duty)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::safety::SafetyLimits;
    use crate::{Calibration, Protocol};

    fn rig() -> Rig {
        Rig::new(
            Protocol::default(),
            Calibration::default(),
            SafetyLimits::default(),
        )
        .unwrap()
    }

    #[test]
    fn only_a_power_up_at_rest_boots_clean() {
        let at_rest = latch_word(&rig());
        assert_eq!(read_latch_word(at_rest), Some((None, true)));
        let mut moving = rig();
        moving.home_from(100.0);
        let moving = latch_word(&moving);
        assert_eq!(read_latch_word(moving), Some((None, false)));
        let latched = LATCH_TAG | (FaultKind::OverForce.code() as u32) << 8;
        use ResetCause::*;
        // A power cycle: the register reads 0.
        assert_eq!(boot_latch(PowerUp, 0), None);
        assert_eq!(boot_latch(PowerUp, at_rest), None);
        assert_eq!(boot_latch(PowerUp, moving), Some(FaultKind::Reset));
        assert_eq!(boot_latch(PowerUp, latched), Some(FaultKind::OverForce));
        // The watchdog and the panic handler always latch, keeping an earlier fault.
        assert_eq!(boot_latch(Watchdog, 0), Some(FaultKind::Watchdog));
        assert_eq!(boot_latch(Watchdog, at_rest), Some(FaultKind::Watchdog));
        assert_eq!(boot_latch(Forced, moving), Some(FaultKind::Panic));
        assert_eq!(boot_latch(Forced, latched), Some(FaultKind::OverForce));
        // Someone else's words are not ours.
        for w in [0xB007_C0D3, LATCH_TAG | 0x4200, LATCH_TAG | 0x0f02] {
            assert_eq!(read_latch_word(w), None, "{w:#x}");
        }
    }

    #[test]
    fn a_servo_duty_survives_a_reset_only_as_our_word() {
        assert_eq!(
            recall_servo_duty(remembered_servo_word(5_728), 62_500),
            Some(5_728)
        );
        // Power-on value, someone else's word, no pulse, a duty beyond the top.
        for w in [0, 0xB007_C0D3, remembered_servo_word(0), 0xCA57_FFFF] {
            assert_eq!(recall_servo_duty(w, 62_500), None, "{w:#x}");
        }
    }
}
