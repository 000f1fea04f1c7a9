//! A bench session on the simulated board: the board's boot (settings from flash, or the
//! defaults, said in a `settings` record), then `firmware::runner::serve` with a host sending
//! command lines, a person hanging known weights and pressing the button, and resets, all on
//! one plant and one flash, in virtual time. It is what `capstan rig --sim` drives and what the
//! setup tests run: the same commands the board takes over RTT.

use crate::flash::RamFlash;
use crate::run::{time_limit_us, SetupError};
use crate::time;
use capstan_plant::{rig_io, CordSetup, Plant, PlantConfig};
use core::cell::RefCell;
use embassy_futures::select::{select, Either};
use embassy_time::{Duration, Timer};
use firmware::hal::{Channel, Console};
use firmware::record::{LogSink, Record};
use firmware::runner::serve;
use firmware::safety::SafetyLimits;
use firmware::store::SettingsStore;
use firmware::{Calibration, Protocol, Rig};
use std::collections::VecDeque;

/// The settings range of the simulated board's flash: all of it (four 4 KiB pages).
pub const FLASH_PAGES: usize = 4;

/// Longest a command may wait for its reply, virtual ms (a store erases pages: well under).
pub const REPLY_TIMEOUT_MS: u64 = 5_000;

/// One thing that happens at the bench.
#[derive(Clone, Debug, PartialEq)]
pub enum Step {
    /// The host sends a command line and waits for its reply.
    Send(String),
    /// Time passes, ms.
    Wait(u32),
    /// A known weight (N) hangs on a sensor from now on (0: nothing hangs there).
    Hang(Channel, f64),
    /// The button is pressed for this long, ms.
    Press(u32),
    /// Wait for the run in progress to end (or for the limit of its protocol).
    UntilRunEnd,
    /// The board resets (power cycle, or the reset button): the flash and the plant stay.
    Reset,
}

/// The simulated bench.
#[derive(Clone, Debug)]
pub struct SessionSpec {
    /// The rig's constants.
    pub plant: PlantConfig,
    /// The cord (its `press_at_us` is ignored: presses are steps).
    pub cord: CordSetup,
    /// The firmware's built-in protocol.
    pub protocol: Protocol,
    /// The firmware's built-in calibration.
    pub calibration: Calibration,
    /// The firmware's safety limits.
    pub limits: SafetyLimits,
    /// Seed of the plant.
    pub seed: u64,
}

impl Default for SessionSpec {
    fn default() -> Self {
        SessionSpec {
            plant: PlantConfig::default(),
            cord: CordSetup::default(),
            protocol: Protocol::default(),
            calibration: Calibration::default(),
            limits: SafetyLimits::default(),
            seed: 1,
        }
    }
}

/// One record as the host received it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Event {
    /// Virtual time, µs since the session began.
    pub t_us: u64,
    /// Boots so far (1 = the first).
    pub boot: u32,
    /// The record's sequence number.
    pub seq: u32,
    /// The record.
    pub record: Record,
}

/// What a session produced.
#[derive(Clone, Debug)]
pub struct SessionOutput {
    /// Every record, in order.
    pub events: Vec<Event>,
    /// The flash afterwards.
    pub flash: RamFlash,
    /// Commands that got no reply in [`REPLY_TIMEOUT_MS`].
    pub unanswered: Vec<String>,
    /// The plant afterwards (its truth, servo events, sensor zeros).
    pub plant: Plant,
}

impl SessionOutput {
    /// The records of one kind, via `pick`.
    pub fn records<T>(&self, pick: impl Fn(&Record) -> Option<T>) -> Vec<T> {
        self.events.iter().filter_map(|e| pick(&e.record)).collect()
    }

    /// The settings report of boot `boot` (1 = the first), if it made one.
    pub fn settings_at_boot(&self, boot: u32) -> Option<firmware::record::SettingsReport> {
        self.events
            .iter()
            .filter(|e| e.boot == boot)
            .find_map(|e| match e.record {
                Record::Settings(s) => Some(s),
                _ => None,
            })
    }
}

/// The records, shared by the board's sink and the host.
struct Shared {
    events: RefCell<Vec<Event>>,
    console: RefCell<VecDeque<u8>>,
    boot: core::cell::Cell<u32>,
}

struct Sink<'a>(&'a Shared);

impl LogSink for Sink<'_> {
    fn emit(&mut self, seq: u32, record: &Record) {
        let boot = self.0.boot.get();
        let e = Event {
            t_us: time::now_us(),
            boot,
            seq,
            record: *record,
        };
        self.0.events.borrow_mut().push(e);
    }
}

struct HostConsole<'a>(&'a Shared);

impl Console for HostConsole<'_> {
    fn read_byte(&mut self) -> Option<u8> {
        self.0.console.borrow_mut().pop_front()
    }
}

/// Run `steps` at the simulated bench with `flash` in the board.
pub fn run_session(
    spec: &SessionSpec,
    flash: RamFlash,
    steps: &[Step],
) -> Result<SessionOutput, SetupError> {
    time::reset(0);
    let cord = CordSetup {
        press_at_us: None,
        ..spec.cord
    };
    let plant = Plant::new_at(spec.plant, &[cord], spec.seed, 0).map_err(SetupError::Plant)?;
    let plant = RefCell::new(plant);
    let shared = Shared {
        events: RefCell::new(Vec::new()),
        console: RefCell::new(VecDeque::new()),
        boot: core::cell::Cell::new(0),
    };
    let range = 0..(FLASH_PAGES * crate::flash::ERASE_BYTES) as u32;
    let mut store = SettingsStore::new(flash, range).expect("whole pages");
    let mut unanswered = Vec::new();
    let run_limit_us = time_limit_us(&spec.protocol, &cord);
    let mut rest = steps;
    loop {
        shared.boot.set(shared.boot.get() + 1);
        shared.console.borrow_mut().clear();
        let mut rig =
            Rig::new(spec.protocol, spec.calibration, spec.limits).map_err(SetupError::Protocol)?;
        let mut sink = Sink(&shared);
        let mut io = rig_io(&plant, 0);
        let board = async {
            store.load_into(&mut rig, &mut sink).await;
            let _ = io.boot(&rig);
            let never = |_: &firmware::rig::Outputs, _: &Rig| None::<()>;
            serve(
                &mut io,
                &mut rig,
                &mut sink,
                &mut HostConsole(&shared),
                &mut store,
                never,
            )
            .await
        };
        let host = host(&shared, &plant, rest, &mut unanswered, run_limit_us);
        let limit = time::now_us() + steps_limit_us(rest, run_limit_us);
        let done = match time::block_on_until(select(board, host), limit) {
            Ok(Either::Second(done)) => done,
            _ => rest.len(),
        };
        rest = &rest[done..];
        if rest.first() == Some(&Step::Reset) {
            rest = &rest[1..];
            continue;
        }
        break;
    }
    let mut plant = plant.into_inner();
    plant.advance_to(time::now_us());
    Ok(SessionOutput {
        events: shared.events.into_inner(),
        flash: store.into_flash(),
        unanswered,
        plant,
    })
}

/// Virtual time the steps may take at most.
fn steps_limit_us(steps: &[Step], run_limit_us: u64) -> u64 {
    let each = |s: &Step| match s {
        Step::Send(_) => REPLY_TIMEOUT_MS * 1000,
        Step::Wait(ms) | Step::Press(ms) => *ms as u64 * 1000,
        Step::UntilRunEnd => run_limit_us,
        _ => 0,
    };
    steps.iter().map(each).sum::<u64>() + 1_000_000
}

/// The person and the host at the bench: do the steps up to a reset; how many were done.
async fn host(
    shared: &Shared,
    plant: &RefCell<Plant>,
    steps: &[Step],
    unanswered: &mut Vec<String>,
    run_limit_us: u64,
) -> usize {
    // Let the board boot and settle (and a homing servo reach rest) first.
    Timer::after(Duration::from_millis(50)).await;
    let mut hung = [0.0f64; 2];
    for (i, step) in steps.iter().enumerate() {
        match step {
            Step::Send(line) => {
                let seen = shared.events.borrow().len();
                shared
                    .console
                    .borrow_mut()
                    .extend(line.bytes().chain([b'\n']));
                let replied = until(shared, seen, REPLY_TIMEOUT_MS * 1000, |r| {
                    matches!(r, Record::Reply(_))
                })
                .await;
                if !replied {
                    unanswered.push(line.clone());
                }
            }
            Step::Wait(ms) => Timer::after(Duration::from_millis(*ms as u64)).await,
            Step::Hang(ch, n) => {
                let k = *ch as usize;
                plant.borrow_mut().hang(0, *ch, n - hung[k]);
                hung[k] = *n;
            }
            Step::Press(ms) => {
                let now = time::now_us();
                plant.borrow_mut().press(0, now, *ms as u64 * 1000);
                Timer::after(Duration::from_millis(*ms as u64)).await;
            }
            Step::UntilRunEnd => {
                let seen = shared.events.borrow().len();
                until(shared, seen, run_limit_us, |r| {
                    matches!(r, Record::RunEnd(_))
                })
                .await;
            }
            Step::Reset => return i,
        }
    }
    steps.len()
}

/// Wait until a record after the first `seen` matches, checking every ms; false at the timeout.
async fn until(
    shared: &Shared,
    seen: usize,
    timeout_us: u64,
    hit: impl Fn(&Record) -> bool,
) -> bool {
    let end = time::now_us() + timeout_us;
    while time::now_us() < end {
        if shared.events.borrow()[seen..]
            .iter()
            .any(|e| hit(&e.record))
        {
            return true;
        }
        Timer::after(Duration::from_millis(1)).await;
    }
    false
}
