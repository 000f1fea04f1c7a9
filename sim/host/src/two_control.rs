//! Two-control, single-drive (thesis Figs. 57-60): several cords on one capstan, each pulled by
//! its own servo under its own firmware instance, one drive motor whose load is the sum of their
//! friction torques.
//!
//! Every channel runs `capstan_rig::run_once` with its own `Rig`, on the same virtual clock. All
//! buttons are pressed together, so every rig tares with the capstan stopped; a channel's
//! `delay_ms` lengthens its wait before the trigger, so its steps fall between another's (the
//! cross-talk is only readable when one channel steps while the others hold). The amplifier
//! follows the highest control voltage of the rigs.
//!
//! The result is the drive's speed, current and power over time, each channel's true tensions,
//! and, for every servo step of one channel, what the others saw across it: the change of their
//! T2 and of the capstan speed.

mod crosstalk;
mod force;
mod peaks;

pub use crosstalk::CrossTalk;
pub use force::{ForceCrossTalk, TRACKING_WINDOW};
pub use peaks::DrivePeaks;

use crate::run::{self, time_limit_us, RunFailure, RunLog, SetupError, VecSink};
use crate::setup;
use crate::time;
use capstan_physics::Model;
use capstan_plant::{rig_io, CordSetup, Plant, PlantConfig, ServoEvent, MAX_CORDS};
use capstan_rig::record::RunEnd;
use capstan_rig::safety::SafetyLimits;
use capstan_rig::{Calibration, Protocol, Rig, StepOrder};
use core::cell::RefCell;
use embassy_futures::select::{select, Either};
use embassy_time::Duration;

/// One channel: a cord with its own servo and firmware.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChannelSpec {
    /// Wrap of this cord on the shared capstan, deg.
    pub wrap_deg: f64,
    /// Order of its tension levels.
    pub order: StepOrder,
    /// Extra wait before its trigger, ms (shifts its steps relative to the other channels').
    pub delay_ms: u32,
}

/// A two-control (N-control) run. `Default`: the thesis's example, two 720° cords on the
/// 0.5 in capstan at 10 V, channel 1 a monotone staircase, channel 2 a periodic pulse (level 1,
/// level 12, ...) 5 s out of phase.
#[derive(Clone, Debug)]
pub struct TwoControlConfig {
    /// Capstan diameter, mm.
    pub diameter_mm: f64,
    /// Drive voltage, V.
    pub drive_v: f64,
    /// The channels (1 to 4).
    pub channels: Vec<ChannelSpec>,
    /// The friction model of every cord.
    pub model: Model,
    /// The protocol every firmware runs (order and delay per channel).
    pub protocol: Protocol,
    /// The calibration every firmware starts from.
    pub calibration: Calibration,
    /// The safety limits.
    pub limits: SafetyLimits,
    /// The rig's constants (`capstan_diameter_mm` is set from `diameter_mm`).
    pub plant: PlantConfig,
    /// Plant seed.
    pub seed: u64,
    /// Period of the recorded time series, ms.
    pub sample_every_ms: u32,
    /// Sensor noise on.
    pub sensor_noise: bool,
    /// Force control (issue 43): one setting per channel, each run in force mode (its T2
    /// target, gains and law); empty: every channel runs the protocol.
    pub force: Vec<capstan_rig::ForceConfig>,
}

impl Default for TwoControlConfig {
    fn default() -> Self {
        TwoControlConfig {
            diameter_mm: 12.7,
            drive_v: 10.0,
            channels: vec![
                ChannelSpec {
                    wrap_deg: 720.0,
                    order: StepOrder::Monotone,
                    delay_ms: 0,
                },
                ChannelSpec {
                    wrap_deg: 720.0,
                    order: StepOrder::Pulse,
                    delay_ms: 5_000,
                },
            ],
            model: Model::euler_eytelwein(capstan_plant::THESIS_MU),
            protocol: Protocol::default(),
            calibration: crate::setup::typed_calibration(),
            limits: SafetyLimits::default(),
            plant: PlantConfig::default(),
            seed: 1,
            sample_every_ms: 10,
            sensor_noise: true,
            force: Vec::new(),
        }
    }
}

/// One channel's true state in a series row.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChannelSample {
    /// Servo angle, deg.
    pub angle_deg: f64,
    /// True T1, N.
    pub t1_n: f64,
    /// True T2, N.
    pub t2_n: f64,
}

/// The drive and every channel at one moment.
#[derive(Clone, Debug, PartialEq)]
pub struct SeriesRow {
    /// Time since the buttons were pressed, s.
    pub t_s: f64,
    /// Drive voltage, V.
    pub drive_v: f64,
    /// Capstan speed, rpm.
    pub capstan_rpm: f64,
    /// Drive current, A.
    pub current_a: f64,
    /// Electrical power into the drive motor, W.
    pub power_w: f64,
    /// Friction torque of all cords at the capstan, N m.
    pub load_nm: f64,
    /// 1 while the capstan turns; below 1 when stalled (see `capstan_plant::DriveState`).
    pub transmission: f64,
    /// Every channel, in order.
    pub channels: Vec<ChannelSample>,
}
/// One channel's outcome.
#[derive(Clone, Debug)]
pub struct ChannelResult {
    /// Its firmware's records.
    pub log: RunLog,
    /// How its run ended.
    pub end: Result<RunEnd, RunFailure>,
    /// Servo commands its plant side received.
    pub servo_events: Vec<ServoEvent>,
    /// Its trigger's rising edge, plant µs.
    pub trigger_rise_us: Option<u64>,
}

/// What a two-control run produced.
#[derive(Clone, Debug)]
pub struct TwoControlResult {
    /// The drive and the channels every `sample_every_ms`.
    pub series: Vec<SeriesRow>,
    /// The drive's peaks, from the plant every 1 ms whatever `sample_every_ms` is: the
    /// spin-up's inrush, and the peaks while running.
    pub drive: DrivePeaks,
    /// Every (step of one channel, holding other channel) pair (protocol runs: from the servo
    /// steps).
    pub crosstalk: Vec<CrossTalk>,
    /// Force runs: every (target step of one channel, other channel) pair.
    pub force_crosstalk: Vec<ForceCrossTalk>,
    /// Every channel.
    pub channels: Vec<ChannelResult>,
    /// Virtual time simulated, s.
    pub simulated_s: f64,
    /// Wall time, s.
    pub wall_s: f64,
}

impl TwoControlResult {
    /// Highest drive current in the series (its `sample_every_ms` grid), A. The spin-up's
    /// inrush peaks between the samples: [`TwoControlResult::drive`] has it at 1 ms.
    pub fn peak_current_a(&self) -> f64 {
        self.series.iter().map(|r| r.current_a).fold(0.0, f64::max)
    }

    /// Highest drive power in the series, W (see [`TwoControlResult::peak_current_a`]).
    pub fn peak_power_w(&self) -> f64 {
        self.series.iter().map(|r| r.power_w).fold(0.0, f64::max)
    }

    /// Mean drive power while the drive is on, W.
    pub fn mean_power_w(&self) -> f64 {
        let on: Vec<f64> = self
            .series
            .iter()
            .filter(|r| r.drive_v > 0.0)
            .map(|r| r.power_w)
            .collect();
        on.iter().sum::<f64>() / on.len().max(1) as f64
    }

    /// Largest |relative T2 change| any holding channel saw, and the largest |relative speed
    /// change| across another's step (steps with a stopped capstan before them do not count
    /// for the speed).
    pub fn worst_crosstalk(&self) -> (f64, f64) {
        let finite = |x: f64| if x.is_finite() { x.abs() } else { 0.0 };
        self.crosstalk.iter().fold((0.0, 0.0), |(a, b), c| {
            (
                f64::max(a, finite(c.observer_d_t2_rel())),
                f64::max(b, finite(c.d_rpm_rel())),
            )
        })
    }
}

impl TwoControlConfig {
    /// Check the channel count (1 to 4), the diameter, every wrap and the drive voltage (the
    /// same ranges as a campaign's).
    pub fn validate(&self) -> Result<(), SetupError> {
        let n = self.channels.len();
        if n == 0 || n > MAX_CORDS || !(self.force.is_empty() || self.force.len() == n) {
            return Err(SetupError::Plant(capstan_plant::PlantError::CordCount));
        }
        setup::check_diameter(self.diameter_mm).map_err(SetupError::Range)?;
        for ch in &self.channels {
            setup::check_wrap(ch.wrap_deg).map_err(SetupError::Range)?;
        }
        setup::check_drive_v(self.drive_v, &self.calibration).map_err(SetupError::Range)
    }
}

/// Run every channel's firmware on one shared plant.
pub fn run_two_control(cfg: &TwoControlConfig) -> Result<TwoControlResult, SetupError> {
    cfg.validate()?;
    let n = cfg.channels.len();
    let plant_cfg = setup::cord_plant(&cfg.plant, cfg.diameter_mm, cfg.sensor_noise);
    let (mut rigs, cords, limit) = channel_rigs(cfg)?;
    let wall = std::time::Instant::now();
    time::reset(0);
    let plant =
        RefCell::new(Plant::new_at(plant_cfg, &cords, cfg.seed, 0).map_err(SetupError::Plant)?);
    let mut ios: Vec<_> = (0..n).map(|i| rig_io(&plant, i)).collect();
    let mut sinks: Vec<VecSink> = (0..n).map(|_| VecSink::new(true)).collect();
    let series = RefCell::new(Vec::new());
    let peaks = RefCell::new(DrivePeaks::default());
    let every = Duration::from_millis(cfg.sample_every_ms.max(1) as u64);
    let outcome = {
        let runners: Vec<_> = ios
            .iter_mut()
            .zip(rigs.iter_mut())
            .zip(sinks.iter_mut())
            .map(|((io, rig), sink)| capstan_rig::run_once(io, rig, sink))
            .collect();
        let probe = run::sample_plant(&plant, every, |p| {
            series.borrow_mut().push(series_row(p, n));
        });
        let peak_probe = run::sample_plant(&plant, Duration::from_millis(1), |p| {
            peaks.borrow_mut().add(p.now_us() as f64 * 1e-6, &p.drive());
        });
        let probes = select(probe, peak_probe);
        time::block_on_until(select(time::join_all(runners), probes), limit)
    };
    let ends: Vec<Result<RunEnd, RunFailure>> = match outcome {
        Ok(Either::First(v)) => v
            .into_iter()
            .map(|r| r.map_err(RunFailure::Hardware))
            .collect(),
        Ok(Either::Second(_)) => unreachable!("the probes never end"),
        Err(_) => (0..n).map(|_| Err(RunFailure::Timeout)).collect(),
    };
    let mut p = plant.into_inner();
    p.advance_to(time::now_us());
    let series = series.into_inner();
    let channels: Vec<ChannelResult> = sinks
        .into_iter()
        .zip(ends)
        .enumerate()
        .map(|(i, (sink, end))| ChannelResult {
            log: sink.log,
            end,
            servo_events: p.servo_events(i).0.to_vec(),
            trigger_rise_us: p.trigger_rise_us(i),
        })
        .collect();
    let (crosstalk, force_crosstalk) = if cfg.force.is_empty() {
        let c = crosstalk::crosstalk(&series, &channels, &cfg.calibration.servo);
        (c, Vec::new())
    } else {
        (Vec::new(), force::crosstalk(&series, &channels))
    };
    Ok(TwoControlResult {
        series,
        drive: peaks.into_inner(),
        crosstalk,
        force_crosstalk,
        channels,
        simulated_s: (p.now_us() - p.origin_us()) as f64 * 1e-6,
        wall_s: wall.elapsed().as_secs_f64(),
    })
}

/// Each channel's rig (its protocol delayed by the channel's delay) and cord, and the time
/// limit of the longest.
fn channel_rigs(cfg: &TwoControlConfig) -> Result<(Vec<Rig>, Vec<CordSetup>, u64), SetupError> {
    let mut rigs = Vec::with_capacity(cfg.channels.len());
    let mut cords = Vec::with_capacity(cfg.channels.len());
    let mut limit = 0;
    for (i, ch) in cfg.channels.iter().enumerate() {
        let mut protocol = Protocol {
            pre_trigger_ms: cfg.protocol.pre_trigger_ms + ch.delay_ms,
            ..setup::cord_protocol(
                &cfg.protocol,
                &cfg.calibration,
                ch.order,
                cfg.diameter_mm,
                ch.wrap_deg,
                cfg.drive_v,
            )
        };
        if let Some(f) = cfg.force.get(i) {
            protocol.force = capstan_rig::ForceConfig {
                mode: capstan_rig::ControlMode::Force,
                ..*f
            };
        }
        let plant = setup::cord_plant(&cfg.plant, cfg.diameter_mm, cfg.sensor_noise);
        let limits = setup::cord_limits(&cfg.limits, &plant);
        rigs.push(Rig::new(protocol, cfg.calibration, limits).map_err(SetupError::Protocol)?);
        let cord = CordSetup::new(ch.wrap_deg, cfg.model);
        limit = limit.max(time_limit_us(&protocol, &cord));
        cords.push(cord);
    }
    Ok((rigs, cords, limit))
}

/// The drive and every channel's truth now.
fn series_row(p: &Plant, n: usize) -> SeriesRow {
    let d = p.drive();
    let channels = (0..n)
        .map(|i| {
            let c = p.truth(i);
            ChannelSample {
                angle_deg: c.angle_deg,
                t1_n: c.t1_n,
                t2_n: c.t2_n,
            }
        })
        .collect();
    SeriesRow {
        t_s: p.now_us() as f64 * 1e-6,
        drive_v: d.drive_v,
        capstan_rpm: d.capstan_rpm,
        current_a: d.current_a,
        power_w: d.power_w,
        load_nm: d.load_nm,
        transmission: d.transmission,
        channels,
    }
}
