//! RP2040 (Raspberry Pi Pico) board binary: wires the Pico's pins to the rig core and serves
//! runs forever. All behaviour (protocol, tare, conditioning, safety, records) is in the
//! library; this file only builds the drivers, adapts what embedded-hal has no trait for (the
//! ADC, the watchdog, the RTT command channel), loads the stored settings and calls
//! [`capstan_rig::runner::serve`]. The pins, PWM
//! timing, protocol and calibration are in `board.rs`; the panic and HardFault handlers, which
//! drive the outputs safe through the registers, in `board_safe.rs`.
//!
//! Build and flash from the workspace root:
//! `cargo run --release -p capstan-board --target thumbv6m-none-eabi` (see README.md, "Firmware on a Raspberry Pi Pico").
//!
//! On the host this compiles to a stub `main` that says what it is, so that `cargo test` at
//! the root can build the whole workspace.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(target_os = "none")]
mod board;
#[cfg(target_os = "none")]
mod board_log;
#[cfg(target_os = "none")]
mod board_safe;

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!(
        "this is the RP2040 (Raspberry Pi Pico) firmware of the capstan rig; build and flash it \
         with `cargo run --release -p capstan-board --target thumbv6m-none-eabi` \
         (see README.md, \"Firmware on a Raspberry Pi Pico\")"
    );
}

#[cfg(target_os = "none")]
mod pico {
    use crate::board::{self, BoardPins, Pins, RigPins};
    use crate::board_safe::{self, PeriodPwm, RememberingServo};
    use capstan_rig::defmt_sink::DefmtSink;
    use capstan_rig::hal::{AdcError, Channel, Console, ForceAdc};
    use capstan_rig::reset::ResetCause;
    use capstan_rig::store::SettingsStore;
    use capstan_rig::{RigIo, SafeDuties};
    use embassy_embedded_hal::adapter::BlockingAsync;
    use embassy_executor::Spawner;
    use embassy_rp::adc::{self, Adc, Blocking};
    use embassy_rp::flash::Flash;
    use embassy_rp::gpio::{Input, Level, Output, Pull};
    use embassy_rp::pwm::{self, Pwm};
    use embassy_rp::watchdog::{ResetReason, Watchdog};
    use embassy_time::Duration;
    use rtt_target::{ChannelMode, DownChannel, UpChannel};

    /// Both force sensors on the RP2040's ADC, read by blocking conversions (2 µs each at
    /// 500 ksps: nothing to gain from the async driver at 1 kHz).
    struct ForceSensors {
        adc: Adc<'static, Blocking>,
        t1: adc::Channel<'static>,
        t2: adc::Channel<'static>,
    }

    impl ForceAdc for ForceSensors {
        fn read_counts(&mut self, channel: Channel) -> Result<u16, AdcError> {
            let input = match channel {
                Channel::T1 => &mut self.t1,
                Channel::T2 => &mut self.t2,
            };
            // A conversion error (the ADC's ERR flag) becomes AdcError; the supervisor counts
            // it like a reading at the rail.
            self.adc.blocking_read(input).map_err(|_| AdcError)
        }
    }

    /// The RP2040's hardware watchdog, reloaded with the same timeout at every feed, and its
    /// control put back at every feed: enabled, and paused by a debugger's halt only as
    /// `board::WATCHDOG_PAUSES_WHILE_HALTED` says. A debugger (or a stray write) that disabled
    /// it, or set it to pause, is undone within a sample.
    struct HardwareWatchdog {
        dog: Watchdog,
        timeout: Duration,
    }

    impl HardwareWatchdog {
        fn reassert(&mut self) {
            let pause = board::WATCHDOG_PAUSES_WHILE_HALTED;
            embassy_rp::pac::WATCHDOG.ctrl().modify(|w| {
                w.set_enable(true);
                w.set_pause_dbg0(pause);
                w.set_pause_dbg1(pause);
                w.set_pause_jtag(pause);
            });
        }
    }

    impl capstan_rig::hal::Watchdog for HardwareWatchdog {
        fn feed(&mut self) {
            self.dog.feed(self.timeout);
            self.reassert();
        }
        fn allow_ms(&mut self, ms: u32) {
            self.dog.feed(Duration::from_millis(ms as u64));
            self.reassert();
        }
    }

    /// The host's command lines on RTT down channel 0. Each read also puts the defmt up
    /// channel back to non-blocking: a host (probe-rs run) may have set it to block when full,
    /// and a blocked log write would stall the safety loop.
    struct RttConsole {
        commands: DownChannel,
        log: UpChannel,
    }

    impl Console for RttConsole {
        fn read_byte(&mut self) -> Option<u8> {
            if self.log.mode() != ChannelMode::NoBlockSkip {
                self.log.set_mode(ChannelMode::NoBlockSkip);
            }
            let mut b = [0u8];
            (self.commands.read(&mut b) == 1).then_some(b[0])
        }
    }

    /// RTT: defmt on up channel 0, the host's commands on down channel 0.
    fn rtt() -> RttConsole {
        let channels = rtt_target::rtt_init! {
            up: { 0: { size: board::LOG_BUFFER_BYTES, mode: ChannelMode::NoBlockSkip, name: "defmt" } }
            down: { 0: { size: board::COMMAND_BUFFER_BYTES, name: "commands" } }
        };
        crate::board_log::set_channel(channels.up.0);
        // SAFETY: channel 0 was just initialised; this second handle only sets its mode.
        let log = unsafe { UpChannel::conjure(0) };
        RttConsole {
            commands: channels.down.0,
            log: defmt::unwrap!(log),
        }
    }

    fn pwm_config(divider: u8, top: u16) -> pwm::Config {
        let mut c = pwm::Config::default();
        c.divider = divider.into();
        c.top = top;
        // Output low until the rig's first command (make_safe, below).
        c.compare_a = 0;
        c
    }

    /// The board's I/O as the rig core drives it.
    type BoardIo = RigIo<
        RememberingServo,
        PeriodPwm,
        Output<'static>,
        Output<'static>,
        Input<'static>,
        ForceSensors,
        HardwareWatchdog,
    >;

    #[embassy_executor::main]
    async fn main(_spawner: Spawner) {
        let mut console = rtt();
        let p = embassy_rp::init(Default::default());
        let clk = embassy_rp::clocks::clk_sys_freq();
        defmt::assert_eq!(
            clk,
            board::CLK_SYS_HZ,
            "PWM timing assumes a 125 MHz clk_sys"
        );
        let pins = Pins::take(p);
        // The panic path writes these pins' registers by number (board_safe.rs), the host and
        // the emulated board take them from the same schema.
        defmt::assert!(
            pins.are_the_schemas(),
            "board::Pins must be the pins of capstan_wire::pins::PINS"
        );
        let BoardPins {
            watchdog,
            smps_mode,
            flash,
        } = pins.board;
        // Quieter 3V3/ADC_VREF for the force sensors; kept for the whole program (dropping an
        // Output would release the pin).
        let _smps_pwm_mode = Output::new(smps_mode, Level::High);
        let mut dog = Watchdog::new(watchdog);
        let cause = reset_cause(&dog);
        // Not paused while a debugger halts the core (see board::WATCHDOG_PAUSES_WHILE_HALTED),
        // set before anything can halt.
        dog.pause_on_debug(board::WATCHDOG_PAUSES_WHILE_HALTED);

        let mut rig = defmt::unwrap!(capstan_rig::Rig::new(
            board::protocol(),
            board::calibration(),
            board::safety_limits(),
        ));
        let flash =
            Flash::<_, embassy_rp::flash::Blocking, { board::FLASH_BYTES }>::new_blocking(flash);
        let mut store = defmt::unwrap!(SettingsStore::new(
            BlockingAsync::new(flash),
            board::SETTINGS_FLASH
        ));
        let mut sink = DefmtSink::default();
        boot(&mut rig, &mut store, &mut sink, cause).await;

        let mut io = rig_io(pins.rig, dog);
        // Amplifier to 0 V, trigger low, the servo at the stored rest (or without pulses after
        // a reset that latched a fault), before anything runs.
        defmt::unwrap!(io.boot(&rig));
        io.watchdog.dog.start(board::WATCHDOG_TIMEOUT);
        defmt::info!(
            "capstan rig ready: {=u32} Hz sampling, watchdog {=u64} ms; press the button to run, or set it up with capstan rig",
            rig.protocol().sample_hz,
            board::WATCHDOG_TIMEOUT.as_millis()
        );
        serve(&mut io, &mut rig, &mut sink, &mut console, &mut store).await
    }

    /// Why the chip last reset (and the log says): the watchdog's REASON, whether the latch
    /// word survived (the core alone reset), the chip's CHIP_RESET flags
    /// (`capstan_rig::reset::ResetCause::from_registers`).
    fn reset_cause(dog: &Watchdog) -> ResetCause {
        let timer = dog
            .reset_reason()
            .map(|r| matches!(r, ResetReason::TimedOut));
        let chip = embassy_rp::pac::VREG_AND_CHIP_RESET.chip_reset().read();
        let cause = ResetCause::from_registers(
            timer,
            board_safe::latch_word_before_reset(),
            chip.had_run(),
            chip.had_psm_restart(),
        );
        match cause {
            ResetCause::Watchdog => defmt::warn!(
                "the hardware watchdog reset the chip: the loop stopped (a hang, a lockup, a stack overflow), or a debugger held the core halted"
            ),
            ResetCause::Forced => defmt::warn!(
                "reset by the panic/HardFault handler, after it had made the outputs safe"
            ),
            ResetCause::RunPin => {
                defmt::warn!("reset by the RUN pin: what the rig was doing is not kept")
            }
            ResetCause::DebugPort => {
                defmt::warn!("restarted by the debug port: what the rig was doing is not kept")
            }
            ResetCause::Core => defmt::warn!("the core was reset (a debugger)"),
            ResetCause::PowerOn => {}
        }
        cause
    }

    /// Before the servo's first pulse: the stored settings (or the built-in ones, logged either
    /// way, by the first sample: that pulse is the stored rest), the fault a reset latches, and
    /// the panic path armed.
    async fn boot(
        rig: &mut capstan_rig::Rig,
        store: &mut SettingsStore<impl embedded_storage_async::nor_flash::NorFlash>,
        sink: &mut DefmtSink,
        cause: ResetCause,
    ) {
        store.load_into(rig, sink).await;
        // A reset that was not a clean power-up at rest latches a fault (kept across it), and
        // the servo gets no pulses until a person acknowledges it: nothing moves by itself.
        let latched =
            capstan_rig::reset::boot(rig, cause, board_safe::latch_word_before_reset(), sink);
        board_safe::remember_latch(capstan_rig::reset::latch_word(rig));
        if let (Some(_), Some(duty)) = (latched, board_safe::servo_duty_before_reset()) {
            let angle = rig
                .calibration()
                .servo
                .angle_for_duty(duty, board::SERVO_FULL_SCALE);
            defmt::warn!(
                "the servo was commanded to {=f32} deg before the reset: no pulses until a press (after a release) or `ack`; the first is the rest pulse",
                angle
            );
        }
        // (The records of the boot, the settings and a latched fault, are held: the first
        // sample sends them, after its outputs, as it sends every record.)
        // From here a panic puts the servo at rest (before: no pulses at all; and none while
        // the rig holds the servo without pulses).
        board_safe::arm(SafeDuties::for_rig(rig, board::SERVO_FULL_SCALE));
    }

    /// The rig's drivers: both PWMs (low until the rig's first command), the trigger, LED and
    /// button, the ADC, the watchdog.
    fn rig_io(pins: RigPins, dog: Watchdog) -> BoardIo {
        let servo = Pwm::new_output_a(
            pins.servo_slice,
            pins.servo,
            pwm_config(board::SERVO_PWM_DIVIDER, board::SERVO_PWM_TOP),
        );
        let amp = Pwm::new_output_a(
            pins.amp_slice,
            pins.amp,
            pwm_config(board::AMP_PWM_DIVIDER, board::AMP_PWM_TOP),
        );
        let adc = ForceSensors {
            adc: Adc::new_blocking(pins.adc, adc::Config::default()),
            // No pad pulls: they would load the sensor's divider.
            t1: adc::Channel::new_pin(pins.t1, Pull::None),
            t2: adc::Channel::new_pin(pins.t2, Pull::None),
        };
        RigIo {
            // Duties as fractions of the whole period (top + 1 counts), see `PeriodPwm`.
            servo: RememberingServo(PeriodPwm::new(servo, board::SERVO_SLICE)),
            amp: PeriodPwm::new(amp, board::AMP_SLICE),
            trigger: Output::new(pins.trigger, Level::Low),
            led: Output::new(pins.led, Level::Low),
            button: Input::new(pins.button, Pull::Up),
            adc,
            watchdog: HardwareWatchdog {
                dog,
                timeout: board::WATCHDOG_TIMEOUT,
            },
        }
    }

    /// Runs, setup mode and host commands, forever: `serve` returns only on a hardware error,
    /// which cannot happen with this HAL (its pins are infallible, duties are clamped to top).
    /// The runner has then already commanded the safe state; the panic handler forces it again
    /// through the registers and the chip resets.
    async fn serve(
        io: &mut BoardIo,
        rig: &mut capstan_rig::Rig,
        sink: &mut DefmtSink,
        console: &mut RttConsole,
        store: &mut SettingsStore<impl embedded_storage_async::nor_flash::NorFlash>,
    ) {
        // New settings may move the rest angle or change the servo map, and an acknowledged
        // reset gives the servo its pulses back: the panic path's rest duty follows them. The
        // latch word is kept every sample for the next boot.
        let never = |out: &capstan_rig::rig::Outputs, rig: &capstan_rig::Rig| {
            board_safe::remember_latch(capstan_rig::reset::latch_word(rig));
            if out.settings_changed {
                board_safe::arm(SafeDuties::for_rig(rig, board::SERVO_FULL_SCALE));
            }
            None::<()>
        };
        let served = capstan_rig::runner::serve(io, rig, sink, console, store, never).await;
        if let Err(e) = served {
            defmt::panic!("hardware error {}: outputs made safe", e);
        }
    }
}
