//! Why a planted case could not be simulated or analysed. The cause's text is part of each
//! message (as it was when these were strings), so a message reads the same printed alone or
//! with its causes.

use capstan_engine::analysis::AnalysisError;
use capstan_sim::campaign::CampaignError;

/// Why a case's data set could not be made: the simulator refused it, or its pairs did not
/// go through the CSV schema.
#[derive(Debug, thiserror::Error)]
pub enum CaseError {
    /// The simulator refused the campaign.
    #[error("{0}")]
    Campaign(Box<CampaignError>),
    /// The pairs could not be written as CSV.
    #[error("{0}")]
    Write(std::io::Error),
    /// The CSV written could not be read back.
    #[error("{0}")]
    Read(Box<capstan_data::DataError>),
}

/// Why a validation run stopped.
#[derive(Debug, thiserror::Error)]
pub enum ValidationError {
    /// A case's data set could not be made (`case` names it: "case 17 ...", "cord set ...").
    #[error("{case} does not simulate: {cause}")]
    NotSimulated {
        /// The case, in words.
        case: String,
        /// Why.
        cause: CaseError,
    },
    /// A case's data set could not be made, in the whole-analysis validation.
    #[error("case {case}: {cause}")]
    Case {
        /// The case, in words.
        case: String,
        /// Why.
        cause: CaseError,
    },
    /// A case's data could not be analysed.
    #[error("{0}")]
    Analysis(AnalysisError),
    /// The closed loop's campaign for one cord was refused.
    #[error("closed loop, cord {cord}: {cause:?}")]
    ClosedLoop {
        /// The cord's label.
        cord: String,
        /// Why.
        cause: Box<CampaignError>,
    },
}
