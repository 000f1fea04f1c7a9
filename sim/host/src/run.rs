//! One firmware run against the plant: `capstan_rig::run_once` with a `capstan_rig::Rig`, the plant
//! adapters as its hardware and a `Vec` sink, in virtual time, with an optional probe of the
//! plant's true state (also used by the two-control rig).

use crate::setup::OutOfRange;
use crate::time;
use capstan_plant::{
    rig_io_on, CordSetup, Injection, InjectionReport, Plant, PlantConfig, PlantError, ServoEvent,
};
use capstan_rig::record::{Fault, RawSample, RunEnd, RunStart, StepPair};
use capstan_rig::safety::SafetyLimits;
use capstan_rig::{Calibration, LogSink, Protocol, ProtocolError, Record, Rig, RunError};
use core::cell::RefCell;
use embassy_time::{Duration, Ticker};
use std::fmt;

/// Everything one simulated run needs.
#[derive(Clone, Debug)]
pub struct RunSpec {
    /// The rig's constants.
    pub plant: PlantConfig,
    /// The cord: wrap, friction model, repeat run, when the button is pressed.
    pub cord: CordSetup,
    /// The protocol the firmware runs.
    pub protocol: Protocol,
    /// The calibration the firmware starts from (its tare re-zeroes both channels).
    pub calibration: Calibration,
    /// The firmware's safety limits.
    pub limits: SafetyLimits,
    /// Seed of the plant (sensor zeros and noise).
    pub seed: u64,
    /// Faults to inject (on cord 0).
    pub injections: Vec<Injection>,
    /// Keep the decimated raw samples in the log.
    pub keep_raw: bool,
    /// Sample the plant's true state every this many ms into [`RunOutput::trace`] (0 = never).
    pub trace_every_ms: u32,
}

impl Default for RunSpec {
    /// The thesis's run: 360°, mu 0.115, pressed at 10 ms, raw samples kept, no trace.
    fn default() -> Self {
        RunSpec {
            plant: PlantConfig::default(),
            cord: CordSetup::default(),
            protocol: Protocol::default(),
            calibration: crate::setup::typed_calibration(),
            limits: SafetyLimits::default(),
            seed: 1,
            injections: Vec::new(),
            keep_raw: true,
            trace_every_ms: 0,
        }
    }
}

/// The records of one run, as the firmware emitted them (raw samples compact).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunLog {
    /// The run-start record (protocol and the calibration after the tare).
    pub start: Option<RunStart>,
    /// Decimated raw samples, if kept.
    pub raw: Vec<RawSample>,
    /// Conditioned pairs, in step order.
    pub pairs: Vec<StepPair>,
    /// Fault records.
    pub faults: Vec<Fault>,
    /// The run-end record.
    pub end: Option<RunEnd>,
    /// Records emitted.
    pub records: u32,
    /// Sequence numbers were consecutive from the first record.
    pub sequence_ok: bool,
}

/// A `LogSink` into a [`RunLog`].
#[derive(Debug)]
pub struct VecSink {
    /// What was collected.
    pub log: RunLog,
    keep_raw: bool,
    next_seq: Option<u32>,
}

impl VecSink {
    /// An empty sink; raw samples are dropped unless `keep_raw`.
    pub fn new(keep_raw: bool) -> Self {
        VecSink {
            log: RunLog {
                sequence_ok: true,
                ..RunLog::default()
            },
            keep_raw,
            next_seq: None,
        }
    }
}

impl LogSink for VecSink {
    fn emit(&mut self, seq: u32, record: &Record) {
        if self.next_seq.is_some_and(|n| n != seq) {
            self.log.sequence_ok = false;
        }
        self.next_seq = Some(seq.wrapping_add(1));
        self.log.records += 1;
        match record {
            Record::RunStart(s) => self.log.start = Some(*s),
            Record::Raw(r) => {
                if self.keep_raw {
                    self.log.raw.push(*r)
                }
            }
            Record::Pair(p) => self.log.pairs.push(*p),
            Record::Fault(f) => self.log.faults.push(*f),
            Record::RunEnd(e) => self.log.end = Some(*e),
            // Setup mode and host commands: not part of a run.
            Record::Live(_) | Record::Reply(_) | Record::Settings(_) => {}
        }
    }
}

/// The plant's true state at one moment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraceSample {
    /// Plant time, µs.
    pub t_us: u64,
    /// True T1, N.
    pub t1_n: f64,
    /// True T2, N.
    pub t2_n: f64,
    /// Servo angle, deg.
    pub angle_deg: f64,
    /// The servo pulse commanded, µs (0: none).
    pub pulse_us: f64,
    /// Capstan speed, rpm.
    pub capstan_rpm: f64,
    /// The drive motor's voltage (after the amplifier control's RC filter), V.
    pub drive_v: f64,
    /// Drive current, A.
    pub current_a: f64,
}

impl TraceSample {
    /// Cord 0 of `p` now.
    pub fn of(p: &Plant) -> TraceSample {
        let (c, d) = (p.truth(0), p.drive());
        TraceSample {
            t_us: p.now_us(),
            t1_n: c.t1_n,
            t2_n: c.t2_n,
            angle_deg: c.angle_deg,
            pulse_us: c.commanded_pulse_us,
            capstan_rpm: d.capstan_rpm,
            drive_v: d.drive_v,
            current_a: d.current_a,
        }
    }
}

/// How a run went wrong (beyond a fault the firmware handled).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RunFailure {
    /// A HAL call failed (never, with the plant's adapters).
    Hardware(RunError),
    /// The run did not end in time (e.g. the button was never pressed).
    Timeout,
}

/// What one run produced.
#[derive(Clone, Debug)]
pub struct RunOutput {
    /// The firmware's records.
    pub log: RunLog,
    /// How `run_once` returned.
    pub end: Result<RunEnd, RunFailure>,
    /// What became of the injections.
    pub injections: Vec<InjectionReport>,
    /// Servo commands the plant received.
    pub servo_events: Vec<ServoEvent>,
    /// Trigger edges the plant saw (µs, level).
    pub trigger_edges: Vec<(u64, bool)>,
    /// The trigger's first rising edge, µs (the logger's time zero).
    pub trigger_rise_us: Option<u64>,
    /// Since when the rig has been commanding the safe state at the end, µs.
    pub safe_since_us: Option<u64>,
    /// The plant's true state every `trace_every_ms`.
    pub trace: Vec<TraceSample>,
    /// Virtual time simulated, µs.
    pub simulated_us: u64,
    /// Longest gap between watchdog feeds, µs.
    pub max_feed_gap_us: u64,
    /// The sensors' zeros this plant drew (counts), for checking the tare.
    pub sensor_zero_counts: [f64; 2],
}

impl RunOutput {
    /// Pair time (ms since trigger, as in the records) to plant µs.
    pub fn plant_us(&self, since_trigger_us: i64) -> Option<u64> {
        Some((self.trigger_rise_us? as i64 + since_trigger_us) as u64)
    }
}

/// A run that could not be set up.
#[derive(Clone, Debug, PartialEq)]
pub enum SetupError {
    /// The firmware refused the protocol.
    Protocol(ProtocolError),
    /// The plant refused its constants or an injection.
    Plant(PlantError),
    /// A diameter, wrap or drive voltage is out of range ([`crate::setup`]).
    Range(OutOfRange),
}

impl fmt::Display for SetupError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SetupError::Protocol(e) => {
                write!(f, "the firmware refuses the protocol: {e}")
            }
            SetupError::Plant(e) => write!(f, "{e}"),
            SetupError::Range(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for SetupError {}

/// Every `every` of virtual time, bring the plant to the present and hand it to `record`. Never
/// ends: select it against the firmware's runners.
pub(crate) async fn sample_plant(
    plant: &RefCell<Plant>,
    every: Duration,
    mut record: impl FnMut(&Plant),
) {
    let mut t = Ticker::every(every);
    loop {
        t.next().await;
        let mut p = plant.borrow_mut();
        p.advance_to(time::now_us());
        record(&p);
    }
}

/// Longest a run may take in virtual time: the protocol, the press, and 10 s of slack.
pub fn time_limit_us(protocol: &Protocol, cord: &CordSetup) -> u64 {
    let press = cord.press_at_us.unwrap_or(0) + 1_000_000;
    press + protocol.end_ms() as u64 * 1_000 + 10_000_000
}

/// Run the firmware once against a fresh plant, on this thread's virtual clock (reset to 0).
pub fn run(spec: &RunSpec) -> Result<RunOutput, SetupError> {
    time::reset(0);
    let mut rig =
        Rig::new(spec.protocol, spec.calibration, spec.limits).map_err(SetupError::Protocol)?;
    let mut plant =
        Plant::new_at(spec.plant, &[spec.cord], spec.seed, 0).map_err(SetupError::Plant)?;
    for inj in &spec.injections {
        plant.inject(*inj).map_err(SetupError::Plant)?;
    }
    let plant = RefCell::new(plant);
    let mut sink = VecSink::new(spec.keep_raw);
    if spec.keep_raw {
        // The whole run's raw records at once: no regrowth (and copies) of ~300 KiB per run.
        let p = &spec.protocol;
        let raw = p.end_ms() as u64 * p.raw_log_hz as u64 / 1000 + 1;
        sink.log.raw.reserve(raw as usize);
    }
    let limit = time_limit_us(&spec.protocol, &spec.cord);
    let trace = RefCell::new(Vec::new());
    let outcome = time::with_clock(|clock| {
        let mut io = rig_io_on(&plant, 0, clock);
        let runner = capstan_rig::run_once(&mut io, &mut rig, &mut sink);
        if spec.trace_every_ms > 0 {
            let every = Duration::from_millis(spec.trace_every_ms as u64);
            let probe = sample_plant(&plant, every, |p| {
                trace.borrow_mut().push(TraceSample::of(p))
            });
            let both = embassy_futures::select::select(runner, probe);
            time::block_on_until(both, limit).map(|e| match e {
                embassy_futures::select::Either::First(r) => r,
                embassy_futures::select::Either::Second(()) => unreachable!(),
            })
        } else {
            time::block_on_until(runner, limit)
        }
    });
    let end = match outcome {
        Ok(Ok(end)) => Ok(end),
        Ok(Err(e)) => Err(RunFailure::Hardware(e)),
        Err(_) => Err(RunFailure::Timeout),
    };
    let mut p = plant.into_inner();
    p.advance_to(time::now_us());
    Ok(RunOutput {
        log: sink.log,
        end,
        injections: p.injections().to_vec(),
        servo_events: p.servo_events(0).0.to_vec(),
        trigger_edges: p.trigger_edges(0).to_vec(),
        trigger_rise_us: p.trigger_rise_us(0),
        safe_since_us: p.safe_since_us(0),
        trace: trace.into_inner(),
        simulated_us: p.now_us() - p.origin_us(),
        max_feed_gap_us: p.max_feed_gap_us(0),
        sensor_zero_counts: p.sensor_zero_counts(0),
    })
}
