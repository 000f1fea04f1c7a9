//! The last-resort safe state: what a panic or HardFault handler does before anything else.
//!
//! In normal operation the runner makes the rig safe through its drivers
//! ([`crate::RigIo::make_safe`], and every fault ends its run in the safe state). A panic or a
//! HardFault can strike with those drivers in any state — borrowed mid-write, not yet built, or
//! the whole rig never made — so the handlers cannot use them, nor the [`crate::Rig`], nor
//! floating point, locks or the log. They call [`force_safe`] on a [`ForceOutputs`] that reaches
//! the outputs directly: the RP2040 board implements it on raw registers
//! (`firmware/rig/src/board_panic.rs`), the simulated plant on its pins (`capstan-plant`'s
//! `hal::ForcedOutputs`), so the simulator proves the same sequence the board runs.
//!
//! The only number the handlers need, the servo's rest duty, is computed once at boot while
//! everything works ([`SafeDuties::for_rig`]) and kept where a handler can read it.
//!
//! What survives a reset (the fault latch, the servo's last command) is in [`crate::reset`].

use crate::rig::Rig;

/// The rig's outputs as a panic or HardFault handler reaches them: directly, whatever state
/// their drivers are in. Every method must be safe to call at any time, any number of times,
/// in any order, and must not block.
pub trait ForceOutputs {
    /// Amplifier control to 0 V (PWM duty 0, or the pin driven low): the drive stops.
    fn force_amp_off(&mut self);
    /// Servo PWM to `duty` counts of its frame's top; 0 stops the pulses (the servo is then
    /// unpowered: it holds no position and pulls on nothing).
    fn force_servo_duty(&mut self, duty: u16);
    /// Logger trigger line low.
    fn force_trigger_low(&mut self);
}

/// What the handlers command, computed at boot while everything still works.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SafeDuties {
    /// Servo PWM duty of the rest angle (0: no pulses).
    pub servo_rest: u16,
}

impl SafeDuties {
    /// Before the rig exists: no servo pulses at all (the servo goes limp), amplifier off.
    pub const NO_SERVO_PULSES: SafeDuties = SafeDuties { servo_rest: 0 };

    /// The rig's rest angle through its calibration, on a servo PWM whose top is
    /// `servo_max_duty`: the same duty the runner writes for the rest angle. No pulses while
    /// the rig holds the servo without them ([`Rig::is_limp`]: after a reset, until a person
    /// acknowledges it): a panic then must not be what moves the servo.
    pub fn for_rig(rig: &Rig, servo_max_duty: u16) -> SafeDuties {
        if rig.is_limp() {
            return SafeDuties::NO_SERVO_PULSES;
        }
        let cal = rig.calibration();
        SafeDuties {
            servo_rest: cal.servo.duty(rig.protocol().rest_deg, servo_max_duty),
        }
    }

    /// What the handlers command with the servo last commanded to `commanded_duty`: rest, or
    /// where it is if that releases more (setup mode jogged it past rest, to the release side:
    /// the rest pulse would swing it back toward tension at the servo's full speed). A longer
    /// pulse releases: the calibration's map is never reversed and rest is a run's longest
    /// pulse. No pulses stays no pulses.
    pub const fn releasing(self, commanded_duty: u16) -> SafeDuties {
        if self.servo_rest == 0 || commanded_duty <= self.servo_rest {
            self
        } else {
            SafeDuties {
                servo_rest: commanded_duty,
            }
        }
    }
}

/// Drive every output to the safe state: the amplifier off first (the drive is the hazard),
/// then the servo to its rest duty (releasing the cord), then the trigger low.
pub fn force_safe(out: &mut impl ForceOutputs, duties: SafeDuties) {
    out.force_amp_off();
    out.force_servo_duty(duties.servo_rest);
    out.force_trigger_low();
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::safety::SafetyLimits;
    use crate::{Calibration, Protocol};
    use std::vec::Vec;

    #[derive(Default)]
    struct Pins(Vec<&'static str>, Vec<u16>);

    impl ForceOutputs for Pins {
        fn force_amp_off(&mut self) {
            self.0.push("amp");
        }
        fn force_servo_duty(&mut self, duty: u16) {
            self.0.push("servo");
            self.1.push(duty);
        }
        fn force_trigger_low(&mut self) {
            self.0.push("trigger");
        }
    }

    #[test]
    fn the_amplifier_goes_first_and_the_servo_to_the_runners_rest_duty() {
        let rig = Rig::new(
            Protocol::default(),
            Calibration::default(),
            SafetyLimits::default(),
        )
        .unwrap();
        let duties = SafeDuties::for_rig(&rig, 62_500);
        // 125° under the Arduino convention: 1833 µs of the 20 ms frame.
        assert_eq!(duties.servo_rest, 5_728);
        assert_eq!(
            duties.servo_rest,
            rig.calibration().servo.duty(125.0, 62_500)
        );
        let mut pins = Pins::default();
        force_safe(&mut pins, duties);
        assert_eq!(pins.0, ["amp", "servo", "trigger"]);
        assert_eq!(pins.1, [5_728]);
        let mut pins = Pins::default();
        force_safe(&mut pins, SafeDuties::NO_SERVO_PULSES);
        assert_eq!(pins.1, [0]);
        // Jogged past rest (135°, a longer pulse): it stays; at a level (65°): rest.
        let past = rig.calibration().servo.duty(135.0, 62_500);
        let level = rig.calibration().servo.duty(65.0, 62_500);
        assert_eq!(duties.releasing(past).servo_rest, past);
        assert_eq!(duties.releasing(level).servo_rest, 5_728);
        assert_eq!(SafeDuties::NO_SERVO_PULSES.releasing(past).servo_rest, 0);
    }
}
