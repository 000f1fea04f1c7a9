//! The rig's answers to host commands, and setup mode's sample period: what each command may
//! do in each phase, its `reply` record, and the settings it changes. Pure, like `rig.rs`.

use super::{on_grid, Inputs, Outputs, Phase, Rig, ARM_MS, TARE_MAX_N};
use crate::button::Edge;
use crate::calib::{CalSource, ChannelCal};
use crate::command::{Command, CommandError, CommandKind};
use crate::hal::Channel;
use crate::record::{Fault, Live, LogSink, Record, Reply, SettingsReport, SettingsSource};
use crate::safety::{SafetyInput, Supervisor};
use crate::settings::{Settings, SettingsError, END_STOP_MARGIN_DEG};
use crate::setup::{self, Measure, Measuring, LIVE_EVERY_MS, SETUP_DEG_PER_S};
use capstan_wire::Key;

/// An angle within the servo map's travel, [`END_STOP_MARGIN_DEG`] clear of its ends (a jog
/// or a typo never drives the servo into its end stops). Not `f32::clamp`: its assertion links
/// ~1 KiB of float formatting into the board image.
#[allow(clippy::manual_clamp)]
fn servo_range(a: f32, max_deg: f32) -> f32 {
    let (lo, hi) = (END_STOP_MARGIN_DEG, max_deg - END_STOP_MARGIN_DEG);
    if a < lo {
        lo
    } else if a > hi {
        hi
    } else {
        a
    }
}

/// `s` after `set KEY`: a typed sensitivity counts as measured (by the person who typed it),
/// at the zero in force; a typed zero that moves more than 1 N from the one its sensitivity
/// was measured at leaves that sensitivity unmeasured.
fn typed(mut s: Settings, key: Key) -> Settings {
    let c = &mut s.calibration;
    match key {
        Key::T1NPerCount => c.t1 = c.t1.measured(CalSource::Typed),
        Key::T2NPerCount => c.t2 = c.t2.measured(CalSource::Typed),
        Key::T1Zero => c.t1 = c.t1.rezeroed(c.t1.zero_counts),
        Key::T2Zero => c.t2 = c.t2.rezeroed(c.t2.zero_counts),
        _ => {}
    }
    s
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
    /// differ from the firmware's, or if under its calibration the over-force check could not
    /// trip). The servo never jumps: with a new servo map its command becomes the angle that
    /// keeps today's pulse, and from there it moves slowly (idle: homing to the new rest angle,
    /// supervised, not while a fault is latched; setup mode: towards the host's target).
    pub fn use_settings(&mut self, s: Settings) -> Result<(), SettingsError> {
        self.check_settings(&s)?;
        let commanded = match self.phase {
            Phase::Setup { servo_deg, .. } => servo_deg,
            _ => self.idle_servo_deg,
        };
        let pulse_us = self.cal.servo.pulse_us(commanded);
        self.adopt(s);
        let same_place = self.cal.servo.angle_deg(pulse_us);
        let max_deg = self.cal.servo.max_deg;
        match &mut self.phase {
            Phase::Setup { servo_deg, .. } => *servo_deg = servo_range(same_place, max_deg),
            _ => {
                self.idle_servo_deg = self.protocol.rest_deg;
                self.home_from(same_place);
            }
        }
        Ok(())
    }

    /// At boot, before the servo has had a pulse: run with `s` (the stored settings), as
    /// [`Rig::use_settings`] but with nothing to home from: the first pulse is `s`'s rest.
    pub fn use_stored_settings(&mut self, s: Settings) -> Result<(), SettingsError> {
        self.check_settings(&s)?;
        self.adopt(s);
        self.idle_servo_deg = self.protocol.rest_deg;
        Ok(())
    }

    // Not inlined: two callers, ~250 bytes of flash each.
    #[inline(never)]
    fn check_settings(&self, s: &Settings) -> Result<(), SettingsError> {
        s.validate()?;
        let (p, d) = (&s.protocol, &self.defaults.protocol);
        if p.sample_hz != d.sample_hz || p.raw_log_hz != d.raw_log_hz || self.is_running() {
            return Err(SettingsError::Rates);
        }
        self.limits
            .visible(&s.calibration)
            .map_err(|_| SettingsError::Blind)
    }

    fn adopt(&mut self, s: Settings) {
        self.settings_changed = true;
        self.protocol = s.protocol;
        self.cal = s.calibration;
        self.zeros = self.cal.zeros();
    }

    /// True when the servo is commanded to rest and stays there (idle at rest, or setup mode
    /// with the servo at rest and no move asked): a flash write, which holds the loop, may
    /// only come then.
    fn servo_at_rest(&self) -> bool {
        let rest = self.protocol.rest_deg;
        match self.phase {
            Phase::Setup {
                servo_deg,
                target_deg,
                ..
            } => servo_deg == rest && target_deg == rest,
            _ => self.is_at_rest(),
        }
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
            // be in what was stored. The write holds the loop (and its checks) for up to
            // ~0.4 s a sector: only with the servo at rest (and the amplifier off, as always
            // outside a run).
            let ready = self.ensure_not_measuring().and_then(|()| {
                self.servo_at_rest()
                    .then_some(())
                    .ok_or(CommandError::NotAtRest)
            });
            if let Err(e) = ready {
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
                let s = self.settings().with(key, value).map(|s| typed(s, key));
                self.use_settings(s.map_err(|_| CommandError::Invalid)?)
                    .map_err(|e| match e {
                        SettingsError::Blind => CommandError::Blind,
                        _ => CommandError::Invalid,
                    })?;
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
                    zeroed: None,
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
            // A weight pulls: its force is above 0.
            Command::Weigh(_, n) if n.is_nan() || n <= 0.0 => Err(CommandError::Invalid),
            Command::Weigh(ch, n) => self.start_measure(Measuring::Weigh(ch, n), now_us),
            Command::Run if latched => Err(CommandError::FaultLatched),
            Command::Run if self.is_in_setup() => Err(CommandError::NotApplicable),
            Command::Run if self.is_homing() => Err(CommandError::Homing),
            Command::Run if self.cal.unmeasured().is_some() => Err(CommandError::Uncalibrated),
            Command::Run => {
                // Armed only: the drive starts on a press at the rig.
                self.armed_until_us = Some(now_us + ARM_MS as u64 * 1000);
                info!("run armed: press the rig's button to start it");
                Ok([(self.runs + 1) as f32, (ARM_MS / 1000) as f32])
            }
            Command::Ack if self.limp || self.latched_fault().is_some_and(|k| k.needs_press()) => {
                Err(CommandError::NeedsPress)
            }
            Command::Ack if latched => {
                self.acknowledge();
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
        let max_deg = self.cal.servo.max_deg;
        let Phase::Setup { target_deg, .. } = &mut self.phase else {
            return Err(CommandError::NotInSetup);
        };
        let a = servo_range(to(*target_deg), max_deg);
        *target_deg = a;
        Ok([a, 0.0])
    }

    fn start_measure(&mut self, what: Measuring, now_us: u64) -> Result<[f32; 2], CommandError> {
        let period_us = self.period_us;
        let in_force = self.cal.zeros();
        let Phase::Setup {
            measure,
            zeroed,
            origin_us,
            servo_deg,
            target_deg,
            ..
        } = &mut self.phase
        else {
            return Err(CommandError::NotInSetup);
        };
        if measure.is_some() {
            return Err(CommandError::Measuring);
        }
        // The weighed channel's zero in force must be the one measured in this session, and
        // the servo still where it was then.
        if let Measuring::Weigh(ch, _) = what {
            let ch = ch as usize;
            let same = |(z, at): ([f32; 2], f32)| {
                z[ch] == in_force[ch] && *servo_deg == at && *target_deg == at
            };
            if !zeroed.is_some_and(same) {
                return Err(CommandError::NotZeroed);
            }
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
        edge: Edge,
        sink: &mut impl LogSink,
    ) -> Outputs {
        let Phase::Setup {
            mut servo_deg,
            target_deg,
            mut measure,
            mut zeroed,
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
        if edge == Edge::Held {
            return self.setup_fault(Self::held_fault(inp), servo_deg, sink);
        }
        if edge == (Edge::Released { consumed: false }) {
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
            driven: None,
        };
        if let Some(f) = self.supervisor.check(&safety) {
            return self.setup_fault(f, servo_deg, sink);
        }
        if let Some(done) = measure.as_mut().and_then(|m| m.push(now_us, counts_ok)) {
            let what = measure.map(|m| m.what);
            measure = None;
            if self.finish_measure(what, done, sink) {
                zeroed = Some((self.cal.zeros(), servo_deg));
            }
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
            zeroed,
            origin_us,
            next_live_us,
        };
        Outputs {
            servo_deg,
            led: (inp.now_us / 1000 / 250).is_multiple_of(2),
            ..self.safe_outputs()
        }
    }

    /// A finished zero or weigh: put into the calibration (or refused) and replied to; true
    /// when a zero was taken (the servo's position then is where a weigh must be made).
    fn finish_measure(
        &mut self,
        what: Option<Measuring>,
        done: Result<setup::Means, CommandError>,
        sink: &mut impl LogSink,
    ) -> bool {
        let result = match what {
            Some(w) => done.and_then(|m| self.apply_measure(w, m)),
            None => Err(CommandError::NoLoad),
        };
        let kind = match what {
            Some(Measuring::Zero) => CommandKind::Zero,
            _ => CommandKind::Weigh,
        };
        let zero_taken = kind == CommandKind::Zero && result.is_ok();
        self.reply(sink, kind, result);
        zero_taken
    }

    /// A zero or weigh put into the calibration, if the force limits stay visible under the
    /// result (else nothing changes). A zero moves the zeros a run's tare is held to (and a
    /// sensitivity whose zero it moves more than 1 N from the one it was measured at is
    /// unmeasured from then on); a weigh measures the sensitivity at the zero in force.
    fn apply_measure(
        &mut self,
        what: Measuring,
        m: setup::Means,
    ) -> Result<[f32; 2], CommandError> {
        let mut cal = self.cal;
        let values = setup::apply(what, m, &mut cal)?;
        match what {
            Measuring::Zero => {
                cal.t1 = self.cal.t1.rezeroed(cal.t1.zero_counts);
                cal.t2 = self.cal.t2.rezeroed(cal.t2.zero_counts);
            }
            Measuring::Weigh(Channel::T1, _) => cal.t1 = cal.t1.measured(CalSource::Weighed),
            Measuring::Weigh(Channel::T2, _) => cal.t2 = cal.t2.measured(CalSource::Weighed),
        }
        self.limits.visible(&cal).map_err(|_| CommandError::Blind)?;
        // A zero taken under a load hides that load from every force, the over-force check's
        // included: one that moves the zero in force by more than a tare may is refused.
        let moved = |old: &ChannelCal, new: &ChannelCal| {
            (new.zero_counts - old.zero_counts).abs() * old.n_per_count
        };
        if what == Measuring::Zero
            && (moved(&self.cal.t1, &cal.t1) > TARE_MAX_N
                || moved(&self.cal.t2, &cal.t2) > TARE_MAX_N)
        {
            return Err(CommandError::ZeroMoved);
        }
        self.cal = cal;
        self.zeros = cal.zeros();
        Ok(values)
    }

    /// A safety fault in setup mode: logged, latched; the servo goes to rest if that releases,
    /// or stays where it is (jogged beyond rest, to the release side).
    fn setup_fault(&mut self, f: Fault, servo_deg: f32, sink: &mut impl LogSink) -> Outputs {
        warn!("fault {} in setup mode: outputs safe", f.kind);
        self.emit(sink, Record::Fault(f));
        self.interrupt_measure(sink);
        self.phase = Phase::Idle {
            latched: Some(f.kind),
        };
        self.supervisor = Supervisor::new(self.limits);
        self.idle_servo_deg = self.toward_release(servo_deg);
        self.idle_outputs()
    }
}
