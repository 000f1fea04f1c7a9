//! Which numbers of a [`capstan_physics::Model`] a fit may move, and how.
//!
//! A fit works in *internal coordinates* θ (unbounded reals); each free parameter maps θ to its
//! model value through a [`Transform`] (bounds by reparametrisation: `Log` keeps a value
//! positive, `Logistic` keeps it in an interval). A [`ModelSpec`] is a base model, the list of
//! free parameters and, optionally, a per-group random effect added to the internal coordinate
//! of one of them (on a `Log` parameter this is a multiplicative factor exp(u), e.g. a per-cord
//! log-mu offset).
//!
//! * [`param`]: the scalars of a `Model` ([`Param`]) and their transforms ([`Transform`]).
//! * [`spec`]: a model to fit ([`ModelSpec`]): free parameters, random effect, ties.

pub mod param;
pub mod spec;

pub(crate) use param::Role;
pub use param::{Param, Transform};
pub use spec::{FreeParam, ModelSpec, Tie};
