//! The bench: the simulated rig wired to the emulated RP2040's pins.
//!
//! The harness (`sim/emu/harness.mjs`) calls in at every event of the emulated chip, with the
//! emulator's time in ns:
//!
//! The pins are the wire schema's (`capstan_wire::pins`), the board's own.
//!
//! * an output pin changes ([`Bench::pin`]): the servo (GP16) and amplifier (GP18) PWMs are
//!   measured edge by edge ([`crate::meter`]) and each change of waveform is handed to the
//!   plant — the servo's pulse width when a pulse ends, the amplifier's duty at the start of
//!   the period that has it (the plant's RC filter and amplifier take it from there) — and
//!   the trigger (GP20) directly;
//! * a conversion starts ([`Bench::adc`]): the plant is brought to that instant, its sensor's
//!   reading goes through the board's divider and ADC ([`crate::front_end`]), and the code is
//!   what the emulated ADC returns 2 µs later;
//! * the core goes to sleep after a busy stretch ([`Bench::burst`]): its cycles, for the loop
//!   budget;
//! * the chip is reset ([`Bench::reset`]): every pin is released.
//!
//! The bench tells the harness when to call [`Bench::wake`] ([`Bench::deadline`]): the
//! operator's button edges (GP21), the chip fault of the case, the end.
//!
//! **The plant's clock.** The plant is made at the firmware's first conversion, and its time
//! zero is put one sample period (1 ms) before it: when the firmware's sampling ticker
//! started, as host-sim's clock starts with `run_once`. A plant time is the emulator's time
//! from there, rounded to the µs. The T1 conversions then fall on whole milliseconds of plant
//! time, as host-sim's do (the T2 conversion a few µs later), the operator's press falls on
//! the same sample, and every conversion draws the same sensor noise as in host-sim.
//!
//! **PWM values for the plant.** The plant takes a PWM as a duty of a full scale, in counts,
//! as host-sim's adapters give it. The meters measure the pin in ns; the harness gives each
//! PWM pin's counter tick (its slice's divider over clk_sys: 320 ns for the servo, 8 ns for
//! the amplifier), and the bench hands the plant high time / tick of period / tick: the pin's
//! duty, in the counts the firmware wrote (the servo's 62 500-count frame is host-sim's
//! `SERVO_MAX_DUTY`, so both plants get the same pulse widths to the bit).

use crate::case::Case;
use crate::front_end::{quantise, FrontEnd};
use crate::meter::{Event, PwmMeter};
pub use crate::report::{
    Budget, CoreFaultOut, InjectionOut, PlantServoEvent, Report, Reset, ResetReason, Stats,
    CYCLES_PER_SAMPLE,
};
use capstan_plant::{Plant, PlantError};
use capstan_rig::hal::Channel;
use capstan_wire::pins::{adc_channel, PINS};

mod tally;
mod timeline;

/// GPIO of the servo signal (the wire schema's pin map, as the board's).
pub const SERVO_GPIO: u32 = PINS.servo as u32;
/// GPIO of the amplifier control PWM.
pub const AMP_GPIO: u32 = PINS.amp as u32;
/// GPIO of the logger trigger.
pub const TRIGGER_GPIO: u32 = PINS.trigger as u32;
/// GPIO of the start/abort button.
pub const BUTTON_GPIO: u32 = PINS.button as u32;
/// GPIO of the LED.
pub const LED_GPIO: u32 = PINS.led as u32;
/// ADC input of the T1 sensor (T2 is the other).
const T1_ADC: u32 = match adc_channel(PINS.t1) {
    Some(c) => c as u32,
    None => panic!("T1 is not on an ADC input"),
};

/// The pin map as the harness reads it (`job.json`'s `pins`: every pin by name, its GPIO).
pub fn pin_map_json() -> serde_json::Value {
    let pins = PINS
        .named()
        .map(|(name, gpio)| (name.to_string(), gpio.into()));
    serde_json::Value::Object(pins.into_iter().collect())
}

/// [`Bench::pin`]: the pin is driven low.
pub const LEVEL_LOW: u32 = 0;
/// [`Bench::pin`]: the pin is driven high.
pub const LEVEL_HIGH: u32 = 1;
/// [`Bench::pin`]: the pin is not driven (an input: the board's pull-downs hold it low).
pub const LEVEL_INPUT: u32 = 2;

/// [`Bench::wake`]: the button's level changed (read it with [`Bench::button_pressed`]).
pub const WAKE_BUTTON: u32 = 1;
/// [`Bench::wake`]: divert the core into the firmware's panic path now.
pub const WAKE_PANIC: u32 = 2;
/// [`Bench::wake`]: the emulation is over.
pub const WAKE_STOP: u32 = 4;
/// [`Bench::wake`]: put the core's stack pointer at the bottom of SRAM now.
pub const WAKE_STACK_OVERFLOW: u32 = 8;
/// [`Bench::wake`]: a debugger writes the watchdog's control now (disabled, paused on halt).
pub const WAKE_DEBUGGER: u32 = 16;

/// The rig around the emulated chip. See the module documentation.
pub struct Bench {
    case: Case,
    front_end: FrontEnd,
    plant: Option<Plant>,
    origin_ns: f64,
    servo: PwmMeter,
    servo_tick_ns: f64,
    servo_first_pending: bool,
    amp: PwmMeter,
    amp_tick_ns: f64,
    amp_sent: Option<(u16, u16)>,
    /// The amplifier's pin is not driven (a reset released it): its filter discharges slowly.
    amp_released: bool,
    pwm_off_grid: u64,
    releasing: bool,
    trigger_high: bool,
    trigger: Vec<(f64, bool)>,
    led_high: bool,
    led_edges: u64,
    button_pressed: bool,
    button: Vec<(f64, bool)>,
    button_mismatches: u64,
    conversions: u64,
    rounding_mismatches: u64,
    mismatch_examples: Vec<(f64, f64)>,
    t1_phase_ns: Option<(f64, f64)>,
    late_t1: Vec<(f64, f64)>,
    trigger_rise_ns: Option<f64>,
    core_fault_done: bool,
    core_fault_struck_ns: Option<f64>,
    hang: bool,
    /// The loop hangs from this instant on (the debugger case), ns.
    hang_from_ns: Option<f64>,
    resets: Vec<Reset>,
    run_since_ns: Option<f64>,
    first_run_over: bool,
    run_bursts: Vec<(f64, u32)>,
    idle_bursts: Vec<(f64, u32)>,
    cycles: u64,
    stopped: bool,
    now_ns: f64,
    samples: Vec<(f64, u16, u16)>,
    after_reset: Vec<(f64, f64, f64, f64, f64)>,
    drive_v_at_reset: Option<f64>,
}

impl Bench {
    /// A bench for `case`, before the chip boots.
    pub fn new(case: Case) -> Bench {
        Bench {
            case,
            front_end: FrontEnd::BOARD,
            plant: None,
            origin_ns: 0.0,
            // The servo frame is 20 ms, the amplifier's period 32.8 µs.
            servo: PwmMeter::new(25e6),
            servo_tick_ns: 0.0,
            servo_first_pending: false,
            amp: PwmMeter::new(100e3),
            amp_tick_ns: 0.0,
            amp_sent: None,
            amp_released: false,
            pwm_off_grid: 0,
            releasing: false,
            trigger_high: false,
            trigger: Vec::new(),
            led_high: false,
            led_edges: 0,
            button_pressed: false,
            button: Vec::new(),
            button_mismatches: 0,
            conversions: 0,
            rounding_mismatches: 0,
            mismatch_examples: Vec::new(),
            t1_phase_ns: None,
            late_t1: Vec::new(),
            trigger_rise_ns: None,
            core_fault_done: false,
            core_fault_struck_ns: None,
            hang: false,
            hang_from_ns: None,
            resets: Vec::new(),
            run_since_ns: None,
            first_run_over: false,
            run_bursts: Vec::new(),
            idle_bursts: Vec::new(),
            cycles: 0,
            stopped: false,
            now_ns: 0.0,
            samples: Vec::new(),
            after_reset: Vec::new(),
            drive_v_at_reset: None,
        }
    }

    /// The case.
    pub fn case(&self) -> &Case {
        &self.case
    }

    /// The plant, once made.
    pub fn plant(&self) -> Option<&Plant> {
        self.plant.as_ref()
    }

    fn plant_us(&self, t_ns: f64) -> u64 {
        ((t_ns - self.origin_ns) / 1_000.0).round().max(0.0) as u64
    }

    fn ns(&self, plant_us: u64) -> f64 {
        self.origin_ns + plant_us as f64 * 1_000.0
    }

    /// The plant brought to `t_ns` (never back: a change known late applies now).
    fn plant_at(&mut self, t_ns: f64) -> Option<&mut Plant> {
        let us = self.plant_us(t_ns);
        let p = self.plant.as_mut()?;
        p.advance_to(us);
        Some(p)
    }

    fn make_plant(&mut self, first_conversion_ns: f64) -> Result<(), PlantError> {
        self.origin_ns = first_conversion_ns - 1e6;
        let mut plant = Plant::new_at(self.case.plant, &[self.case.cord], self.case.seed, 0)?;
        for inj in &self.case.injections {
            plant.inject(*inj)?;
        }
        for (ch, n) in [Channel::T1, Channel::T2].into_iter().zip(self.case.hung_n) {
            if n != 0.0 {
                plant.hang(0, ch, n);
            }
        }
        self.plant = Some(plant);
        // What the pins show already (before the plant existed nothing was forwarded).
        let t = first_conversion_ns;
        if let Some(p) = self.plant_at(t) {
            p.set_trigger(0, false);
        }
        let amp = self.amp.current();
        self.apply_amp(t, amp.high_ns, amp.period_ns, amp.duty);
        if let (Some(period), false) = (self.servo.period_ns(), self.servo.current().is_static()) {
            let width = self.servo.current().high_ns;
            self.apply_servo(t, width, period);
        }
        Ok(())
    }

    /// A high time in PWM ticks, counting one off the tick grid (but for a pulse a reset cut).
    fn ticks(&mut self, ns: f64, tick_ns: f64) -> u16 {
        let x = ns / tick_ns;
        if (x - x.round()).abs() > 0.01 && !self.releasing {
            self.pwm_off_grid += 1;
        }
        x.round().clamp(0.0, u16::MAX as f64) as u16
    }

    /// A period in PWM ticks. Not checked against the grid: rp2040js recomputes a PWM's counter
    /// from the clock, rounded to a whole tick, when its divider or top is written (the panic
    /// path writes the servo slice's again), which shifts the next wrap by up to half a tick.
    fn period_ticks(ns: f64, tick_ns: f64) -> u16 {
        (ns / tick_ns).round().clamp(0.0, u16::MAX as f64) as u16
    }

    fn apply_servo(&mut self, t_ns: f64, width_ns: f64, period_ns: f64) {
        let tick = self.servo_tick_ns;
        if tick <= 0.0 {
            return;
        }
        let duty = self.ticks(width_ns, tick);
        let full_scale = Self::period_ticks(period_ns, tick);
        if let Some(p) = self.plant_at(t_ns) {
            p.set_servo_duty(0, duty, full_scale);
        }
    }

    /// The amplifier's PWM to the plant, if it changed (every period reports its shape).
    fn apply_amp(&mut self, t_ns: f64, high_ns: f64, period_ns: f64, duty: f64) {
        let (duty, full_scale) = if period_ns > 0.0 && self.amp_tick_ns > 0.0 {
            let tick = self.amp_tick_ns;
            let full_scale = Self::period_ticks(period_ns, tick);
            (self.ticks(high_ns, tick), full_scale)
        } else {
            // Static: 0 or 100 %.
            (if duty > 0.0 { 1 } else { 0 }, 1)
        };
        if self.plant.is_none() || self.amp_sent == Some((duty, full_scale)) {
            return;
        }
        self.amp_sent = Some((duty, full_scale));
        if let Some(p) = self.plant_at(t_ns) {
            p.set_amp_duty(0, duty, full_scale);
        }
    }

    fn servo_event(&mut self, e: Event) {
        match e {
            Event::PulseEnd {
                rise_ns,
                width_ns,
                period_ns: Some(period),
            } => self.apply_servo(rise_ns + width_ns, width_ns, period),
            Event::PulseEnd {
                period_ns: None, ..
            } => self.servo_first_pending = true,
            Event::Period {
                start_ns,
                high_ns,
                period_ns,
            } => {
                if self.servo_first_pending {
                    self.servo_first_pending = false;
                    self.apply_servo(start_ns + period_ns, high_ns, period_ns);
                }
            }
            // No pulses (or a pin stuck high, which is no valid pulse either): the servo is
            // unpowered and stays where it is.
            Event::Static { since_ns, .. } => {
                self.servo_first_pending = false;
                if let Some(p) = self.plant_at(since_ns) {
                    p.set_servo_duty(0, 0, 1);
                }
            }
        }
    }

    fn amp_event(&mut self, e: Event) {
        match e {
            Event::Period {
                start_ns,
                high_ns,
                period_ns,
            } => self.apply_amp(start_ns, high_ns, period_ns, high_ns / period_ns),
            Event::Static { since_ns, high } => {
                self.apply_amp(since_ns, 0.0, 0.0, if high { 1.0 } else { 0.0 });
                if !high && self.run_since_ns.take().is_some() {
                    // The amplifier's stop ends a run (normally or by a fault).
                    self.first_run_over = true;
                }
            }
            Event::PulseEnd { .. } => {}
        }
    }

    /// Bring the meters up to `t_ns` (a PWM that stopped switching) and forward what changed.
    fn settle(&mut self, t_ns: f64) {
        self.now_ns = self.now_ns.max(t_ns);
        for e in self.servo.settle(t_ns).into_iter().flatten() {
            self.servo_event(e);
        }
        for e in self.amp.settle(t_ns).into_iter().flatten() {
            self.amp_event(e);
        }
    }

    /// Output pin `gpio` is now at `level` ([`LEVEL_LOW`], [`LEVEL_HIGH`] or [`LEVEL_INPUT`]:
    /// not driven, which reads low through the board's pull-downs) at `t_ns`; `tick_ns` is its
    /// PWM counter's period (0 for a software-driven pin). The amplifier's pin released lets
    /// its filter discharge through the pull-down until it is driven again.
    pub fn pin(&mut self, gpio: u32, level: u32, t_ns: f64, tick_ns: f64) {
        let high = level == LEVEL_HIGH;
        if gpio == AMP_GPIO {
            self.amp_driven(t_ns, level != LEVEL_INPUT);
        }
        self.pin_level(gpio, high, t_ns, tick_ns);
    }

    /// The amplifier's pin driven (`true`) or released, from `t_ns`.
    fn amp_driven(&mut self, t_ns: f64, driven: bool) {
        if driven != self.amp_released {
            return;
        }
        self.amp_released = !driven;
        if let Some(p) = self.plant_at(t_ns) {
            if driven {
                // Driven low (a high level comes with the meter's period).
                p.set_amp_duty(0, 0, 1);
            } else {
                p.release_amp(0);
            }
        }
    }

    fn pin_level(&mut self, gpio: u32, high: bool, t_ns: f64, tick_ns: f64) {
        self.settle(t_ns);
        match gpio {
            SERVO_GPIO => {
                if tick_ns > 0.0 {
                    self.servo_tick_ns = tick_ns;
                }
                if let Some(e) = self.servo.edge(t_ns, high) {
                    self.servo_event(e);
                }
            }
            AMP_GPIO => {
                if tick_ns > 0.0 {
                    self.amp_tick_ns = tick_ns;
                }
                if let Some(e) = self.amp.edge(t_ns, high) {
                    self.amp_event(e);
                }
            }
            TRIGGER_GPIO if high != self.trigger_high => {
                self.trigger_high = high;
                self.trigger.push((t_ns, high));
                if high && self.trigger_rise_ns.is_none() {
                    self.trigger_rise_ns = Some(t_ns);
                }
                if let Some(p) = self.plant_at(t_ns) {
                    p.set_trigger(0, high);
                }
            }
            LED_GPIO if high != self.led_high => {
                self.led_high = high;
                self.led_edges += 1;
            }
            _ => {}
        }
    }

    /// A conversion of ADC channel `channel` (T1's input, else T2's: ADC0 on GP26, ADC1 on GP27) starts at
    /// `t_ns`: its result, or `None` if it never completes (the case's hang).
    pub fn adc(&mut self, channel: u32, t_ns: f64) -> Option<u16> {
        self.settle(t_ns);
        if self.plant.is_none() {
            if let Err(e) = self.make_plant(t_ns) {
                panic!("the case's plant cannot be made: {e}");
            }
        }
        if self.hang_from_ns.is_some_and(|h| t_ns >= h) {
            self.hang = true;
        }
        if self.hang {
            self.core_fault_struck_ns.get_or_insert(t_ns);
            return None;
        }
        self.conversions += 1;
        let ch = if channel == T1_ADC {
            Channel::T1
        } else {
            Channel::T2
        };
        // The sampling grid of the first run (each `run_once` starts its own ticker).
        if ch == Channel::T1 && !self.first_run_over {
            let x = t_ns - self.origin_ns;
            let phase = x - (x / 1e6).round() * 1e6;
            let (lo, hi) = self.t1_phase_ns.unwrap_or((phase, phase));
            self.t1_phase_ns = Some((lo.min(phase), hi.max(phase)));
            if phase.abs() > 2_000.0 && self.late_t1.len() < 10 {
                self.late_t1.push((t_ns, phase));
            }
        }
        let pressed = self.button_pressed;
        let fe = self.front_end;
        let after_reset = !self.resets.is_empty();
        let own_presses = !after_reset
            && t_ns >= self.case.held_from_power_up_us as f64 * 1e3
            && self.case.held_us.is_none();
        let p = self.plant_at(t_ns).expect("made above");
        let plant_pressed = p.button_pressed(0);
        let counts = p.read_analog(0, ch);
        let row = (ch == Channel::T1 && after_reset).then(|| {
            let (t, d) = (p.truth(0), p.drive());
            (t_ns, t.angle_deg, t.t1_n, t.commanded_pulse_us, d.drive_v)
        });
        // The firmware reads the button just after its T2 conversion. (The plant models the
        // cord's own press and the aborts; the operator's other presses, from power-up or
        // after a reset, are the bench's alone.)
        if ch == Channel::T2 && own_presses && plant_pressed != pressed {
            self.button_mismatches += 1;
        }
        self.after_reset.extend(row);
        let code = fe.code(fe.pin_v(fe.sensor_v(counts)));
        if code != quantise(counts) {
            self.rounding_mismatches += 1;
            if self.mismatch_examples.len() < 5 {
                self.mismatch_examples.push((t_ns, counts));
            }
        }
        if self.case.keep_samples {
            match (ch, self.samples.last_mut()) {
                (Channel::T2, Some(last)) => last.2 = code,
                _ => self.samples.push((t_ns, code, 0)),
            }
        }
        Some(code)
    }

    /// The core was busy for `cycles` from `t_ns` until it slept again.
    pub fn burst(&mut self, t_ns: f64, cycles: u32) {
        self.cycles += cycles as u64;
        let in_run = self.run_since_ns.is_some_and(|s| t_ns >= s);
        if in_run {
            self.run_bursts.push((t_ns, cycles));
        } else {
            self.idle_bursts.push((t_ns, cycles));
        }
    }

    /// The harness diverted the core into the panic path at `t_ns`.
    pub fn panicked(&mut self, t_ns: f64) {
        self.core_fault_struck_ns.get_or_insert(t_ns);
    }

    /// The chip was reset at `t_ns`: every pin is an input from then on, until the firmware
    /// drives it again.
    pub fn reset(&mut self, t_ns: f64, reason: ResetReason) {
        self.settle(t_ns);
        if self.resets.is_empty() {
            self.drive_v_at_reset = self.plant_at(t_ns).map(|p| p.drive().drive_v);
        }
        self.resets.push(Reset { t_ns, reason });
        self.hang = false;
        self.hang_from_ns = None;
        self.releasing = true;
        for e in self.servo.release(t_ns) {
            self.servo_event(e);
        }
        for e in self.amp.release(t_ns) {
            self.amp_event(e);
        }
        self.amp_driven(t_ns, false);
        self.releasing = false;
        self.run_since_ns = None;
        self.first_run_over = true;
        self.pin_level(TRIGGER_GPIO, false, t_ns, 0.0);
        self.pin_level(LED_GPIO, false, t_ns, 0.0);
    }
}
