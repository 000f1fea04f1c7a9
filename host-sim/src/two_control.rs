//! Two-control, single-drive (thesis Figs. 57-60): several cords on one capstan, each pulled by
//! its own servo under its own firmware instance, one drive motor whose load is the sum of their
//! friction torques.
//!
//! Every channel runs `firmware::run_once` with its own `Rig`, on the same virtual clock. All
//! buttons are pressed together, so every rig tares with the capstan stopped; a channel's
//! `delay_ms` lengthens its wait before the trigger, so its steps fall between another's (the
//! cross-talk is only readable when one channel steps while the others hold). The amplifier
//! follows the highest control voltage of the rigs.
//!
//! The result is the drive's speed, current and power over time, each channel's true tensions,
//! and, for every servo step of one channel, what the others saw across it: the change of their
//! T2 and of the capstan speed.

use crate::run::{time_limit_us, RunFailure, RunLog, SetupError, VecSink};
use crate::time;
use capstan_friction::Model;
use capstan_plant::{rig_io, CordSetup, Plant, PlantConfig, ServoEvent, MAX_CORDS};
use core::cell::RefCell;
use embassy_futures::select::{select, Either};
use embassy_time::{Duration, Ticker};
use firmware::record::RunEnd;
use firmware::safety::SafetyLimits;
use firmware::{Calibration, Protocol, Rig, StepOrder};
use std::future::{poll_fn, Future};
use std::pin::Pin;
use std::task::Poll;

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
            calibration: Calibration::default(),
            limits: SafetyLimits::default(),
            plant: PlantConfig::default(),
            seed: 1,
            sample_every_ms: 10,
            sensor_noise: true,
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

/// What one channel saw while another stepped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CrossTalk {
    /// The channel that stepped (0-based).
    pub stepping: usize,
    /// When its servo command changed, s since the press.
    pub t_s: f64,
    /// Its commanded angle before and after, deg.
    pub from_deg: f64,
    /// See `from_deg`.
    pub to_deg: f64,
    /// The stepping channel's own T2 change, N.
    pub stepping_d_t2_n: f64,
    /// The channel that held (0-based).
    pub observer: usize,
    /// Its mean T2 over [t − 1 s, t − 50 ms), N.
    pub observer_t2_before_n: f64,
    /// Its mean T2 over [t + 0.5 s, t + 1.5 s), N.
    pub observer_t2_after_n: f64,
    /// Capstan speed over the same windows, rpm.
    pub rpm_before: f64,
    /// See `rpm_before`.
    pub rpm_after: f64,
    /// Drive current over the same windows, A.
    pub current_before_a: f64,
    /// See `current_before_a`.
    pub current_after_a: f64,
}

impl CrossTalk {
    /// The observer's T2 change, as a fraction of its T2 before.
    pub fn observer_d_t2_rel(&self) -> f64 {
        (self.observer_t2_after_n - self.observer_t2_before_n) / self.observer_t2_before_n
    }

    /// The capstan speed change, as a fraction.
    pub fn d_rpm_rel(&self) -> f64 {
        (self.rpm_after - self.rpm_before) / self.rpm_before
    }
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
    /// Every (step of one channel, holding other channel) pair.
    pub crosstalk: Vec<CrossTalk>,
    /// Every channel.
    pub channels: Vec<ChannelResult>,
    /// Virtual time simulated, s.
    pub simulated_s: f64,
    /// Wall time, s.
    pub wall_s: f64,
}

impl TwoControlResult {
    /// Highest drive current, A.
    pub fn peak_current_a(&self) -> f64 {
        self.series.iter().map(|r| r.current_a).fold(0.0, f64::max)
    }

    /// Highest drive power, W.
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

/// Poll every future to completion; outputs in the same order.
async fn join_all<F: Future>(futs: Vec<F>) -> Vec<F::Output> {
    let mut futs: Vec<Pin<Box<F>>> = futs.into_iter().map(Box::pin).collect();
    let mut outs: Vec<Option<F::Output>> = futs.iter().map(|_| None).collect();
    poll_fn(move |cx| {
        for (f, o) in futs.iter_mut().zip(outs.iter_mut()) {
            if o.is_none() {
                if let Poll::Ready(v) = f.as_mut().poll(cx) {
                    *o = Some(v);
                }
            }
        }
        if outs.iter().all(Option::is_some) {
            Poll::Ready(outs.iter_mut().map(|o| o.take().unwrap()).collect())
        } else {
            Poll::Pending
        }
    })
    .await
}

fn mean_over(series: &[SeriesRow], a_s: f64, b_s: f64, f: impl Fn(&SeriesRow) -> f64) -> f64 {
    let v: Vec<f64> = series
        .iter()
        .filter(|r| r.t_s >= a_s && r.t_s < b_s)
        .map(f)
        .collect();
    if v.is_empty() {
        f64::NAN
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

/// Run every channel's firmware on one shared plant.
pub fn run_two_control(cfg: &TwoControlConfig) -> Result<TwoControlResult, SetupError> {
    let n = cfg.channels.len();
    if n == 0 || n > MAX_CORDS {
        return Err(SetupError::Plant(capstan_plant::PlantError::CordCount));
    }
    let gain = cfg.calibration.amp.amp_gain as f64;
    let mut plant_cfg = cfg.plant;
    plant_cfg.capstan_diameter_mm = cfg.diameter_mm;
    if !cfg.sensor_noise {
        plant_cfg.sensor.noise_sd_n = 0.0;
    }
    let mut rigs = Vec::with_capacity(n);
    let mut cords = Vec::with_capacity(n);
    let mut limit = 0;
    for ch in &cfg.channels {
        let protocol = Protocol {
            order: ch.order,
            pre_trigger_ms: cfg.protocol.pre_trigger_ms + ch.delay_ms,
            amp_control_v: (cfg.drive_v / gain) as f32,
            capstan_diameter_mm: cfg.diameter_mm as f32,
            wrap_deg: ch.wrap_deg as f32,
            ..cfg.protocol
        };
        rigs.push(Rig::new(protocol, cfg.calibration, cfg.limits).map_err(SetupError::Protocol)?);
        let cord = CordSetup::new(ch.wrap_deg, cfg.model);
        limit = limit.max(time_limit_us(&protocol, &cord));
        cords.push(cord);
    }
    let wall = std::time::Instant::now();
    time::reset(0);
    let plant =
        RefCell::new(Plant::new_at(plant_cfg, &cords, cfg.seed, 0).map_err(SetupError::Plant)?);
    let mut ios: Vec<_> = (0..n).map(|i| rig_io(&plant, i)).collect();
    let mut sinks: Vec<VecSink> = (0..n).map(|_| VecSink::new(true)).collect();
    let series = RefCell::new(Vec::new());
    let every = Duration::from_millis(cfg.sample_every_ms.max(1) as u64);
    let outcome = {
        let runners: Vec<_> = ios
            .iter_mut()
            .zip(rigs.iter_mut())
            .zip(sinks.iter_mut())
            .map(|((io, rig), sink)| firmware::run_once(io, rig, sink))
            .collect();
        let probe = async {
            let mut t = Ticker::every(every);
            loop {
                t.next().await;
                let mut p = plant.borrow_mut();
                p.advance_to(time::now_us());
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
                series.borrow_mut().push(SeriesRow {
                    t_s: p.now_us() as f64 * 1e-6,
                    drive_v: d.drive_v,
                    capstan_rpm: d.capstan_rpm,
                    current_a: d.current_a,
                    power_w: d.power_w,
                    load_nm: d.load_nm,
                    transmission: d.transmission,
                    channels,
                });
            }
        };
        time::block_on_until(select(join_all(runners), probe), limit)
    };
    let ends: Vec<Result<RunEnd, RunFailure>> = match outcome {
        Ok(Either::First(v)) => v
            .into_iter()
            .map(|r| r.map_err(RunFailure::Hardware))
            .collect(),
        Ok(Either::Second(())) => unreachable!("the probe never ends"),
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
    let crosstalk = crosstalk(&series, &channels);
    Ok(TwoControlResult {
        series,
        crosstalk,
        channels,
        simulated_s: (p.now_us() - p.origin_us()) as f64 * 1e-6,
        wall_s: wall.elapsed().as_secs_f64(),
    })
}

fn crosstalk(series: &[SeriesRow], channels: &[ChannelResult]) -> Vec<CrossTalk> {
    let mut out = Vec::new();
    for (j, ch) in channels.iter().enumerate() {
        for w in ch.servo_events.windows(2) {
            let (prev, ev) = (w[0], w[1]);
            let t = ev.t_us as f64 * 1e-6;
            let mean = |a: f64, b: f64, f: &dyn Fn(&SeriesRow) -> f64| mean_over(series, a, b, f);
            let own = mean(t + 0.5, t + 1.5, &|r| r.channels[j].t2_n)
                - mean(t - 1.0, t - 0.05, &|r| r.channels[j].t2_n);
            for (i, other) in channels.iter().enumerate() {
                if i == j {
                    continue;
                }
                let busy = other.servo_events.iter().skip(1).any(|e| {
                    let te = e.t_us as f64 * 1e-6;
                    te > t - 1.0 && te < t + 1.5
                });
                if busy {
                    continue;
                }
                let before = (t - 1.0, t - 0.05);
                let after = (t + 0.5, t + 1.5);
                let c = CrossTalk {
                    stepping: j,
                    t_s: t,
                    from_deg: prev.angle_deg,
                    to_deg: ev.angle_deg,
                    stepping_d_t2_n: own,
                    observer: i,
                    observer_t2_before_n: mean(before.0, before.1, &|r| r.channels[i].t2_n),
                    observer_t2_after_n: mean(after.0, after.1, &|r| r.channels[i].t2_n),
                    rpm_before: mean(before.0, before.1, &|r| r.capstan_rpm),
                    rpm_after: mean(after.0, after.1, &|r| r.capstan_rpm),
                    current_before_a: mean(before.0, before.1, &|r| r.current_a),
                    current_after_a: mean(after.0, after.1, &|r| r.current_a),
                };
                if c.observer_t2_before_n.is_finite() && c.observer_t2_after_n.is_finite() {
                    out.push(c);
                }
            }
        }
    }
    out.sort_by(|a, b| a.t_s.total_cmp(&b.t_s).then(a.observer.cmp(&b.observer)));
    out
}
