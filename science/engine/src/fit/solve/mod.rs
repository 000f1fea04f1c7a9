//! Least-squares fits driven by the `levenberg-marquardt` crate.
//!
//! * [`FitProblem`]: a [`ModelSpec`] on a set of runs as a `LeastSquaresProblem`: residuals
//!   are predicted − measured T2 (N) on the training rows, plus √λ·u_g for each group's random
//!   effect (penalised least squares: Σr² + λΣu²); the Jacobian is analytic in structure (see
//!   [`super::predict`]).
//! * [`fit_fixed`]: fixed effects only (random effects held at zero).
//! * [`fit_penalised`]: fixed effects and group effects at a given λ.
//! * [`fit_mixed`]: λ = σ²/σ_u² re-estimated (EM / Laplace updates, as for a linear mixed
//!   model with the Jacobian as design), optionally capped so that fixed + edf ≤ a budget.
//! * [`loco`]: leave-one-group-out: refit on the other groups, predict the held-out group with
//!   population values (u = 0).
//! * [`information_criteria`]: AIC/BIC on T2 residuals, n·ln(RSS/n) + 2p / p·ln n.
//! * [`Budget`]: every fit's work budget; a fit that spends it stops and says it did not
//!   converge ([`Fit::converged`], [`Fit::stopped`]).
//!
//! Files: [`problem`] (the least-squares problem), [`result`] (a fitted spec, its counts and
//! information criteria), [`fixed`], [`mixed`] (penalised and mixed fits), [`loco`].

pub mod budget;
pub mod fixed;
pub mod loco;
pub mod mixed;
pub mod problem;
pub mod result;

pub use budget::Budget;
pub use fixed::{fit_fixed, fit_fixed_multistart, fit_fixed_with};
pub use loco::{loco, loco_over, Loco};
pub use mixed::{fit_mixed, fit_mixed_from, fit_penalised, MixedOptions};
pub use problem::FitProblem;
pub use result::{information_criteria, Fit};
