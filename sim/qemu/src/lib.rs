//! What the emulated-ARM firmware does, as one async function over the rig core and the
//! simulated plant: [`scenario`]. The firmware image (`src/main.rs`, thumbv7m-none-eabi under
//! QEMU) runs it with the defmt sink; the host test `tests/log_qemu.rs` runs the same runs
//! ([`RUNS`], [`protocol`], [`plant_config`], [`cords`], [`calibration`], [`limits`]: taken
//! from here) with host-sim and compares them with what `capstan log` decoded from QEMU. One
//! definition, so the two cannot drift.
//!
//! QEMU can run in real time, so the protocol is short: three levels of 600 ms. Two runs: a
//! clean one (2.8 s) and one that an injected snag ends with an over-force fault (1.7 s).
//!
//! Timing contract (what makes the two executions sample the plant at the same instants): each
//! plant's clock starts at a timer deadline [`SETUP_MS`] ahead, and `capstan_rig::run_once` is
//! entered when that deadline wakes the task, with nothing awaited in between, so the rig
//! samples at plant origin + k ms, k = 1, 2, ... on both.
#![no_std]

use capstan_physics::Model;
use capstan_plant::THESIS_MU;
use capstan_plant::{rig_io, CordSetup, Injection, InjectionKind, Plant, PlantConfig, PlantError};
use capstan_rig::record::{LogSink, RunEnd};
use capstan_rig::safety::SafetyLimits;
use capstan_rig::{run_once, Calibration, Protocol, ProtocolError, Rig, RunError, StepOrder};
use core::cell::RefCell;

/// Seed of the simulated plant's noise (run 1; run 2's plant uses `SEED + 1`).
pub const SEED: u64 = 0x6361_7073_7461_6e06;

/// Time allowed for making a plant before its clock starts, ms.
pub const SETUP_MS: u64 = 20;

/// When the snag of run 2 happens, µs after its trigger (during step 2).
pub const SNAG_AFTER_TRIGGER_US: u64 = 1_300_000;

/// The QEMU end-to-end protocol: the thesis's, scaled down to 2.8 s (three levels).
pub fn protocol() -> Protocol {
    Protocol {
        rest_deg: 125.0,
        step_deg: 5.0,
        final_deg: 110.0,
        order: StepOrder::Monotone,
        dwell_ms: 600,
        pre_trigger_ms: 300,
        trigger_ms: 100,
        tare_ms: 200,
        amp_control_v: 2.5,
        sample_hz: 1_000,
        raw_log_hz: 50,
        window_after_change_ms: 200,
        window_before_next_ms: 100,
        capstan_diameter_mm: 12.7,
        wrap_deg: 360.0,
        force: capstan_rig::ForceConfig::default(),
    }
}

/// The simulated rig: the thesis's (0.5 in capstan, default cord, motor and sensors).
pub fn plant_config() -> PlantConfig {
    PlantConfig::default()
}

/// One cord at 360° with Euler-Eytelwein at the thesis's mu; the operator presses the button
/// 10 ms after the plant is made, for 200 ms.
pub fn cords() -> [CordSetup; 1] {
    [CordSetup::new(360.0, Model::euler_eytelwein(THESIS_MU))]
}

/// The calibration the rig starts from (the tare then re-zeroes both channels): the built-in
/// sensitivities, typed (a placeholder nobody measured would never run).
pub fn calibration() -> Calibration {
    Calibration::default().typed()
}

/// The safety limits in force.
pub fn limits() -> SafetyLimits {
    SafetyLimits::default()
}

/// Why the scenario could not run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ScenarioError {
    /// The plant refused its configuration.
    Plant(PlantError),
    /// The rig refused the protocol.
    Protocol(ProtocolError),
    /// A run failed on a hardware error.
    Run(RunError),
}

/// One run of the scenario: the plant's seed and the fault injected into it, if any.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunPlan {
    /// Seed of this run's plant.
    pub seed: u64,
    /// A fault the plant suffers during the run.
    pub injection: Option<Injection>,
}

/// The scenario's runs, in order:
///
/// 1. a clean run of [`protocol`] on a fresh plant (seed [`SEED`]);
/// 2. a run on a fresh plant (seed `SEED + 1`: a new cord) in which the cord snags
///    [`SNAG_AFTER_TRIGGER_US`] after the trigger: T2 jumps over the force limit and the rig
///    stops with an over-force fault.
pub const RUNS: [RunPlan; 2] = [
    RunPlan {
        seed: SEED,
        injection: None,
    },
    RunPlan {
        seed: SEED + 1,
        injection: Some(Injection {
            kind: InjectionKind::OverForce,
            cord: 0,
            after_trigger_us: SNAG_AFTER_TRIGGER_US,
        }),
    },
];

/// The whole scenario: every run of [`RUNS`] on one rig (so run numbers and sequence numbers
/// continue), each on its own fresh plant whose operator presses the button 10 ms after the
/// plant's clock starts. Returns each run's end.
pub async fn scenario(sink: &mut impl LogSink) -> Result<[RunEnd; 2], ScenarioError> {
    let mut rig = Rig::new(protocol(), calibration(), limits()).map_err(ScenarioError::Protocol)?;
    let first = one_run(&mut rig, &RUNS[0], sink).await?;
    let second = one_run(&mut rig, &RUNS[1], sink).await?;
    Ok([first, second])
}

async fn one_run(
    rig: &mut Rig,
    plan: &RunPlan,
    sink: &mut impl LogSink,
) -> Result<RunEnd, ScenarioError> {
    // The plant's clock starts at a tick boundary a little ahead; the rig starts right when
    // that tick wakes it, however long making the plant took (QEMU translates all the plant's
    // code on its first run).
    let origin = embassy_time::Instant::now() + embassy_time::Duration::from_millis(SETUP_MS);
    // A `Plant` is ~5.5 KiB. Bound as the `Result` the helper returns, it lands straight in
    // this future (the call's return slot is the future's own field). `RefCell::new(...?)`
    // here instead moved it through two stack temporaries in this poll function and kept a
    // second copy in the future (measured: poll frame 11.4 KiB instead of 124 bytes, the task
    // 11.8 KiB instead of 6.2 KiB).
    let made = make_plant(plan.seed, origin.as_micros());
    let plant = made.as_ref().map_err(|e| ScenarioError::Plant(*e))?;
    if let Some(i) = plan.injection {
        plant.borrow_mut().inject(i).map_err(ScenarioError::Plant)?;
    }
    embassy_time::Timer::at(origin).await;
    let mut io = rig_io(plant, 0);
    run_once(&mut io, rig, sink)
        .await
        .map_err(ScenarioError::Run)
}

/// This scenario's plant, whose clock starts at `origin_us`, ready to be shared with the rig's
/// I/O. Not inlined, so that its temporaries (`Plant::new_at`'s result and the `RefCell`
/// before it is returned: 11.4 KiB of frame, LLVM does not merge them) live only while the
/// plant is made, not in the poll function's frame for the whole run.
#[inline(never)]
fn make_plant(seed: u64, origin_us: u64) -> Result<RefCell<Plant>, PlantError> {
    Plant::new_at(plant_config(), &cords(), seed, origin_us).map(RefCell::new)
}
