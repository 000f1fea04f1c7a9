//! The thin async runner: ticks the pure [`Rig`] at the sample rate on embassy-time and moves
//! values between it and the hardware. The RP2040 binary, the emulated-ARM build and the host
//! simulator all run this very function; only the `RigIo` they hand it differs.

use crate::command::LineBuffer;
use crate::hal::{Console, ForceAdc, Watchdog};
use crate::record::{LogSink, RunEnd};
use crate::rig::{Inputs, Outputs, Rig};
use crate::store::SettingsFlash;
use embassy_time::{Duration, Instant, Ticker};
use embedded_hal::digital::{InputPin, OutputPin};
use embedded_hal::pwm::SetDutyCycle;

/// The rig's hardware, as traits.
pub struct RigIo<Servo, Amp, Trigger, Led, Button, Adc, Dog> {
    /// Servo PWM at 50 Hz.
    pub servo: Servo,
    /// Amplifier control voltage: PWM into an RC filter.
    pub amp: Amp,
    /// Logger trigger line (high = trigger).
    pub trigger: Trigger,
    /// Status LED.
    pub led: Led,
    /// Start/abort button, active low (pull-up, switch to ground).
    pub button: Button,
    /// Both force channels.
    pub adc: Adc,
    /// Watchdog fed every sample period.
    pub watchdog: Dog,
}

/// A hardware operation failed (a pin or PWM returned an error).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub enum RunError {
    /// Setting a PWM duty failed.
    Pwm,
    /// Driving or reading a pin failed.
    Pin,
}

impl RunError {
    /// What failed, for a person.
    pub const fn message(self) -> &'static str {
        match self {
            RunError::Pwm => "setting a PWM duty (servo or amplifier) failed",
            RunError::Pin => "driving or reading a pin (trigger, LED or button) failed",
        }
    }
}

impl core::fmt::Display for RunError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.message())
    }
}

/// Last duty written to each PWM, so unchanged commands cost no register (or plant) writes,
/// and the command it was made from, so an unchanged command costs no conversion either.
#[derive(Default)]
struct Written {
    servo: Option<u16>,
    amp: Option<u16>,
    servo_deg: Option<f32>,
    servo_pulses: Option<bool>,
    amp_control_v: Option<f32>,
    trigger: Option<bool>,
    led: Option<bool>,
}

impl Written {
    /// Every output of `out` is what was last written: [`RigIo::apply`] would do nothing.
    /// (Most samples: the outputs change at the steps only.)
    #[inline]
    fn holds(&self, out: &Outputs) -> bool {
        self.servo_deg == Some(out.servo_deg)
            && self.servo_pulses == Some(out.servo_pulses)
            && self.amp_control_v == Some(out.amp_control_v)
            && self.trigger == Some(out.trigger)
            && self.led == Some(out.led)
    }
}

impl<S, A, T, L, B, D, W> RigIo<S, A, T, L, B, D, W>
where
    S: SetDutyCycle,
    A: SetDutyCycle,
    T: OutputPin,
    L: OutputPin,
    B: InputPin,
    D: ForceAdc,
    W: Watchdog,
{
    // Inlined: returned through memory, the inputs cost the host simulator a stalled copy (a
    // wide load of narrow stores) every sample.
    #[inline(always)]
    fn read(&mut self, now_us: u64) -> Result<Inputs, RunError> {
        Ok(Inputs {
            command: None,
            now_us,
            // (T1 then T2: on the board one conversion after the other, `read_both`'s default.)
            counts: self.adc.read_both(),
            button_pressed: self.button.is_low().map_err(|_| RunError::Pin)?,
        })
    }

    fn apply(&mut self, rig: &Rig, out: &Outputs, written: &mut Written) -> Result<(), RunError> {
        // The servo and amplifier maps change only with the settings (never during a run: the
        // tare only re-zeroes the force channels), and `serve` forgets `written` then; so a
        // command equal to the last one maps to the same duty.
        let cal = rig.calibration();
        if written.servo_deg != Some(out.servo_deg)
            || written.servo_pulses != Some(out.servo_pulses)
        {
            // Duty 0: no pulses at all (the servo is unpowered).
            let servo = if out.servo_pulses {
                cal.servo.duty(out.servo_deg, self.servo.max_duty_cycle())
            } else {
                0
            };
            if written.servo != Some(servo) {
                self.servo
                    .set_duty_cycle(servo)
                    .map_err(|_| RunError::Pwm)?;
                written.servo = Some(servo);
            }
            written.servo_deg = Some(out.servo_deg);
            written.servo_pulses = Some(out.servo_pulses);
        }
        if written.amp_control_v != Some(out.amp_control_v) {
            let amp = cal.amp.duty(out.amp_control_v, self.amp.max_duty_cycle());
            if written.amp != Some(amp) {
                self.amp.set_duty_cycle(amp).map_err(|_| RunError::Pwm)?;
                written.amp = Some(amp);
            }
            written.amp_control_v = Some(out.amp_control_v);
        }
        if written.trigger != Some(out.trigger) {
            self.trigger
                .set_state(out.trigger.into())
                .map_err(|_| RunError::Pin)?;
            written.trigger = Some(out.trigger);
        }
        if written.led != Some(out.led) {
            self.led
                .set_state(out.led.into())
                .map_err(|_| RunError::Pin)?;
            written.led = Some(out.led);
        }
        Ok(())
    }

    /// Put the hardware in its safe state: servo at rest (no pulses while the rig holds it
    /// limp), amplifier 0 V, trigger low.
    pub fn make_safe(&mut self, rig: &Rig) -> Result<(), RunError> {
        self.apply(rig, &rig.safe_outputs(), &mut Written::default())
    }

    /// The outputs at boot, before the first sample: amplifier 0 V, trigger low, LED off, and
    /// the servo at the rest of the settings in force, or without pulses after a reset that
    /// latched a fault ([`Rig::idle_outputs`]).
    pub fn boot(&mut self, rig: &Rig) -> Result<(), RunError> {
        self.apply(rig, &rig.idle_outputs(), &mut Written::default())
    }
}

/// The hardware watchdog's timeout while the loop samples, ms (the board's
/// `WATCHDOG_TIMEOUT`; host-sim resets its simulated board this long after a frozen loop's last
/// feed). Ten samples: a loop that has stopped leaves the outputs as they were for at most this
/// long before the chip resets and releases every pin.
pub const WATCHDOG_MS: u32 = 10;

/// The watchdog's allowance while the flash is written, ms: a 4 KiB erase takes ~45 ms and
/// at most ~400 ms on the Pico's W25Q16, and a save may erase several pages (a repair, a
/// migration). The RP2040's watchdog takes up to 8.3 s. Only then, and only with the outputs
/// already safe: the rig asks for a write only with the servo at rest and the amplifier off
/// (`store` is refused otherwise), and the write holds the loop and its checks.
pub const STORE_WATCHDOG_MS: u32 = 5_000;

/// Wait for the button, run the protocol once, return how it ended (no host commands, no
/// flash: the simulator's campaigns).
pub async fn run_once<S, A, T, L, B, D, W>(
    io: &mut RigIo<S, A, T, L, B, D, W>,
    rig: &mut Rig,
    sink: &mut impl LogSink,
) -> Result<RunEnd, RunError>
where
    S: SetDutyCycle,
    A: SetDutyCycle,
    T: OutputPin,
    L: OutputPin,
    B: InputPin,
    D: ForceAdc,
    W: Watchdog,
{
    serve(io, rig, sink, &mut (), &mut (), |out, _| out.finished).await
}

/// Serve the rig: sample every `1/sample_hz` on an embassy-time [`Ticker`] (a late tick is
/// caught by the supervisor's watchdog check), take at most one host command line per sample
/// from `console`, write the settings to `flash` when asked, until `until` returns a value for
/// the outputs of a sample (it also sees the rig, e.g. to re-arm the board's panic path when
/// the settings changed). On a hardware error the rig is made safe (best effort) and the
/// error returned.
pub async fn serve<S, A, T, L, B, D, W, R>(
    io: &mut RigIo<S, A, T, L, B, D, W>,
    rig: &mut Rig,
    sink: &mut impl LogSink,
    console: &mut impl Console,
    flash: &mut impl SettingsFlash,
    mut until: impl FnMut(&Outputs, &Rig) -> Option<R>,
) -> Result<R, RunError>
where
    S: SetDutyCycle,
    A: SetDutyCycle,
    T: OutputPin,
    L: OutputPin,
    B: InputPin,
    D: ForceAdc,
    W: Watchdog,
{
    let period = Duration::from_micros(rig.protocol().sample_period_us() as u64);
    let mut ticker = Ticker::every(period);
    let mut written = Written::default();
    let mut line = LineBuffer::default();
    let result = loop {
        ticker.next().await;
        io.watchdog.feed();
        // (The inputs in a block of their own: dead before the flash write's await below, so
        // the future does not keep them in its state, where every sample stored and reloaded
        // them.)
        let out = {
            let now_us = Instant::now().as_micros();
            sink.sample_started(now_us);
            let mut inputs = match io.read(now_us) {
                Ok(i) => i,
                Err(e) => break Err(e),
            };
            inputs.command = core::iter::from_fn(|| console.read_byte()).find_map(|b| line.push(b));
            rig.step(&inputs, sink)
        };
        if out.settings_changed {
            // New servo or amplifier maps: the same angle may be another duty now.
            written = Written::default();
        }
        let applied = if written.holds(&out) {
            Ok(())
        } else {
            io.apply(rig, &out, &mut written)
        };
        sink.flush();
        if let Err(e) = applied {
            break Err(e);
        }
        if let Some(settings) = out.store {
            io.watchdog.allow_ms(STORE_WATCHDOG_MS);
            let ok = flash.save(&settings).await;
            io.watchdog.feed();
            rig.stored(ok, sink);
            sink.flush();
            // No burst of catch-up ticks after the write.
            ticker.reset();
        }
        if let Some(r) = until(&out, rig) {
            break Ok(r);
        }
    };
    if result.is_err() {
        let _ = io.make_safe(rig);
    }
    result
}
