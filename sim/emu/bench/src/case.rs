//! The emulated board's test cases: the rig the board image is put in (plant constants, cord,
//! seed), what the operator does, what goes wrong, and when the emulation stops. The harness
//! (`sim/emu/harness.mjs`, through the WebAssembly build) and the host test (`tests/emu_rp2040.rs`,
//! which runs host-sim on the same case for comparison) both take them from here, so they
//! cannot drift apart.

use capstan_physics::Model;
use capstan_plant::{AdcConfig, CordSetup, Injection, InjectionKind, PlantConfig, THESIS_MU};
use capstan_rig::hal::Channel;
use capstan_rig::safety::SafetyLimits;
use capstan_rig::{Calibration, Protocol};

/// When the operator presses the start button: 0.5 s after the rig started sampling (the
/// plant's time zero, see [`crate::bench`]). Late enough that the servo's first frames after
/// boot have settled before the tare, as they have on a rig whose operator presses a while
/// after power-up.
pub const PRESS_AT_US: u64 = 500_000;
/// How long the operator holds the start button, µs.
pub const PRESS_US: u64 = 200_000;
/// When the fault cases' faults strike: 11 s after the trigger's rising edge, 0.5 s into step 1
/// (the first tension level, servo at 120°, the cord-break checks armed).
pub const FAULT_AFTER_TRIGGER_US: u64 = 11_000_000;
/// The panic case's instant: 0.4 ms after [`FAULT_AFTER_TRIGGER_US`], between two samples.
pub const PANIC_AFTER_TRIGGER_US: u64 = FAULT_AFTER_TRIGGER_US + 400;

/// The board image's protocol, calibration and safety limits: what `firmware/board/src/board.rs`
/// compiles in (`protocol()`, `calibration()`, `safety_limits()`). That file builds for the
/// RP2040 only, so it is mirrored here; the test checks the decoded run against host-sim with
/// these values (same pair times, same end), which fails if the two ever differ.
pub fn board_protocol() -> Protocol {
    Protocol {
        capstan_diameter_mm: 0.0,
        wrap_deg: 0.0,
        ..Protocol::default()
    }
}

/// See [`board_protocol`]: the built-in calibration, whose sensitivities are the placeholder
/// nobody measured (no run uses them: issue 38).
pub fn board_calibration() -> Calibration {
    Calibration::default()
}

/// The board's calibration after [`TYPED`]: the same values, typed by a person (what every
/// case that runs has, and what host-sim runs with to compare).
pub fn typed_calibration() -> Calibration {
    board_calibration().typed()
}

/// The host's lines that type both sensitivities (the built-in ones, 0.015 N/count) before
/// the operator's press: the board image has no flash in the emulator, so every case that runs
/// says them (a board as flashed never runs on its placeholder).
pub const TYPED: [HostLine; 2] = [
    HostLine::at_ms(100, "set t1_n_per_count 0.015"),
    HostLine::at_ms(150, "set t2_n_per_count 0.015"),
];

/// See [`board_protocol`].
pub fn board_limits() -> SafetyLimits {
    SafetyLimits::default()
}

/// A fault of the chip itself, which the harness brings about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CoreFault {
    /// From this instant (µs after the trigger's rising edge) the ADC completes no conversion:
    /// the firmware's blocking conversion (embassy-rp's `blocking_read`, which spins on the
    /// ADC's READY bit) never returns, so the sampling loop hangs with interrupts still running
    /// and nothing feeds the watchdog.
    Hang {
        /// When, µs after the trigger's rising edge.
        after_trigger_us: u64,
    },
    /// At this instant the core, in thread mode, is diverted into the image's own
    /// `core::panicking::panic` with a message and a source location the harness writes into
    /// unused RAM: what a `panic!("...")` in the rig's task at that instant would execute.
    Panic {
        /// When, µs after the trigger's rising edge.
        after_trigger_us: u64,
    },
    /// At this instant the stack pointer of the core, in thread mode, is put 16 bytes above
    /// the bottom of SRAM, where the image's stack ends (`memory.x`): the next pushes run off
    /// it, as a stack that overflowed would.
    StackOverflow {
        /// When, µs after the trigger's rising edge.
        after_trigger_us: u64,
    },
    /// At this instant a debugger writes the watchdog's control: disabled, paused while the
    /// core is halted (as a probe may leave it); 5 ms later the loop hangs as in
    /// [`CoreFault::Hang`]. The firmware writes the control back at every feed, so the
    /// watchdog still resets the chip.
    DebuggerThenHang {
        /// When, µs after the trigger's rising edge.
        after_trigger_us: u64,
    },
}

/// How long after a debugger's write to the watchdog [`CoreFault::DebuggerThenHang`] hangs the
/// loop, µs.
pub const DEBUGGER_TO_HANG_US: u64 = 5_000;

impl CoreFault {
    /// When it strikes, µs after the trigger's rising edge.
    pub fn after_trigger_us(self) -> u64 {
        match self {
            CoreFault::Hang { after_trigger_us }
            | CoreFault::Panic { after_trigger_us }
            | CoreFault::StackOverflow { after_trigger_us }
            | CoreFault::DebuggerThenHang { after_trigger_us } => after_trigger_us,
        }
    }

    /// Its name in the report.
    pub fn name(self) -> &'static str {
        match self {
            CoreFault::Hang { .. } => "hang",
            CoreFault::Panic { .. } => "panic",
            CoreFault::StackOverflow { .. } => "stack_overflow",
            CoreFault::DebuggerThenHang { .. } => "debugger_then_hang",
        }
    }
}

/// When the emulation stops.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stop {
    /// At this plant time, µs.
    At(u64),
    /// This long after the trigger's rising edge, µs.
    AfterTrigger(u64),
    /// This long after the chip's first reset, µs.
    AfterReset(u64),
}

/// One emulated-board case.
#[derive(Clone, Debug)]
pub struct Case {
    /// Its name (the harness and the test select cases by it).
    pub name: &'static str,
    /// What it shows.
    pub about: &'static str,
    /// Seed of the plant (sensor zeros and noise).
    pub seed: u64,
    /// The rig's constants.
    pub plant: PlantConfig,
    /// The cord, and when the operator presses the start button.
    pub cord: CordSetup,
    /// Physical faults the plant suffers (after the trigger, as host-sim injects them).
    pub injections: Vec<Injection>,
    /// A fault of the chip.
    pub core_fault: Option<CoreFault>,
    /// When the emulation ends.
    pub stop: Stop,
    /// A debug probe is attached (`probe-rs run`): it halts the core on HardFault entry, as
    /// probe-rs does to print the backtrace, and the watchdog, not paused by the halt, resets
    /// the chip.
    pub probe_attached: bool,
    /// In the fixed slice plain `cargo test` runs (the rest only with `CAPSTAN_EMU=full`).
    pub quick: bool,
    /// Command lines the host sends over RTT (the harness writes them into down channel 0).
    pub commands: Vec<HostLine>,
    /// The bench keeps every sample's two ADC codes for the report (`Report::samples`).
    pub keep_samples: bool,
    /// Weights hung on the T1 and T2 sensors from the start, N (a load during the tare).
    pub hung_n: [f64; 2],
    /// The operator holds the button down from power-up for this long, emulator µs (0: no).
    pub held_from_power_up_us: u64,
    /// The button held down (or its lead shorted) from this emulator µs for this long.
    pub held_us: Option<(u64, u64)>,
    /// A healthy run whose log must pass `capstan log --strict`.
    pub strict_log: bool,
    /// After the chip's first reset, the operator presses the button this long after it, µs,
    /// for [`PRESS_US`] (to acknowledge the fault the reset latched).
    pub press_after_reset_us: Option<u64>,
    /// The host stops reading the log over this window, emulator µs since power-up, and sets
    /// RTT up channel 0 to block when full at its start (as `probe-rs run` may): the buffer
    /// fills.
    pub rtt_stall_us: Option<(u64, u64)>,
}

/// A command line from the host, as `capstan rig` sends it through a debug probe.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HostLine {
    /// When it is due: emulated µs since power-up (the emulator's time zero, not the plant's,
    /// which starts when the firmware starts sampling, about 0.6 ms later).
    pub at_us: u64,
    /// The line, without its `\n`.
    pub line: &'static str,
}

impl HostLine {
    /// `line`, due 0.5 ms after `ms` after power-up (between two samples whatever the boot's
    /// offset of the sample grid).
    pub const fn between(ms: u64, line: &'static str) -> HostLine {
        HostLine {
            at_us: ms * 1_000 + 500,
            line,
        }
    }

    /// `line`, due `ms` after power-up.
    pub const fn at_ms(ms: u64, line: &'static str) -> HostLine {
        HostLine {
            at_us: ms * 1_000,
            line,
        }
    }
}

impl Case {
    /// A case of the thesis's cord, pressed at [`PRESS_AT_US`], with nothing going wrong,
    /// stopping at `stop`, in the full set only.
    pub(crate) fn base(name: &'static str, about: &'static str, seed: u64, stop: Stop) -> Case {
        Case {
            name,
            about,
            seed,
            plant: PlantConfig::default(),
            cord: cord(),
            injections: Vec::new(),
            core_fault: None,
            stop,
            probe_attached: false,
            quick: false,
            commands: TYPED.to_vec(),
            keep_samples: false,
            hung_n: [0.0; 2],
            held_from_power_up_us: 0,
            held_us: None,
            strict_log: false,
            press_after_reset_us: None,
            rtt_stall_us: None,
        }
    }

    /// Capstan diameter of the case's plant, mm.
    pub fn diameter_mm(&self) -> f64 {
        self.plant.capstan_diameter_mm
    }

    /// The fault the firmware must report, if the case has one of the plant's.
    pub fn expected_fault(&self) -> Option<capstan_rig::FaultKind> {
        self.injections.first().map(|i| i.kind.fault())
    }
}

/// The thesis's 360° cord on the 12.7 mm capstan, Euler-Eytelwein at mu 0.115, pressed at
/// [`PRESS_AT_US`].
pub(crate) fn cord() -> CordSetup {
    CordSetup {
        press_at_us: Some(PRESS_AT_US),
        press_us: PRESS_US,
        ..CordSetup::new(360.0, Model::euler_eytelwein(THESIS_MU))
    }
}

fn fault_case(name: &'static str, about: &'static str, kind: InjectionKind, quick: bool) -> Case {
    Case {
        injections: vec![Injection {
            kind,
            cord: 0,
            after_trigger_us: FAULT_AFTER_TRIGGER_US,
        }],
        quick,
        ..Case::base(
            name,
            about,
            11,
            Stop::AfterTrigger(FAULT_AFTER_TRIGGER_US + 200_000),
        )
    }
}

pub(crate) fn core_case(
    name: &'static str,
    about: &'static str,
    fault: CoreFault,
    probe_attached: bool,
    quick: bool,
) -> Case {
    Case {
        core_fault: Some(fault),
        probe_attached,
        quick,
        // Long enough after the reset for the boot, its reports, and a person who
        // acknowledges the latched reset a second later.
        press_after_reset_us: Some(1_000_000),
        ..Case::base(name, about, 12, Stop::AfterReset(1_500_000))
    }
}

/// When the setup case's host sends what (emulated time since power-up): setup mode, a zero with
/// the servo at rest (its 500 ms measurement ends before the next line), the servo to 95° (1 s
/// at setup mode's 30°/s), a jog of -10° (85°, 0.33 s), a setting, the settings shown, and out
/// of setup mode, from where the servo homes to rest (125°) at 10°/s: 4 s, before the case's
/// end at 8 s.
pub const SETUP_COMMANDS: [HostLine; 7] = [
    HostLine::at_ms(300, "setup"),
    HostLine::at_ms(500, "zero"),
    HostLine::at_ms(1_200, "servo 95"),
    HostLine::at_ms(2_400, "jog -10"),
    HostLine::at_ms(2_900, "set dwell_ms 8000"),
    HostLine::at_ms(3_000, "show"),
    HostLine::at_ms(3_200, "leave"),
];

/// Then, while the servo homes, the host sends this many `show` lines at once, at
/// [`BURST_AT_MS`]: 150 bytes, more than RTT down channel 0's 128-byte buffer holds, so the
/// harness writes what fits and the rest at its next polls as the board reads (a line per
/// sample), wrapping around the buffer, as a probe's RTT host would.
pub const SHOW_BURST: usize = 30;
/// When the burst is due, ms after power-up.
pub const BURST_AT_MS: u64 = 5_000;

/// The setup case: no button press, the host's [`SETUP_COMMANDS`] and the burst.
fn setup_case() -> Case {
    let burst = std::iter::repeat_n(HostLine::at_ms(BURST_AT_MS, "show"), SHOW_BURST);
    Case {
        cord: CordSetup {
            press_at_us: None,
            ..cord()
        },
        quick: true,
        commands: SETUP_COMMANDS.iter().copied().chain(burst).collect(),
        keep_samples: true,
        ..Case::base(
            "setup",
            "setup mode by host command lines over RTT: zero, servo, jog, set, show, leave; \
             the servo homes to rest; compared with host-sim's session",
            21,
            Stop::At(8_000_000),
        )
    }
}

/// When the RTT case's host stops reading, and for how long, emulator µs since power-up: from
/// 1 s before its fault (the press at 0.5 s of plant time, ~0.6 ms after power-up, the
/// trigger 1.01 s later) to 1 s after it; 2 s of records (~5 KB) for a 1 KiB buffer.
pub const RTT_STALL_US: (u64, u64) = (
    PRESS_AT_US + 1_010_000 + FAULT_AFTER_TRIGGER_US - 1_000_000,
    PRESS_AT_US + 1_010_000 + FAULT_AFTER_TRIGGER_US + 1_000_000,
);

/// The force-control case's host (issue 43): the rig's wrap and diameter, the thesis fit's law
/// as `capstan rig load-model` sends it (its values at the 12.7 mm capstan and 10 V), a short
/// protocol (4 s dwells, targets 5 and 10 N), force mode, and a run, from the host. Each line
/// ≤ 64 bytes, 100 ms apart (one is taken per sample; the board answers each), each written
/// half a millisecond past the ms, between two samples (the test maps lines to samples).
pub const FORCE_COMMANDS: [HostLine; 12] = [
    HostLine::between(300, "set wrap_deg 720"),
    HostLine::between(400, "set diameter_mm 12.7"),
    HostLine::between(500, "set model_mu 0.14527485"),
    HostLine::between(600, "set model_heat_per_n 0.008294685"),
    HostLine::between(700, "set model_t2_offset_n -0.8234439"),
    HostLine::between(800, "set dwell_ms 4000"),
    HostLine::between(900, "set window_before_ms 500"),
    HostLine::between(1_000, "set force_level3_n 0"),
    HostLine::between(1_100, "set force_level4_n 0"),
    HostLine::between(1_200, "set mode force"),
    HostLine::between(1_300, "show"),
    HostLine::between(1_400, "run"),
];

/// During the force run (its first segment, ~5.5 s after the trigger) the host sends this
/// many `show` lines at once: the board takes one a sample, so one of them comes with a
/// sample of the force controller (every tenth, the run's busiest): the loop budget's worst
/// case, a settings record on top of the controller (issue 43's settings record made a
/// sample late; its encoding now waits for the next sample).
pub const FORCE_SHOW_BURST: usize = 12;
/// When that burst is due, ms after power-up.
pub const FORCE_SHOW_AT_MS: u64 = 8_000;

/// When the operator presses in the force case, plant µs: after the host's `run` armed the
/// board (~1.4 s after power-up; the host never starts the drive, issue 38).
pub const FORCE_PRESS_AT_US: u64 = 1_600_000;

/// When the force run ends, plant µs: from the press, pre-trigger 1 s + trigger 0.5 s + 3
/// dwells of 4 s.
pub const FORCE_END_US: u64 = FORCE_PRESS_AT_US + 1_000_000 + 500_000 + 3 * 4_000_000;

/// The thesis fit (`capstan analyze` on the bundled data; host-sim's `force::thesis_fit`, which
/// the test checks it against): the cord of the force case.
pub fn thesis_fit() -> Model {
    let mut m = Model::euler_eytelwein(0.145_274_841);
    m.law.heat_per_ns = 0.033_178_741;
    m.law.heat_tau_s = 0.25;
    m.sensors.t2_offset_n = -0.823_443_891;
    m
}

fn force_case() -> Case {
    let mut plant = PlantConfig::default();
    plant.servo.dynamics = capstan_plant::ServoDynamics::HS_322HD;
    Case {
        plant,
        cord: CordSetup {
            press_at_us: Some(FORCE_PRESS_AT_US),
            press_us: PRESS_US,
            ..CordSetup::new(720.0, thesis_fit())
        },
        quick: true,
        commands: TYPED
            .into_iter()
            .chain(FORCE_COMMANDS)
            .chain(std::iter::repeat_n(
                HostLine::between(FORCE_SHOW_AT_MS, "show"),
                FORCE_SHOW_BURST,
            ))
            .collect(),
        keep_samples: true,
        ..Case::base(
            "force",
            "force control from the host (issue 43): both sensitivities typed, the fitted law \
             loaded by set lines, force mode, `run` (armed) and a press at the rig, a run holding \
             T2 at 5 then 10 N on a 720° cord with the servo's dead band, a burst of `show` \
             during it; compared with host-sim's session",
            22,
            Stop::At(FORCE_END_US + 300_000),
        )
    }
}

/// The cases of issue 24's negative tests (where the pins matter).
fn guard_cases() -> Vec<Case> {
    vec![
        Case {
            hung_n: [8.0, 8.0],
            quick: true,
            ..Case::base(
                "tare_under_load",
                "8 N hangs on both sensors during the tare: the run is refused before the \
                 drive is on (issue 24)",
                13,
                Stop::At(PRESS_AT_US + 2_000_000),
            )
        },
        Case {
            held_from_power_up_us: 5_000_000,
            cord: CordSetup {
                press_at_us: Some(6_000_000),
                ..cord()
            },
            quick: true,
            ..Case::base(
                "held_button",
                "the button held from power-up for 5 s starts nothing; pressed after a \
                 release, a run starts (issue 24)",
                14,
                Stop::At(8_000_000),
            )
        },
        core_case(
            "stack_overflow",
            "the stack runs off the bottom of SRAM during step 1: the core locks up, the \
             watchdog resets the chip within 10 ms (issue 24)",
            CoreFault::StackOverflow {
                after_trigger_us: PANIC_AFTER_TRIGGER_US,
            },
            false,
            true,
        ),
        Case {
            rtt_stall_us: Some(RTT_STALL_US),
            // Past the stall's end: the host reads again, and a `show` after it gives a record
            // whose sequence number shows the gap (the idle rig logs nothing by itself).
            stop: Stop::AfterTrigger(FAULT_AFTER_TRIGGER_US + 1_500_000),
            commands: TYPED
                .into_iter()
                .chain([HostLine {
                    at_us: RTT_STALL_US.1 + 200_000,
                    line: "show",
                }])
                .collect(),
            ..fault_case(
                "rtt_full",
                "the host stops reading the log (its buffer set to block) for 2 s, and the \
                 cord snags meanwhile: the loop never blocks, the fault is safe within 20 ms \
                 (issue 24)",
                InjectionKind::OverForce,
                false,
            )
        },
    ]
}

/// The core, guard and force cases, the full protocol run first (the hazards are
/// [`crate::hazards`]; every case: [`crate::cases`]).
pub fn core_set() -> Vec<Case> {
    let protocol = board_protocol();
    // The press is debounced for 10 samples; the run ends `end_ms` after that.
    let run_end_us = PRESS_AT_US + 10_000 + protocol.end_ms() as u64 * 1_000;
    let mut run = Case::base(
        "run",
        "a whole protocol run through the button, compared with host-sim, with the RP2040's \
         ADC offset and noise: no fault (issue 38)",
        1,
        Stop::At(run_end_us + 300_000),
    );
    run.plant.adc = AdcConfig::RP2040;
    run.strict_log = true;
    let mut all = vec![run];
    all.extend([
        fault_case(
            "abort",
            "the operator presses the button again during step 1",
            InjectionKind::Abort,
            true,
        ),
        fault_case(
            "over_force",
            "the cord snags: T2 jumps to 50 N during step 1",
            InjectionKind::OverForce,
            false,
        ),
        fault_case(
            "cord_break",
            "the cord parts during step 1",
            InjectionKind::CordBreak,
            false,
        ),
        fault_case(
            "sensor_unplugged",
            "the T2 sensor's connector comes out during step 1",
            InjectionKind::SensorUnplugged(Channel::T2),
            false,
        ),
        core_case(
            "hang",
            "the sampling loop hangs during step 1: the watchdog resets the chip within \
             10 ms; the servo gets no pulse (the cord back-drives the horn) until a person \
             presses the button, then the rest pulse (issue 24)",
            CoreFault::Hang {
                after_trigger_us: FAULT_AFTER_TRIGGER_US,
            },
            false,
            true,
        ),
        core_case(
            "panic",
            "the firmware panics during step 1 (issue 12)",
            CoreFault::Panic {
                after_trigger_us: PANIC_AFTER_TRIGGER_US,
            },
            false,
            true,
        ),
        core_case(
            "panic_probe",
            "the firmware panics during step 1 with probe-rs attached: the core halts on the \
             HardFault, the watchdog resets the chip",
            CoreFault::Panic {
                after_trigger_us: PANIC_AFTER_TRIGGER_US,
            },
            true,
            false,
        ),
        setup_case(),
    ]);
    all.extend(guard_cases());
    all.push(force_case());
    all
}
