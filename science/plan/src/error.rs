//! Why a plan could not be made, or was stopped.

use capstan_engine::analysis::AnalysisError;
use capstan_sim::campaign::CampaignError;
use capstan_validation::{CaseError, ValidationError};

/// Why [`crate::plan`] returned no plan.
#[derive(Debug, thiserror::Error)]
pub enum PlanError {
    /// `progress` (a signal) asked to stop before every protocol was simulated.
    #[error("stopped before every protocol was simulated")]
    Stopped,
    /// The data describe a world the simulator does not take (a scatter too large ...).
    #[error(
        "cannot plan on these data: the simulated campaigns would need {what} = {value:.4}, but \
         the simulator takes {}; it comes from {origin}",
        allowed.trim_start_matches("must be ")
    )]
    OutsideSimulator {
        /// The simulator's quantity ("scatter (%)").
        what: &'static str,
        /// The value the data give it, in the quantity's unit.
        value: f64,
        /// What the simulator takes ("must be ...").
        allowed: String,
        /// What in the data gave the value, in words.
        origin: String,
    },
    /// The data's design cannot be simulated for another reason.
    #[error("cannot plan on these data: their design cannot be simulated ({0})")]
    Design(Box<CampaignError>),
    /// The data could not be analysed (the cords question).
    #[error("{0}")]
    Analysis(AnalysisError),
    /// A simulated campaign could not be made or diagnosed.
    #[error("{0}")]
    Validation(ValidationError),
    /// A simulated cord set could not be made.
    #[error("{0}")]
    Case(CaseError),
}
