//! What survives a reset, and what the rig does with it at boot.
//!
//! The RP2040's watchdog scratch registers keep their value through a watchdog or panic reset
//! (and a debugger's reset of the core), not through a power-on, a brown-out, the RUN pin or
//! the debug port's restart, which reset the whole chip. The board reads why it reset
//! ([`ResetCause::from_registers`]: the watchdog's REASON, then whether our word survived, then
//! the chip's CHIP_RESET flags) and keeps two words there, written every sample
//! ([`latch_word`]) and by every servo write ([`remembered_servo_word`]):
//!
//! * the fault latch and whether the rig was at rest (idle, servo commanded to rest, nothing
//!   latched): so a latch is never cleared by a reset, and a reset in the middle of anything
//!   is latched too ([`boot_latch`]);
//! * the servo's last command, for the boot's log line (where the horn was told to be).
//!
//! Per reset kind ([`boot_latch`]):
//!
//! | reset | kept | boots |
//! |---|---|---|
//! | watchdog (a hang, a lockup) | the latch word | latched: the fault before it, or `watchdog` |
//! | forced (the panic/HardFault handler) | the latch word | latched: the fault before it, or `panic` |
//! | the core alone (a debugger's SYSRESETREQ) | the latch word | latched: the fault before it, or `reset` unless it was at rest |
//! | the RUN pin, the debug port | nothing | latched `reset` (what it was doing is unknown) |
//! | power-on or brown-out | nothing | clean: the first pulse is the stored rest |
//!
//! A power-on and a brown-out are one flag on the RP2040 (HAD_POR): the chip cannot tell a
//! supply that dipped mid-run from a person plugging it in, so both boot clean. A fault latched
//! before either is lost; what the boot does is still safe: the pins were released (the drive
//! off, the servo without pulses, the cord back-driving it toward release) and the first pulse
//! is rest, which releases further; nothing runs without a press.
//!
//! A reset that is not a clean power-up at rest boots latched ([`crate::Rig::boot_latched`]):
//! the servo gets no pulses (the cord can only back-drive it toward release) and nothing runs
//! until a person acknowledges the fault, with a press (after the button was seen released)
//! or `ack`. The first pulse then is the rest pulse. Before, such a boot re-sent the last
//! tension pulse and homed from it at once: a re-pull at the servo's full speed on a horn the
//! cord had pulled back while the chip was in reset.

use crate::record::{FaultKind, LogSink, NONE_CODE};
use crate::rig::Rig;

/// Why the chip last reset.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub enum ResetCause {
    /// A power-on or a brown-out (the chip's HAD_POR, or no flag at all): nothing kept.
    PowerOn,
    /// The RUN pin (HAD_RUN: a reset button, a supervisor chip): nothing kept.
    RunPin,
    /// The debug port restarted the chip (HAD_PSM_RESTART): nothing kept.
    DebugPort,
    /// Only the core was reset (a debugger's SYSRESETREQ): the scratch registers kept.
    Core,
    /// The watchdog timed out: the loop stopped (a hang, a lockup, a stack overflow).
    Watchdog,
    /// Software triggered the watchdog: the panic or HardFault handler.
    Forced,
}

impl ResetCause {
    /// The cause from the registers: the watchdog's REASON (`Some(true)` timer, `Some(false)`
    /// forced), whether the latch word in the scratch register is ours (it survived: only the
    /// core reset), and the chip's CHIP_RESET flags (`had_run`, `had_psm_restart`; HAD_POR
    /// or none is a power-on). REASON is cleared by every chip-level reset, CHIP_RESET only
    /// by the next chip-level reset: so it is read last.
    pub fn from_registers(
        watchdog_timer: Option<bool>,
        latch_word: u32,
        had_run: bool,
        had_psm_restart: bool,
    ) -> ResetCause {
        match watchdog_timer {
            Some(true) => ResetCause::Watchdog,
            Some(false) => ResetCause::Forced,
            None if read_latch_word(latch_word).is_some() => ResetCause::Core,
            None if had_run => ResetCause::RunPin,
            None if had_psm_restart => ResetCause::DebugPort,
            None => ResetCause::PowerOn,
        }
    }
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

/// The fault to latch at boot, if any (the module's table): after a watchdog or panic reset,
/// always (the fault latched before, or the reset's own kind); after a reset of the core, the
/// fault latched before it, or [`FaultKind::Reset`] if the rig was not at rest; after the RUN
/// pin or the debug port, which keep nothing, [`FaultKind::Reset`]. Only a power-on (or a
/// brown-out), or a core reset with the rig at rest and nothing latched, boots clean.
pub fn boot_latch(cause: ResetCause, word: u32) -> Option<FaultKind> {
    let kept = read_latch_word(word);
    let before = kept.and_then(|(f, _)| f);
    match cause {
        ResetCause::Watchdog => Some(before.unwrap_or(FaultKind::Watchdog)),
        ResetCause::Forced => Some(before.unwrap_or(FaultKind::Panic)),
        ResetCause::RunPin | ResetCause::DebugPort => Some(before.unwrap_or(FaultKind::Reset)),
        ResetCause::Core | ResetCause::PowerOn => match kept {
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
        assert_eq!(boot_latch(PowerOn, 0), None);
        // The core alone reset, the word kept.
        assert_eq!(boot_latch(Core, at_rest), None);
        assert_eq!(boot_latch(Core, moving), Some(FaultKind::Reset));
        assert_eq!(boot_latch(Core, latched), Some(FaultKind::OverForce));
        // The RUN pin and the debug port keep nothing: what the rig was doing is unknown.
        assert_eq!(boot_latch(RunPin, 0), Some(FaultKind::Reset));
        assert_eq!(boot_latch(DebugPort, 0), Some(FaultKind::Reset));
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
    fn the_cause_is_read_from_reason_then_the_kept_word_then_the_chip_flags() {
        let kept = latch_word(&rig());
        use ResetCause::*;
        let c = ResetCause::from_registers;
        assert_eq!(c(Some(true), kept, true, false), Watchdog);
        assert_eq!(c(Some(false), 0, false, false), Forced);
        // A chip-level reset clears the scratch registers; HAD_POR stays set from the
        // power-on through a later core reset, so the kept word decides first.
        assert_eq!(c(None, kept, false, false), Core);
        assert_eq!(c(None, 0, true, false), RunPin);
        assert_eq!(c(None, 0, false, true), DebugPort);
        assert_eq!(c(None, 0, false, false), PowerOn);
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
