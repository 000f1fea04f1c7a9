//! The rig's configuration on the Raspberry Pi Pico: pins, PWM timing, watchdog, protocol and
//! built-in protocol and calibration (the defaults until settings are stored from the host).
//! Compiled into the RP2040 binary only (`main.rs` declares it for `target_os = "none"`); the
//! rig core (`lib.rs`) never sees it. Calibration and protocol are set at the bench without a
//! rebuild (`capstan rig`, README "Setting up the rig"); what needs one is in this file. The wiring itself is in
//! the user guide (docs/book/src/hardware.md, "Firmware on a Raspberry Pi Pico").
//!
//! The pin map is the wire schema's (`capstan_wire::pins`, with its table of signals, GPIOs,
//! peripherals and Pico header pins; every signal is 3.3 V logic), which the emulated board's
//! harness and bench use too. [`Pins`] takes those pins as embassy-rp's typed peripherals, and
//! `main` checks at boot that they are the schema's.
//!
//! GP23 is the Pico's own regulator "power save" pin, not on the header: driving it high puts
//! the RT6150 buck-boost into PWM mode, which the Pico datasheet recommends for ADC work (much
//! less ripple on 3V3 and ADC_VREF at light load, at some efficiency cost).
//!
//! The two PWM outputs sit on different slices (0 and 1) because both channels of a slice share
//! one counter, so one frequency: the servo's 50 Hz and the amplifier's 30.5 kHz could not
//! share a slice. GP17 (slice 0 B) and GP19 (slice 1 B) must therefore not be used for another
//! PWM of a different frequency. GP25's slice (4) and GP26/GP27's slice (5) are not used as PWM.
//! GP24 and GP29 are wired inside the Pico (VBUS sense, VSYS/3) and GP0/GP1 are the usual
//! UART0 console: all avoided. (On a Pico W, GP23/GP24/GP25/GP29 belong to the wireless chip:
//! this binary is for the plain Pico.)
//!
//! To move a signal, change its GPIO in `capstan_wire::pins::PINS` and its line in [`Pins`]
//! (type and `take`); for a PWM pin, the slice must be the one that pin belongs to (the
//! compiler checks that). `main` checks at boot that [`Pins`] are the schema's pins, whose
//! registers the panic path writes directly ([`SERVO_GPIO`], [`SERVO_SLICE`], ...).

use capstan_rig::safety::SafetyLimits;
use capstan_rig::{Calibration, Protocol};
use capstan_wire::pins::{pwm_slice, PINS};
use core::ops::Range;
use embassy_rp::peripherals::{
    ADC, FLASH, PIN_16, PIN_18, PIN_20, PIN_21, PIN_23, PIN_25, PIN_26, PIN_27, PWM_SLICE0,
    PWM_SLICE1, WATCHDOG,
};
use embassy_rp::{Peri, Peripherals};
use embassy_time::Duration;

/// The peripherals the rig uses, taken out of embassy-rp's singletons in one place.
pub struct Pins {
    /// What the board needs before the rig runs.
    pub board: BoardPins,
    /// What the rig's I/O is made of.
    pub rig: RigPins,
}

/// The peripherals of the board's own set-up: power, watchdog, flash.
pub struct BoardPins {
    /// The hardware watchdog.
    pub watchdog: Peri<'static, WATCHDOG>,
    /// The Pico's SMPS power-save pin (driven high: PWM mode, quieter ADC reference).
    pub smps_mode: Peri<'static, PIN_23>,
    /// The QSPI flash (the settings store).
    pub flash: Peri<'static, FLASH>,
}

/// The peripherals of the rig's inputs and outputs.
pub struct RigPins {
    /// PWM slice of the servo signal.
    pub servo_slice: Peri<'static, PWM_SLICE0>,
    /// Servo signal (slice 0, channel A).
    pub servo: Peri<'static, PIN_16>,
    /// PWM slice of the amplifier's control voltage.
    pub amp_slice: Peri<'static, PWM_SLICE1>,
    /// Amplifier control PWM (slice 1, channel A) into the RC filter.
    pub amp: Peri<'static, PIN_18>,
    /// Logger trigger line.
    pub trigger: Peri<'static, PIN_20>,
    /// Start/abort button, active low.
    pub button: Peri<'static, PIN_21>,
    /// Onboard LED of the Pico (not the Pico W, whose LED hangs off the wireless chip).
    pub led: Peri<'static, PIN_25>,
    /// The ADC block.
    pub adc: Peri<'static, ADC>,
    /// T1 (servo side) force sensor, ADC0.
    pub t1: Peri<'static, PIN_26>,
    /// T2 (fixed side) force sensor, ADC1.
    pub t2: Peri<'static, PIN_27>,
}

impl Pins {
    /// Take the rig's peripherals.
    pub fn take(p: Peripherals) -> Self {
        Pins {
            board: BoardPins {
                watchdog: p.WATCHDOG,
                smps_mode: p.PIN_23,
                flash: p.FLASH,
            },
            rig: RigPins {
                servo_slice: p.PWM_SLICE0,
                servo: p.PIN_16,
                amp_slice: p.PWM_SLICE1,
                amp: p.PIN_18,
                trigger: p.PIN_20,
                button: p.PIN_21,
                led: p.PIN_25,
                adc: p.ADC,
                t1: p.PIN_26,
                t2: p.PIN_27,
            },
        }
    }
}

/// GPIO of the servo signal, for the panic path's register writes (the pin of [`RigPins::servo`]).
pub const SERVO_GPIO: usize = PINS.servo as usize;
/// PWM slice of the servo signal (of [`RigPins::servo_slice`]).
pub const SERVO_SLICE: usize = pwm_slice(PINS.servo) as usize;
/// GPIO of the amplifier control PWM (of [`RigPins::amp`]).
pub const AMP_GPIO: usize = PINS.amp as usize;
/// PWM slice of the amplifier control (of [`RigPins::amp_slice`]).
pub const AMP_SLICE: usize = pwm_slice(PINS.amp) as usize;
/// GPIO of the logger trigger (of [`RigPins::trigger`]).
pub const TRIGGER_GPIO: usize = PINS.trigger as usize;

impl Pins {
    /// True if these are the schema's pins (`capstan_wire::pins::PINS`), as the panic path, the
    /// emulated board and the hardware chapter take them.
    pub fn are_the_schemas(&self) -> bool {
        use embassy_rp::gpio::Pin;
        use embassy_rp::pwm::Slice;
        let r = &self.rig;
        [
            (r.servo.pin(), PINS.servo),
            (r.amp.pin(), PINS.amp),
            (r.trigger.pin(), PINS.trigger),
            (r.button.pin(), PINS.button),
            (r.led.pin(), PINS.led),
            (r.t1.pin(), PINS.t1),
            (r.t2.pin(), PINS.t2),
            (self.board.smps_mode.pin(), PINS.smps_mode),
        ]
        .iter()
        .all(|(a, b)| a == b)
            && r.servo_slice.number() == SERVO_SLICE
            && r.amp_slice.number() == AMP_SLICE
    }
}

/// clk_sys that the PWM settings below assume: embassy-rp's default clocks (12 MHz crystal,
/// PLL to 125 MHz). `main` checks it at boot.
pub const CLK_SYS_HZ: u32 = 125_000_000;

/// Servo PWM clock divider: 125 MHz / 40 = 3.125 MHz, 0.32 µs per count.
pub const SERVO_PWM_DIVIDER: u8 = 40;
/// Servo PWM top: (62 499 + 1) counts × 0.32 µs = 20 ms, a 50 Hz frame.
pub const SERVO_PWM_TOP: u16 = 62_499;
/// The servo PWM's full scale, counts: the whole 20 ms frame, `top + 1` (the output is high for
/// `compare` counts of every `top + 1`). The rig core's duty is a fraction of
/// `max_duty_cycle()`, which the board's PWM driver (`main.rs`, `PeriodPwm`) reports as this,
/// so a duty count is 0.32 µs of pulse.
pub const SERVO_FULL_SCALE: u16 = SERVO_PWM_TOP + 1;

/// Amplifier PWM clock divider: the full 125 MHz.
pub const AMP_PWM_DIVIDER: u8 = 1;
/// Amplifier PWM top: 4096 counts per period → 125 MHz / 4096 = 30.5 kHz, 12-bit resolution
/// (0.8 mV steps of the 3.3 V swing). The RC filter is sized for this frequency (see docs/book/src/hardware.md).
/// The duty's full scale is the period, 4096 counts (as for the servo, [`SERVO_FULL_SCALE`]).
pub const AMP_PWM_TOP: u16 = 4_095;

/// Hardware watchdog timeout while the loop samples (idle, setup mode and runs alike). The
/// runner feeds it every sample (1 ms; the busiest sample takes ~0.5 ms), so only a loop that
/// has stopped — a hang, a conversion that never completes, a write that blocks, a lockup
/// (a stack overflow: `memory.x`), or a core halted by the debugger — lets it run out; the chip
/// then resets within this of the last feed, and every output pin falls back to an input
/// (servo pulses stop, amplifier control and trigger are pulled low by their resistors), and
/// the next boot latches the reset as a fault (`capstan_rig::reset`). It is widened only around a
/// flash write (`capstan_rig::runner::STORE_WATCHDOG_MS`), which the rig asks for only with the
/// servo at rest and the amplifier off. A panic or HardFault does not wait for it: its handler
/// drives the outputs safe first (`board_safe.rs`). The software supervisor's 10 ms sample-gap
/// fault catches a merely slow loop.
pub const WATCHDOG_TIMEOUT: Duration =
    Duration::from_millis(capstan_rig::runner::WATCHDOG_MS as u64);

/// Does the watchdog pause while a debugger halts the core? Not on the rig (`false`): a core
/// halted by the probe — probe-rs stopping it on a HardFault, or a breakpoint — is reset within
/// [`WATCHDOG_TIMEOUT`], with every output pin. (The RP2040's reset value pauses it: with a
/// probe attached a halted core would then leave the amplifier at its control voltage and the
/// servo pulling, for as long as it stays halted.) Set `true` only to debug with breakpoints
/// on a rig whose drive motor and servo are unpowered.
pub const WATCHDOG_PAUSES_WHILE_HALTED: bool = false;

/// Size of the Pico's flash chip (W25Q16JV: 2 MiB).
pub const FLASH_BYTES: usize = 2 * 1024 * 1024;

/// Where the settings store lives: the top four 4 KiB sectors of the flash, as offsets from its
/// start (memory.x keeps the program below them). `sequential-storage` needs at least two
/// sectors; four spread the wear (a save, settings and generation, is ~130 bytes: ~30 saves fill
/// a sector, and the W25Q16 endures 100 000 erases of each).
pub const SETTINGS_FLASH: Range<u32> = (FLASH_BYTES as u32 - 16 * 1024)..FLASH_BYTES as u32;

/// RTT buffer of the host's command lines, bytes (a line is at most 64).
pub const COMMAND_BUFFER_BYTES: usize = 128;

/// RTT buffer of the defmt log, bytes (~0.3 s of a run's records at ~3 KB/s).
pub const LOG_BUFFER_BYTES: usize = 1024;

/// The built-in test protocol: the thesis's protocol (`Protocol::default()`), used until
/// settings are stored from the host (`capstan rig set ...` then `capstan rig store`: README,
/// "Setting up the rig") and again after `capstan rig defaults`.
///
/// The capstan diameter and wrap angle are metadata only (they go into every `run_start`
/// record so the log says what was on the rig): set them from the host (`set diameter_mm`,
/// `set wrap_deg`). 0 means "not given". The sample and raw-log rates can only be changed
/// here (a rebuild): the host cannot set them. `Rig::new` refuses an invalid protocol at boot.
pub fn protocol() -> Protocol {
    Protocol {
        capstan_diameter_mm: 0.0,
        wrap_deg: 0.0,
        ..Protocol::default()
    }
}

/// The built-in calibration, used until one is stored from the host (`capstan rig zero`,
/// `weigh`, `set ...`, `store`): the defaults (50 N sensors, zero at 400 counts, 0.015 N/count; servo
/// angles as the thesis's Arduino Servo library meant them, 544-2400 µs over 0-180°, so 125°
/// is 1833 µs and 65° 1214 µs; amplifier 3.3 V full scale, gain 4). Each run re-zeroes both
/// channels during its tare, so only the sensitivities (`n_per_count`, measured through the
/// divider in front of the ADC) need to be right. Keep the servo map unless the rig's angles
/// are meant to differ from the thesis's: the protocol's angles are Arduino commands.
pub fn calibration() -> Calibration {
    Calibration::default()
}

/// The safety supervisor's thresholds (45 N over-force, rails, cord break, 10 ms sample gap,
/// −3 N). `rail_high_counts` (3900) must stay below where a saturated sensor sits behind the
/// divider (~3990 counts for a 0-5 V sensor on the hardware chapter's 10k/18k): with other sensors or
/// another divider, measure that reading and set it lower.
pub fn safety_limits() -> SafetyLimits {
    SafetyLimits::default()
}
