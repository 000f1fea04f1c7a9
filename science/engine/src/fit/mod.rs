//! Generic fitting machinery over [`capstan_physics::Model`] (used by `analyze`, and meant for
//! `diagnose` too).
//!
//! * [`params`]: which numbers of a `Model` are free ([`Param`]), with bounds by
//!   reparametrisation ([`Transform`]), and an optional per-group random effect ([`ModelSpec`]).
//! * [`obs`]: measured pairs arranged in cords (groups), runs and step timing
//!   ([`Observations`]).
//! * [`predict`]: predictions through `FrictionLaw::t2_n` with the load memory carried along
//!   each run, and their Jacobian.
//! * [`solve`]: the Levenberg-Marquardt problem ([`solve::FitProblem`], a
//!   `levenberg_marquardt::LeastSquaresProblem`), fixed-effects fits, penalised / mixed fits
//!   with the variance ratio re-estimated, leave-one-group-out, information criteria.
//! * [`stats`]: small statistics (mean, variance, median, R², jackknife; regressions with
//!   cluster-robust errors, rank correlation, t and F distributions).
//! * [`par`]: independent fits on a few threads, results in input order.
//!
//! Typical use:
//! ```no_run
//! use capstan_engine::fit::{obs::Observations, params::{ModelSpec, Param}, solve};
//! use capstan_physics::Model;
//! let obs = Observations::from_dataset(&capstan_data::thesis_dataset());
//! let spec = ModelSpec::new("ee", Model::euler_eytelwein(0.115)).free(Param::Mu);
//! let fit = solve::fit_fixed(&spec, &obs, &obs.all_runs(), None);
//! println!("mu = {:.4}, RMSE = {:.3} N", fit.model(None).law.mu, fit.rmse());
//! ```

pub mod obs;
pub mod par;
pub mod params;
pub mod predict;
pub mod solve;
pub mod stats;

pub use obs::Observations;
pub use params::{FreeParam, ModelSpec, Param, Tie, Transform};
