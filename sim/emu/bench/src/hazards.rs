//! Issue 38's hazards as emulated-board cases: sensors, cords, buttons and hosts that fail the
//! way real parts do, on the release image. Kept short (a few seconds of protocol where they
//! can be); the quick ones are in the fixed slice.

use crate::case::{cord, core_case, Case, CoreFault, HostLine, Stop, TYPED};
use capstan_plant::{AdcConfig, CordSetup, Injection, InjectionKind};
use capstan_rig::hal::Channel;

/// When T2 freezes and when the cord snags, µs after the trigger (the reproduction:
/// 15 s and 20 s; level 2 begins at 20.5 s).
pub const FROZEN_AT_US: u64 = 15_000_000;
/// See [`FROZEN_AT_US`].
pub const SNAG_AT_US: u64 = 20_000_000;
/// When the cord parts, µs after the trigger: 2 s into level 1, with a preload of 0.02 N
/// (the tare reads it as the reference, 0.1 N).
pub const PARTED_AT_US: u64 = 12_500_000;
/// When T1 is unplugged in `unplugged_low_zero`, µs after the trigger (a run started by its
/// second press would have triggered at ~2.5 s).
pub const UNPLUGGED_AT_US: u64 = 1_000_000;
/// The held button: from 1 s after power-up, for 100 s.
pub const HELD_US: (u64, u64) = (1_000_000, 100_000_000);

fn at(kind: InjectionKind, after_trigger_us: u64) -> Injection {
    Injection {
        kind,
        cord: 0,
        after_trigger_us,
    }
}

/// The cases, each named for its hazard.
pub fn cases() -> Vec<Case> {
    let mut frozen = Case::base(
        "frozen_snag",
        "T2 frozen at its value 15 s after the trigger, a 50 N snag at 20 s: the drive off \
         within 5 s of the snag (issue 38)",
        31,
        Stop::AfterTrigger(SNAG_AT_US + 5_500_000),
    );
    frozen.plant.adc = AdcConfig::RP2040;
    frozen.injections = vec![
        at(InjectionKind::Frozen(Channel::T2), FROZEN_AT_US),
        at(InjectionKind::OverForce, SNAG_AT_US),
    ];
    let mut parted = Case::base(
        "parted_low_preload",
        "the cord parts 2 s into level 1 with a preload of 0.02 N (the tare's reference is \
         0.1 N): the drive off within 2 s (issue 38)",
        32,
        Stop::AfterTrigger(PARTED_AT_US + 2_500_000),
    );
    parted.plant.adc = AdcConfig::RP2040;
    parted.plant.cord.preload_n = 0.02;
    parted.injections = vec![at(InjectionKind::CordBreak, PARTED_AT_US)];
    let placeholder = Case {
        commands: Vec::new(),
        quick: true,
        ..Case::base(
            "placeholder",
            "a board as flashed, its sensitivities the placeholder nobody measured: a press \
             starts nothing (issue 38)",
            33,
            Stop::At(3_000_000),
        )
    };
    let host_run = Case {
        cord: CordSetup {
            press_at_us: None,
            ..cord()
        },
        commands: TYPED
            .into_iter()
            .chain([HostLine::at_ms(300, "run")])
            .collect(),
        quick: true,
        ..Case::base(
            "host_run",
            "the host sends `run` and nobody presses: no drive (issue 38)",
            34,
            Stop::At(10_000_000),
        )
    };
    let held = Case {
        cord: CordSetup {
            press_at_us: None,
            ..cord()
        },
        held_us: Some(HELD_US),
        ..Case::base(
            "held_100s",
            "the button held (a shorted lead) for 100 s from 1 s after power-up: no drive; \
             reported after 2 s (issue 38)",
            35,
            Stop::At(HELD_US.0 + HELD_US.1 + 1_000_000),
        )
    };
    // Two presses: the first acknowledges what the boot latched (the readings at the floor),
    // the second would start a run. (Before issue 38: a zero of 15 was taken, the run ran, and
    // the unplug read as 0 N: no fault.)
    let mut low_zero = Case {
        commands: TYPED
            .into_iter()
            .chain([
                HostLine::at_ms(200, "set t1_zero 15"),
                HostLine::at_ms(250, "set t2_zero 15"),
            ])
            .collect(),
        held_us: Some((1_500_000, 200_000)),
        injections: vec![at(
            InjectionKind::SensorUnplugged(Channel::T1),
            UNPLUGGED_AT_US,
        )],
        quick: true,
        ..Case::base(
            "unplugged_low_zero",
            "0-5 V sensors at 0 V with no load read the ADC's floor (15 counts), where an \
             unplugged one reads: their zeros refused, the channels at the floor latched, no \
             drive; T1 unplugged 1 s after a trigger that never comes (issue 38)",
            36,
            Stop::At(6_000_000),
        )
    };
    low_zero.plant.adc = AdcConfig::RP2040;
    low_zero.plant.sensor.zero_counts = 0.0;
    low_zero.plant.sensor.zero_spread_counts = 0.0;
    let debugger = core_case(
        "debugger_watchdog",
        "a debugger disables the watchdog (and sets it to pause on halt) 2 s after the \
         trigger, and 5 ms later the loop hangs: the firmware had written its control back at \
         the next feed, and the watchdog resets the chip 10 ms after the last one (issue 38)",
        CoreFault::DebuggerThenHang {
            after_trigger_us: 2_000_000,
        },
        false,
        true,
    );
    vec![
        frozen,
        parted,
        placeholder,
        host_run,
        held,
        low_zero,
        debugger,
    ]
}
