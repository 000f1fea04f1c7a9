//! What the bench saw, as the JSON the harness writes next to the stream (`emulation.json`'s
//! `bench`): the pins' waveforms, the plant's records, the resets, the loop budget.

use crate::meter::Segment;
use serde::Serialize;

/// Cycles per 1 ms sample at 125 MHz.
pub const CYCLES_PER_SAMPLE: u32 = 125_000;

/// Why the chip was reset (the watchdog's REASON register).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ResetReason {
    /// The watchdog timed out.
    Timeout,
    /// Software triggered the watchdog (the HardFault handler does).
    Forced,
}

/// A chip reset.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Reset {
    /// When, ns.
    pub t_ns: f64,
    /// Why.
    pub reason: ResetReason,
}

/// Busy cycles per wake of the core: statistics.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Stats {
    /// Busy stretches (one per sample: the timer interrupt wakes the core, the sample runs,
    /// the core sleeps).
    pub bursts: u64,
    /// Mean cycles.
    pub mean: f64,
    /// Median.
    pub p50: u32,
    /// 99th percentile.
    pub p99: u32,
    /// 99.9th percentile.
    pub p999: u32,
    /// Largest.
    pub max: u32,
    /// When the largest began, ns.
    pub max_at_ns: f64,
    /// Largest as a fraction of the 125 000 cycles of a 1 ms sample.
    pub max_fraction: f64,
}

impl Stats {
    pub(crate) fn of(bursts: &mut [(f64, u32)]) -> Stats {
        if bursts.is_empty() {
            return Stats::default();
        }
        let n = bursts.len();
        let sum: u64 = bursts.iter().map(|b| b.1 as u64).sum();
        let (max_at_ns, max) = bursts
            .iter()
            .copied()
            .max_by_key(|b| b.1)
            .expect("not empty");
        bursts.sort_by_key(|b| b.1);
        let q = |f: f64| bursts[((n as f64 - 1.0) * f).round() as usize].1;
        Stats {
            bursts: n as u64,
            mean: sum as f64 / n as f64,
            p50: q(0.5),
            p99: q(0.99),
            p999: q(0.999),
            max,
            max_at_ns,
            max_fraction: max as f64 / CYCLES_PER_SAMPLE as f64,
        }
    }
}

/// The loop budget: busy cycles per sample against the 125 000 a 1 ms sample has at 125 MHz.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Budget {
    /// Cycles available per sample.
    pub available_per_sample: u32,
    /// During runs: from the press (after its 10 ms debounce) to the amplifier's stop or a
    /// reset.
    pub run: Stats,
    /// The rest (boot, idle, after the run).
    pub idle: Stats,
    /// Both, the boot's included, up to the case's chip fault (a hung loop, the panic path
    /// or a lockup is not a sample): what the loop budget's bound holds to.
    pub working: Stats,
    /// The five busiest stretches of the runs: (start, ns since the trigger's rising edge,
    /// cycles).
    pub run_worst: Vec<(f64, u32)>,
    /// Busy cycles in all.
    pub cycles: u64,
}

/// What became of a plant injection.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct InjectionOut {
    /// The fault's name (`cord_break`, ...).
    pub kind: &'static str,
    /// When it took effect, emulator ns.
    pub at_ns: Option<f64>,
    /// When the plant saw the rig command the safe state (servo at rest, amplifier 0) after
    /// it, emulator ns (at the plant's µs resolution).
    pub plant_safe_at_ns: Option<f64>,
}

/// The chip fault of the case.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CoreFaultOut {
    /// `hang` or `panic`.
    pub kind: &'static str,
    /// When it was due, ns.
    pub due_ns: Option<f64>,
    /// When it struck: the first conversion that never completed, or the instant the harness
    /// diverted the core, ns.
    pub struck_ns: Option<f64>,
}

/// A servo command as the plant received it, in emulator ns.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PlantServoEvent {
    /// When the plant received it, ns.
    pub t_ns: f64,
    /// The pulse the plant made of it, µs.
    pub pulse_us: f32,
    /// The horn angle that pulse holds, deg.
    pub angle_deg: f32,
}

/// Everything the bench saw: the JSON the harness writes next to the stream.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Report {
    /// The case.
    pub case: String,
    /// The plant's time zero, emulator ns.
    pub origin_ns: Option<f64>,
    /// When the emulation ended, ns.
    pub end_ns: f64,
    /// The servo signal (GP16), one segment per change of waveform.
    pub servo: Vec<Segment>,
    /// Pulses seen on GP16.
    pub servo_pulses: u64,
    /// PWM high times that were not a whole number of the PWM's counter ticks (none expected).
    pub pwm_off_grid: u64,
    /// The amplifier control PWM (GP18), one segment per change of waveform.
    pub amp: Vec<Segment>,
    /// Periods seen on GP18.
    pub amp_periods: u64,
    /// Trigger (GP20) edges: (ns, level).
    pub trigger: Vec<(f64, bool)>,
    /// LED (GP25) edges.
    pub led_edges: u64,
    /// The operator's button (GP21) edges: (ns, pressed).
    pub button: Vec<(f64, bool)>,
    /// Conversions where the plant's own button model disagreed with the pin (none
    /// expected).
    pub button_mismatches: u64,
    /// Conversions served.
    pub conversions: u64,
    /// Conversions where divider + ADC gave another code than the plant's own ADC would
    /// have (none expected: see `front_end`).
    pub rounding_mismatches: u64,
    /// The first of them: (ns, the plant's reading in counts).
    pub mismatch_examples: Vec<(f64, f64)>,
    /// T1 conversions' offset from the plant's whole milliseconds until the first run ended
    /// (the next `run_once` starts a ticker of its own, on another phase): (min, max), ns.
    pub t1_phase_ns: Option<(f64, f64)>,
    /// The first ten of those conversions more than 2 µs off: (ns, offset ns).
    pub late_t1: Vec<(f64, f64)>,
    /// The trigger's first rising edge (the logger's time zero), ns.
    pub trigger_rise_ns: Option<f64>,
    /// The plant's faults.
    pub injections: Vec<InjectionOut>,
    /// The chip fault.
    pub core_fault: Option<CoreFaultOut>,
    /// Chip resets.
    pub resets: Vec<Reset>,
    /// The loop budget.
    pub budget: Budget,
    /// Servo commands as the plant received them.
    pub plant_servo: Vec<PlantServoEvent>,
    /// Every sample's codes, if the case keeps them (`Case::keep_samples`): (when the T1
    /// conversion started, ns; the T1 code; the T2 code).
    pub samples: Vec<(f64, u16, u16)>,
    /// From the chip's first reset on, at each T1 conversion: (ns, the horn's angle, deg, the
    /// true T1, N, the servo pulse the plant is given, µs (0: none), the drive's voltage, V).
    pub after_reset: Vec<(f64, f64, f64, f64, f64)>,
    /// The drive's voltage at the first reset, V.
    pub drive_v_at_reset: Option<f64>,
}
