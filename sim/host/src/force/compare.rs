//! Side by side on the same plant (issue 43, item 4): open loop with Euler-Eytelwein and one
//! mu, open loop with the fitted law, and the fitted law with feedback, on the cord the law
//! was fitted to and on new cords whose mu differs, with contact heating as fitted.

use super::{feedback, run_force, thesis_cord, trace_of, ForceRig};
use crate::run::SetupError;
use capstan_rig::BoardLaw;
use capstan_tracking::{steps, SteadyWindow, StepResponse};

/// What the board is given.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Controller {
    /// Euler-Eytelwein with one mu (the analysis's one-mu fit), no feedback.
    OpenLoopEulerEytelwein(f32),
    /// The fitted law, no feedback.
    OpenLoopFitted,
    /// The fitted law with feedback on T2.
    Feedback,
}

impl Controller {
    /// Its name in tables.
    pub fn name(&self) -> &'static str {
        match self {
            Controller::OpenLoopEulerEytelwein(_) => "open loop, Euler-Eytelwein one mu",
            Controller::OpenLoopFitted => "open loop, fitted law",
            Controller::Feedback => "fitted law + feedback",
        }
    }
}

/// The cord on the rig.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CordCase {
    /// Its mu over the fitted law's (1: the model's own cord).
    pub mu_factor: f64,
    /// Contact heating as fitted (false: none on this cord).
    pub heating: bool,
}

impl CordCase {
    /// Its name in tables.
    pub fn name(&self) -> String {
        let mu = if self.mu_factor == 1.0 {
            "the model's cord".to_string()
        } else {
            format!("mu {:+.0} %", 100.0 * (self.mu_factor - 1.0))
        };
        if self.heating {
            mu
        } else {
            format!("{mu}, no heating")
        }
    }
}

/// One controller on one cord: its response to every step.
#[derive(Clone, Debug)]
pub struct ComparisonRow {
    /// What the board was given.
    pub controller: Controller,
    /// The cord.
    pub cord: CordCase,
    /// Every step of the run.
    pub steps: Vec<StepResponse>,
    /// The run ended without a fault.
    pub clean: bool,
}

impl ComparisonRow {
    /// The largest |steady-state error| over the steps, % of the target.
    pub fn worst_ss_error_pct(&self) -> f64 {
        self.steps
            .iter()
            .map(|s| s.ss_error_pct.abs())
            .fold(0.0, f64::max)
    }

    /// The largest overshoot over the steps, % of the step.
    pub fn worst_overshoot_pct(&self) -> f64 {
        self.steps
            .iter()
            .map(|s| s.overshoot_pct)
            .fold(0.0, f64::max)
    }
}

/// Every controller on every cord.
#[derive(Clone, Debug)]
pub struct Comparison {
    /// In controller-major order.
    pub rows: Vec<ComparisonRow>,
}

/// Run every `controller` on every `cord`, on `base` (its profile, noise and seed).
pub fn compare(
    base: &ForceRig,
    controllers: &[Controller],
    cords: &[CordCase],
) -> Result<Comparison, SetupError> {
    let fitted = base.force.law;
    let window = SteadyWindow {
        after_s: base.protocol.window_after_change_ms as f64 * 1e-3,
        before_s: base.protocol.window_before_next_ms as f64 * 1e-3,
    };
    let mut rows = Vec::new();
    for &controller in controllers {
        for &cord in cords {
            let (law, on) = match controller {
                Controller::OpenLoopEulerEytelwein(mu) => (BoardLaw::euler_eytelwein(mu), false),
                Controller::OpenLoopFitted => (fitted, false),
                Controller::Feedback => (fitted, true),
            };
            let mut model = thesis_cord(cord.mu_factor);
            if !cord.heating {
                model.law.heat_per_ns = 0.0;
            }
            let rig = ForceRig {
                cord: model,
                force: feedback(capstan_rig::ForceConfig { law, ..base.force }, on),
                ..base.clone()
            };
            let out = run_force(&rig)?;
            let clean = matches!(out.end, Ok(e) if e.fault.is_none());
            rows.push(ComparisonRow {
                controller,
                cord,
                steps: steps(&trace_of(&out.log), window),
                clean,
            });
        }
    }
    Ok(Comparison { rows })
}

/// The side-by-side comparison `capstan simulate --mode force --compare` runs (and the docs
/// give): on `base` (its rig, profile, noise and seed), open loop with Euler-Eytelwein and
/// `ee_mu`, open loop with the fitted law and the fitted law with feedback, each on the model's
/// cord, cords whose mu is `pct` % above and below it (heating as fitted) and the model's cord
/// without heating.
pub fn standard(base: &ForceRig, ee_mu: f32, pct: f64) -> Result<Comparison, SetupError> {
    let controllers = [
        Controller::OpenLoopEulerEytelwein(ee_mu),
        Controller::OpenLoopFitted,
        Controller::Feedback,
    ];
    let cords: Vec<CordCase> = [1.0, 1.0 + pct / 100.0, 1.0 - pct / 100.0]
        .iter()
        .map(|&mu_factor| CordCase {
            mu_factor,
            heating: true,
        })
        .chain([CordCase {
            mu_factor: 1.0,
            heating: false,
        }])
        .collect();
    compare(base, &controllers, &cords)
}
