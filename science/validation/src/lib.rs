//! The analysis held against the firmware-in-the-loop simulator (`host-sim`): the one place
//! where the evidence engine meets simulated data.
//!
//! * [`cases`]: data sets with planted truths (catalogue effects, or physics outside the
//!   catalogue), made end to end by the simulator with the thesis rig's noise;
//! * [`score`]: the one planted-truth scorer: an answer on those cases against the truth (the
//!   diagnose suite, the calibration, the benchmark and `--validate`), with its acceptance
//!   [`figures`];
//! * [`validate`]: the cause-naming of `capstan analyze` on planted truths (`--validate`);
//! * [`closed_loop`]: the firmware run against the simulated plant with the fitted extended
//!   model, for the report;
//! * [`pairs`]: the simulator's rows as pairs of the data schema (`capstan simulate`'s
//!   `pairs.csv`, and what the cases read back).

pub mod cases;
pub mod closed_loop;
pub mod cord_bounds;
pub mod cord_calibration;
pub mod cord_cases;
pub mod discover_cases;
pub mod error;
pub mod figures;
pub mod pairs;
pub mod score;
pub mod validate;

pub use error::{CaseError, ValidationError};
