//! The rig's answers to host commands, and setup mode's sample period: what each command may
//! do in each phase, its `reply` record, and the settings it changes. Pure, like `rig.rs`.

use super::{on_grid, Inputs, Outputs, Phase, Rig};
use crate::command::{Command, CommandError, CommandKind};
use crate::record::{Fault, Live, LogSink, Record, Reply, SettingsReport, SettingsSource};
use crate::safety::{SafetyInput, Supervisor};
use crate::settings::{Settings, SettingsError};
use crate::setup::{self, Measure, Measuring, LIVE_EVERY_MS, SETUP_DEG_PER_S};

/// An angle within the servo's 0..=180°. Not `f32::clamp`: its assertion links ~1 KiB of
/// float formatting into the board image.
#[allow(clippy::manual_clamp)]
fn servo_range(a: f32) -> f32 {
    if a < 0.0 {
        0.0
    } else if a > 180.0 {
        180.0
    } else {
        a
    }
}

/// One sample's move from `at` toward `target` at [`SETUP_DEG_PER_S`].
fn toward(at: f32, target: f32, sample_hz: u32) -> f32 {
    let step = SETUP_DEG_PER_S / sample_hz as f32;
    let gap = target - at;
    if gap.abs() <= step {
        target
    } else if gap > 0.0 {
        at + step
    } else {
        at - step
    }
}

impl Rig {
    /// The settings in force.
    pub fn settings(&self) -> Settings {
        Settings {
            protocol: self.protocol,
            calibration: self.cal,
        }
    }

    /// Run with `s` from now on (refused during a run, or if invalid, or if its sample rates
    /// differ from the firmware's). The servo never jumps: with a new servo map its command
    /// becomes the angle that keeps today's pulse, and from there it moves slowly (idle: homing
    /// to the new rest angle; setup mode: towards the host's target).
    pub fn use_settings(&mut self, s: Settings) -> Result<(), SettingsError> {
        s.validate()?;
        let (p, d) = (&s.protocol, &self.defaults.protocol);
        if p.sample_hz != d.sample_hz || p.raw_log_hz != d.raw_log_hz {
            return Err(SettingsError::Rates);
        }
        if self.is_running() {
            return Err(SettingsError::Rates);
        }
        let commanded = match self.phase {
            Phase::Setup { servo_deg, .. } => servo_deg,
            _ => self.idle_servo_deg,
        };
        let pulse_us = self.cal.servo.pulse_us(commanded);
        self.settings_changed = true;
        self.protocol = s.protocol;
        self.cal = s.calibration;
        let same_place = self.cal.servo.angle_deg(pulse_us);
        match &mut self.phase {
            Phase::Setup { servo_deg, .. } => *servo_deg = servo_range(same_place),
            _ => {
                self.idle_servo_deg = self.protocol.rest_deg;
                self.home_from(same_place);
            }
        }
        Ok(())
    }

    /// Log the settings in force and where they came from (at boot: stored or defaults, and
    /// why).
    pub fn report_settings(&mut self, source: SettingsSource, sink: &mut impl LogSink) {
        self.settings_source = source;
        // Literal messages: defmt keeps them off the chip (SettingsSource::message is the
        // host's copy of the same words).
        match source {
            SettingsSource::DefaultsNoRecord => {
                warn!("no settings stored: using the built-in defaults")
            }
            SettingsSource::DefaultsCorrupt => {
                warn!("the stored settings are corrupt: using the built-in defaults")
            }
            SettingsSource::DefaultsInvalid => warn!(
                "the stored settings are of another version or invalid: using the built-in defaults"
            ),
            SettingsSource::DefaultsFlashError => {
                warn!("the flash could not be read: using the built-in defaults")
            }
            SettingsSource::Loaded => info!("settings loaded from flash"),
            _ => {}
        }
        let report = SettingsReport {
            source,
            settings: self.settings(),
        };
        self.emit(sink, Record::Settings(report));
    }

    /// The runner's report on a `store` request: written (`true`) or not.
    pub fn stored(&mut self, written: bool, sink: &mut impl LogSink) {
        // The flash write held the loop: the gap is not a fault, and setup mode's sample grid
        // starts again from the next sample.
        self.supervisor = Supervisor::new(self.limits);
        self.reanchor = true;
        if written {
            self.report_settings(SettingsSource::Stored, sink);
            self.reply(sink, CommandKind::Store, Ok([0.0; 2]));
        } else {
            self.reply(sink, CommandKind::Store, Err(CommandError::StoreFailed));
        }
    }

    pub(super) fn reply(
        &mut self,
        sink: &mut impl LogSink,
        command: CommandKind,
        result: Result<[f32; 2], CommandError>,
    ) {
        let reply = Reply {
            command,
            error: result.err(),
            values: result.unwrap_or([0.0; 2]),
        };
        self.emit(sink, Record::Reply(reply));
    }

    /// Act on one command (`Abort` during a run is the runner's button: not here). Returns
    /// settings to store, when asked.
    pub(super) fn command(
        &mut self,
        cmd: Result<Command, CommandError>,
        now_us: u64,
        sink: &mut impl LogSink,
    ) -> Option<Settings> {
        let cmd = match cmd {
            Ok(c) => c,
            Err(e) => {
                self.reply(sink, CommandKind::Unparsed, Err(e));
                return None;
            }
        };
        let kind = cmd.kind();
        if self.is_running() && cmd != Command::Show {
            self.reply(sink, kind, Err(CommandError::Running));
            return None;
        }
        if cmd == Command::Store {
            // A measurement would lose samples to the flash write, and its result would not
            // be in what was stored.
            if let Err(e) = self.ensure_not_measuring() {
                self.reply(sink, kind, Err(e));
                return None;
            }
            return Some(self.settings());
        }
        let result = self.act(cmd, now_us, sink);
        // A zero or weigh replies when its measurement ends.
        if !(result.is_ok() && matches!(cmd, Command::Zero | Command::Weigh(..))) {
            self.reply(sink, kind, result);
        }
        None
    }

    fn act(
        &mut self,
        cmd: Command,
        now_us: u64,
        sink: &mut impl LogSink,
    ) -> Result<[f32; 2], CommandError> {
        let latched = self.latched_fault().is_some();
        match cmd {
            Command::Show => {
                self.report_settings(self.settings_source, sink);
                Ok([0.0; 2])
            }
            Command::Set(key, value) => {
                self.ensure_not_measuring()?;
                let s = self.settings().with(key, value);
                self.use_settings(s.map_err(|_| CommandError::Invalid)?)
                    .map_err(|_| CommandError::Invalid)?;
                self.settings_source = SettingsSource::Current;
                Ok([key.code() as f32, value])
            }
            Command::Defaults => {
                self.ensure_not_measuring()?;
                self.use_settings(self.defaults)
                    .map_err(|_| CommandError::Invalid)?;
                self.report_settings(SettingsSource::DefaultsAsked, sink);
                Ok([0.0; 2])
            }
            Command::Setup if latched => Err(CommandError::FaultLatched),
            Command::Setup if !self.is_in_setup() => {
                self.supervisor = Supervisor::new(self.limits);
                self.phase = Phase::Setup {
                    servo_deg: self.idle_servo_deg,
                    target_deg: self.idle_servo_deg,
                    measure: None,
                    origin_us: now_us,
                    next_live_us: now_us,
                };
                info!("setup mode: amplifier at 0 V, servo jogged by the host");
                Ok([self.idle_servo_deg, 0.0])
            }
            Command::Leave | Command::Abort if self.is_in_setup() => {
                self.leave_setup(sink);
                Ok([0.0; 2])
            }
            Command::Jog(d) => self.move_servo(|at| at + d),
            Command::Servo(a) => self.move_servo(|_| a),
            Command::Zero => self.start_measure(Measuring::Zero, now_us),
            Command::Weigh(ch, n) => self.start_measure(Measuring::Weigh(ch, n), now_us),
            Command::Run if latched => Err(CommandError::FaultLatched),
            Command::Run if self.is_homing() => Err(CommandError::Homing),
            Command::Run if !self.is_in_setup() => {
                self.start(now_us);
                Ok([self.runs as f32, 0.0])
            }
            Command::Ack if latched => {
                self.phase = Phase::Idle { latched: None };
                info!("fault acknowledged by the host");
                Ok([0.0; 2])
            }
            _ => Err(CommandError::NotApplicable),
        }
    }

    fn ensure_not_measuring(&self) -> Result<(), CommandError> {
        match self.phase {
            Phase::Setup {
                measure: Some(_), ..
            } => Err(CommandError::Measuring),
            _ => Ok(()),
        }
    }

    /// Set where the servo goes (a jog adds to the last target); it moves there at
    /// [`SETUP_DEG_PER_S`].
    fn move_servo(&mut self, to: impl Fn(f32) -> f32) -> Result<[f32; 2], CommandError> {
        let Phase::Setup { target_deg, .. } = &mut self.phase else {
            return Err(CommandError::NotInSetup);
        };
        let a = servo_range(to(*target_deg));
        *target_deg = a;
        Ok([a, 0.0])
    }

    fn start_measure(&mut self, what: Measuring, now_us: u64) -> Result<[f32; 2], CommandError> {
        let period_us = self.period_us;
        let Phase::Setup {
            measure, origin_us, ..
        } = &mut self.phase
        else {
            return Err(CommandError::NotInSetup);
        };
        if measure.is_some() {
            return Err(CommandError::Measuring);
        }
        *measure = Some(Measure::new(what, on_grid(now_us, *origin_us, period_us)));
        Ok([0.0; 2])
    }

    /// Back to idle; the servo homes from where it was jogged.
    fn leave_setup(&mut self, sink: &mut impl LogSink) {
        if let Phase::Setup { servo_deg, .. } = self.phase {
            self.interrupt_measure(sink);
            self.phase = Phase::Idle { latched: None };
            self.idle_servo_deg = self.protocol.rest_deg;
            self.home_from(servo_deg);
            info!("setup mode left: the servo homes to rest");
        }
    }

    /// A zero or weigh still measuring when setup mode ends is answered, as interrupted.
    fn interrupt_measure(&mut self, sink: &mut impl LogSink) {
        if let Phase::Setup {
            measure: Some(m), ..
        } = self.phase
        {
            let kind = match m.what {
                Measuring::Zero => CommandKind::Zero,
                Measuring::Weigh(..) => CommandKind::Weigh,
            };
            self.reply(sink, kind, Err(CommandError::Interrupted));
        }
    }

    /// One sample period in setup mode.
    pub(super) fn step_setup(
        &mut self,
        inp: &Inputs,
        pressed: bool,
        sink: &mut impl LogSink,
    ) -> Outputs {
        let Phase::Setup {
            mut servo_deg,
            target_deg,
            mut measure,
            mut origin_us,
            mut next_live_us,
        } = self.phase
        else {
            return self.safe_outputs();
        };
        if core::mem::take(&mut self.reanchor) {
            (origin_us, next_live_us) = (inp.now_us, inp.now_us);
        }
        let now_us = on_grid(inp.now_us, origin_us, self.period_us);
        if pressed {
            self.leave_setup(sink);
            // Logged as a `leave`, so the log shows where setup mode ended.
            self.reply(sink, CommandKind::Leave, Ok([0.0; 2]));
            return self.idle_outputs();
        }
        let force_n = self.forces(inp);
        let counts_ok = match inp.counts {
            [Ok(a), Ok(b)] => Some([a, b]),
            _ => None,
        };
        let safety = SafetyInput {
            t_us: inp.now_us as i64,
            counts: inp.counts,
            force_n,
            cord_check_armed: false,
        };
        if let Some(f) = self.supervisor.check(&safety) {
            return self.setup_fault(f, sink);
        }
        if let Some(done) = measure.as_mut().and_then(|m| m.push(now_us, counts_ok)) {
            let what = measure.map(|m| m.what);
            measure = None;
            let result = match what {
                Some(w) => done.and_then(|m| setup::apply(w, m, &mut self.cal)),
                None => Err(CommandError::NoLoad),
            };
            let kind = match what {
                Some(Measuring::Zero) => CommandKind::Zero,
                _ => CommandKind::Weigh,
            };
            self.reply(sink, kind, result);
        }
        if now_us >= next_live_us {
            next_live_us += LIVE_EVERY_MS as u64 * 1000;
            let live = Live {
                t_ms: (now_us / 1000) as u32,
                counts: [inp.counts[0].unwrap_or(0), inp.counts[1].unwrap_or(0)],
                force_n,
                servo_deg,
            };
            self.emit(sink, Record::Live(live));
        }
        servo_deg = toward(servo_deg, target_deg, self.protocol.sample_hz);
        self.phase = Phase::Setup {
            servo_deg,
            target_deg,
            measure,
            origin_us,
            next_live_us,
        };
        Outputs {
            servo_deg,
            led: (inp.now_us / 1000 / 250).is_multiple_of(2),
            ..self.safe_outputs()
        }
    }

    /// A safety fault in setup mode: logged, latched, servo straight to rest.
    fn setup_fault(&mut self, f: Fault, sink: &mut impl LogSink) -> Outputs {
        warn!("fault {} in setup mode: outputs safe", f.kind);
        self.emit(sink, Record::Fault(f));
        self.interrupt_measure(sink);
        self.phase = Phase::Idle {
            latched: Some(f.kind),
        };
        self.idle_servo_deg = self.protocol.rest_deg;
        self.safe_outputs()
    }
}
