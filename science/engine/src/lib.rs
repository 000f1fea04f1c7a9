//! The evidence engine of the capstan rig's data: which effects a data set holds and how
//! large they are, the models fitted to it, and what they get wrong.
//!
//! * [`fit`]: least squares over the shared friction model ([`capstan_physics::Model`]):
//!   observations, predictions, fixed and mixed fits, small statistics.
//! * [`evidence`]: the engine itself: forward selection of within-run effects, the runs' mu
//!   against the between-cord and between-run covariates, the adequacy checks and the rivals.
//! * [`diagnose`]: the diagnosis (`capstan diagnose`): the engine's assessment as effects found,
//!   a population fit and a verdict in words.
//! * [`analysis`]: the analysis (`capstan analyze`): Euler-Eytelwein, the thesis's Table 3 and
//!   the extended model; their gain, residuals and the mechanisms' verdicts.
//!
//! Nothing here prints; the developer traces go where the program says ([`trace`]).

pub mod analysis;
pub mod diagnose;
pub mod evidence;
pub mod fit;
pub mod text;
pub mod trace;
pub mod verdict;
