//! Force control (issue 43): the capstan as a force amplifier. In force mode a run holds T2 at
//! a target instead of stepping the servo through its angles: the servo command comes from a
//! feedforward through the fitted capstan law (the T1 the law says gives the target) plus
//! feedback on the measured T2 (PI, anti-windup), through a T1 loop that turns the servo at a
//! bounded speed inside its travel.
//!
//! * this file: the settings of force control ([`ForceConfig`]) and their validation;
//! * `law.rs`: the fitted capstan law as the board holds it, and its inverse;
//! * `profile.rs`: the T2 target, segment by segment (steps, a ramp, a stepped sine sweep);
//! * `control.rs`: the control law, a pure `step(state, input) -> (state, output)`;
//! * `run.rs`: a force run's samples: the measurements averaged to the control rate, the
//!   target, the controller (what `rig/run.rs` calls in force mode).
//!
//! A force run is a run: the same press starts it (a button press at the rig, or the host's
//! `run`), the same tare, trigger, amplifier and windows, and the same supervisor checks every
//! sample and ends it with the same safe state. Only the servo's angle comes from here.

mod control;
mod law;
mod profile;
mod run;

pub use capstan_wire::{ControlMode, ForceProfile};
pub use control::{step, Input, Output, Params, State, CONTROL_HZ};
pub use law::BoardLaw;
pub use run::ForceRun;

/// Highest T2 target a setting may ask for, N: the sensors' 50 N less the 45 N over-force
/// limit's margin (the controller also never asks for more than 90 % of the limit in force).
pub const MAX_TARGET_N: f32 = 40.0;
/// Lowest T2 a target may come down to, N: above the cord-break checks' slack threshold, with
/// room for the noise (a sine's trough, a level).
pub const MIN_TARGET_N: f32 = 1.0;
/// Most frequencies of a sine sweep.
pub const MAX_SINE_STEPS: u32 = 16;
/// Highest sine frequency, Hz: 2.5 servo frames (50 Hz) a cycle.
pub const MAX_SINE_HZ: f32 = 20.0;

/// Force control's settings (part of the [`crate::Protocol`]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub struct ForceConfig {
    /// What a run does.
    pub mode: ControlMode,
    /// The T2 target's shape.
    pub profile: ForceProfile,
    /// T2 targets, N (steps: one a segment, a 0 ends the list; ramp: from, to; sine: mean,
    /// amplitude).
    pub levels_n: [f32; 4],
    /// Sine sweep: first frequency, Hz.
    pub sine_hz: f32,
    /// Sine sweep: last frequency, Hz.
    pub sine_to_hz: f32,
    /// Sine sweep: frequencies, one a segment.
    pub sine_steps: u32,
    /// T2 feedback: proportional gain, N of demand per N of error.
    pub kp: f32,
    /// T2 feedback: integral gain, 1/s.
    pub ki: f32,
    /// The T1 loop: servo speed per N of T1 error, deg/s/N.
    pub t1_gain: f32,
    /// Fastest servo command, deg/s.
    pub rate_deg_s: f32,
    /// A jump of the target is shaped over this time constant, ms (0: none).
    pub shape_ms: u32,
    /// The fitted capstan law the feedforward goes through.
    pub law: BoardLaw,
}

impl Default for ForceConfig {
    /// Protocol mode; if switched to force: steps of 5, 10, 20 and 30 N, the gains tuned on the
    /// simulated thesis rig (docs/README-force.md), no model (`capstan rig load-model` sets it).
    fn default() -> Self {
        ForceConfig {
            mode: ControlMode::Protocol,
            profile: ForceProfile::Steps,
            levels_n: [5.0, 10.0, 20.0, 30.0],
            sine_hz: 0.2,
            sine_to_hz: 5.0,
            sine_steps: 8,
            kp: 1.0,
            ki: 5.0,
            t1_gain: 120.0,
            rate_deg_s: 250.0,
            shape_ms: 300,
            law: BoardLaw::NONE,
        }
    }
}

/// Why force control's settings are refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub enum ForceError {
    /// Force mode needs a model: `model_mu` is 0 (`capstan rig load-model`).
    NoModel,
    /// Force mode needs the wrap angle (`wrap_deg`): the law's β.
    NoWrap,
    /// A model parameter is outside what a capstan can have.
    Model,
    /// A T2 target is outside 1..=40 N (0 ends the steps), or the steps are not contiguous.
    Level,
    /// The sine's frequencies or count are outside 0 < first ≤ last ≤ 20 Hz, 1 to 16.
    Sine,
    /// A gain, the servo speed or the shaping time is outside its range.
    Gain,
}

impl ForceError {
    /// What is wrong, for a person.
    pub const fn message(self) -> &'static str {
        match self {
            ForceError::NoModel => "force mode needs a fitted law: capstan rig load-model --from metrics.json (model_mu is 0)",
            ForceError::NoWrap => "force mode needs the wrap angle: set wrap_deg (the law's wrap)",
            ForceError::Model => "a model value is out of range (mu 0 to 2, heat 0 to 1 /N, offset -5 to 5 N, exponent 0.3 to 1)",
            ForceError::Level => "T2 targets must be 1 to 40 N (steps: a 0 ends the list; sine: mean - amplitude >= 1 N, mean + amplitude <= 40 N)",
            ForceError::Sine => "the sine needs 0 < force_sine_hz <= force_sine_to_hz <= 20 Hz and 1 to 16 steps",
            ForceError::Gain => "gains out of range (force_kp 0 to 10, force_ki 0 to 50, force_t1_gain 1 to 2000, force_rate_deg_s 1 to 1000, force_shape_ms at most 10000)",
        }
    }
}

impl core::fmt::Display for ForceError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.message())
    }
}

fn within(v: f32, lo: f32, hi: f32) -> bool {
    v.is_finite() && v >= lo && v <= hi
}

impl ForceConfig {
    /// True in force mode.
    #[inline]
    pub fn is_on(&self) -> bool {
        self.mode == ControlMode::Force
    }

    /// Refuse settings a force run could not use: each value's own range always (so a value
    /// set in protocol mode is already good), and in force mode what it needs to run (a model,
    /// the wrap, a target profile that stays within the rig's forces).
    pub fn validate(&self, wrap_deg: f32) -> Result<(), ForceError> {
        self.law.validate()?;
        let gains_ok = within(self.kp, 0.0, 10.0)
            && within(self.ki, 0.0, 50.0)
            && within(self.t1_gain, 1.0, 2000.0)
            && within(self.rate_deg_s, 1.0, 1000.0)
            && self.shape_ms <= 10_000;
        if !gains_ok {
            return Err(ForceError::Gain);
        }
        if !self
            .levels_n
            .iter()
            .all(|&l| l == 0.0 || within(l, MIN_TARGET_N, MAX_TARGET_N))
        {
            return Err(ForceError::Level);
        }
        if !(self.sine_hz > 0.0
            && self.sine_hz <= self.sine_to_hz
            && self.sine_to_hz <= MAX_SINE_HZ
            && (1..=MAX_SINE_STEPS).contains(&self.sine_steps))
        {
            return Err(ForceError::Sine);
        }
        if !self.is_on() {
            return Ok(());
        }
        if self.law.mu <= 0.0 {
            return Err(ForceError::NoModel);
        }
        if wrap_deg.is_nan() || wrap_deg <= 0.0 {
            return Err(ForceError::NoWrap);
        }
        profile::validate(self)
    }

    /// Segments of a force run (its levels: one per dwell).
    #[inline]
    pub fn segments(&self) -> u32 {
        profile::segments(self)
    }

    /// The T2 target `in_ms` into segment `k` (0: none, at rest), N.
    pub fn target_n(&self, k: u32, in_ms: u32, dwell_ms: u32) -> f32 {
        profile::target_n(self, k, in_ms, dwell_ms)
    }

    /// The target segment `k`'s pair is logged with, `mid_ms` (its window's middle) into it
    /// (0 in protocol mode), N.
    pub fn nominal_n(&self, k: u32, mid_ms: u32, dwell_ms: u32) -> f32 {
        if !self.is_on() {
            return 0.0;
        }
        profile::nominal_n(self, k, mid_ms, dwell_ms)
    }

    /// The frequency of sine segment `k`, Hz (0 for a segment that is not a sine).
    pub fn sine_hz_of(&self, k: u32, dwell_ms: u32) -> f32 {
        profile::sine_hz(self, k, dwell_ms)
    }
}
