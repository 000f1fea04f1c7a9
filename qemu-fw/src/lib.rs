//! The run the emulated-ARM firmware makes, as data: protocol, calibration, safety limits,
//! plant and seed. The firmware image (`src/main.rs`, thumbv7m-none-eabi under QEMU) runs it
//! on the rig core; the host test `tests/log_qemu.rs` runs the very same thing through
//! host-sim and compares the decoded pairs. One definition, so the two cannot drift.
//!
//! QEMU runs in real time, so the protocol is short: three levels of 600 ms (2.8 s).
#![no_std]

pub mod placeholder;

use firmware::safety::SafetyLimits;
use firmware::{Calibration, Protocol, StepOrder};

/// Seed of the simulated plant's noise.
pub const SEED: u64 = 0x6361_7073_7461_6e06;

/// The QEMU end-to-end protocol: the thesis's, scaled down to 2.8 s (three levels).
pub fn protocol() -> Protocol {
    Protocol {
        rest_deg: 125.0,
        step_deg: 5.0,
        final_deg: 110.0,
        order: StepOrder::Monotone,
        dwell_ms: 600,
        pre_trigger_ms: 300,
        trigger_ms: 100,
        tare_ms: 200,
        amp_control_v: 2.5,
        sample_hz: 1_000,
        raw_log_hz: 50,
        window_after_change_ms: 200,
        window_before_next_ms: 100,
        capstan_diameter_mm: 12.7,
        wrap_deg: 360.0,
    }
}

/// The calibration the rig starts from (the tare then re-zeroes both channels).
pub fn calibration() -> Calibration {
    Calibration::default()
}

/// The safety limits in force.
pub fn limits() -> SafetyLimits {
    SafetyLimits::default()
}
