//! The world the planner's campaigns are simulated in: the data's mu and scatter, the thesis
//! rig's noise and sensors, the run protocol; and a design's campaign configuration in it.

use crate::design::Design;
use capstan_engine::diagnose::Diagnosis;
use capstan_physics::{Effect, Model};
use capstan_rig::Protocol;
use capstan_sim::campaign::{CampaignConfig, CampaignError};
use capstan_sim::noise::NoiseProfile;

/// What the simulated campaigns share: the data's mu and scatter, and the protocol.
#[derive(Clone, Debug)]
pub struct World {
    /// Euler-Eytelwein's mu of the data.
    pub mu: f64,
    /// Cord-to-cord scatter of mu, %.
    pub cord_pct: f64,
    /// Run-to-run scatter of mu within cords, %.
    pub run_pct: f64,
    /// The run protocol (dwell, windows, levels).
    pub protocol: Protocol,
}

/// The simulator's configuration of `design` with `effects` planted in `world`.
pub fn campaign(design: &Design, effects: &[Effect], world: &World, seed: u64) -> CampaignConfig {
    let mut cfg = CampaignConfig {
        diameters_mm: design.diameters_mm.clone(),
        wraps_deg: design.wraps_deg.clone(),
        drive_vs: design.drive_v.clone(),
        runs: design.runs_per_cord,
        order: design.order,
        effects: effects.to_vec(),
        model: Model::euler_eytelwein(world.mu),
        protocol: world.protocol,
        seed,
        threads: 1,
        keep_raw: false,
        ..CampaignConfig::default()
    };
    // The planted-truth cases' rig: sensors that read to the ADC's top rail.
    capstan_validation::cases::rail_rig(&mut cfg);
    NoiseProfile::Thesis.apply(&mut cfg);
    cfg.scatter_pct = world.cord_pct;
    cfg.run_scatter_pct = Some(world.run_pct);
    cfg
}

/// The world and design as the simulator takes them, or the plan refused in one sentence: the
/// quantity, its value, the range the simulator takes and what in the data gave it.
pub fn check(design: &Design, world: &World, d: &Diagnosis) -> Result<(), crate::PlanError> {
    let cfg = campaign(design, &[], world, 1);
    match cfg.validate() {
        Ok(()) => Ok(()),
        Err(CampaignError::Bad(what, value, allowed)) => {
            let origin = match what {
                "scatter (%)" => format!(
                    "the cord-to-cord scatter of mu these data show ({:.0} % of their mu {:.4}, \
                     from {} cords): cords this different are not one material on one rig — \
                     check the cord labels, the units and which column is T1",
                    d.scatter.cord_pct, d.baseline.mu, d.design.cords
                ),
                "run scatter (%)" => format!(
                    "the run-to-run scatter of mu within cords these data show ({:.0} % of \
                     their mu {:.4}): runs this different are not repeats of one cord — \
                     check the run labels and the units",
                    d.scatter.run_pct, d.baseline.mu
                ),
                _ => "the design these data describe".to_string(),
            };
            Err(crate::PlanError::OutsideSimulator {
                what,
                value,
                allowed,
                origin,
            })
        }
        Err(e) => Err(crate::PlanError::Design(Box::new(e))),
    }
}
