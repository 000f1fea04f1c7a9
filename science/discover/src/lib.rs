//! `capstan discover`: extend the model beyond the catalogue. After the evidence engine's
//! catalogue selection, search a library of physically meaningful terms ([`library`]) for what
//! is left, each added to the catalogue or in the place of one of its within-run effects
//! ([`joint`]), and propose a term only when it earns its evidence (the engine's statistics and
//! thresholds, plus a penalty for every model the search tries: extended BIC, γ = 1), explains
//! what the replicate runs share ([`replicate`]: not the run-to-run wander of mu), is stable
//! when whole cords are resampled, helps held-out cords, and resolves the lack of fit the
//! catalogue left; otherwise say "nothing in the library explains it", with the residual
//! pattern.
//!
//! The search is linearised about the catalogue fit ([`columns`]): every term is one
//! parameter θ, θ = 0 is the catalogue model, and its column ∂T2/∂θ at θ = 0 enters the
//! engine's within-run least squares (every run its own mu) as one more parameter
//! ([`screen`]). Terms on mu that are constant inside runs are tested where they vary, on the
//! runs' mu between cords or runs. The held-out check is [`heldout`], stability [`stability`].
//! `docs/README-discover.md` states the algorithm, its grammar and its validation.

mod answer;
mod centred;
mod checks;
pub mod columns;
pub mod heldout;
pub mod joint;
pub mod library;
mod model;
pub mod profile;
pub mod replicate;
mod reselect;
pub mod screen;
pub mod stability;
mod verdict;

pub use answer::{DataInfo, Declined, Discovery, NotTestable, Proposed, Rival, ScreenRow, Search};
pub use verdict::{discover, discover_assessed, Options};
