//! Planted truths: generated cases, their scorer, and the validation of the cause-naming.

pub mod cases;
pub mod score;
pub mod validate;
