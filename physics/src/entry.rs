//! What the project knows about one catalogue effect, as plain data: the shape of an entry of
//! [`crate::CATALOGUE`].
//!
//! The simulated plant, the evidence engine, the fitter, the verdicts, the case generators and
//! the report read these fields; none of them matches on [`crate::EffectKind`]. Where the
//! behaviour of effects differs, an entry holds a function pointer; where it is a choice among
//! a few known forms (how θ maps to the value, which closed-form partial of the law applies),
//! a small enum. No allocation: the entries live in the plant on the firmware target too.

use crate::math::{exp, log};
use crate::{EffectKind, Model, Operating};

/// Where in the data an effect shows, and so against which scatter it is judged.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Level {
    /// The shape of T2 against T1, time and wrap inside runs (every run has its own mu).
    WithinRun,
    /// The runs' mu against a covariate that varies between cords (cord scatter as error).
    BetweenCord,
    /// The runs' mu against the run number within cords (run scatter as error).
    BetweenRun,
}

/// What a data set's design offers, for an effect's testability, the range of its parameter
/// and its region of practical equivalence. The engine fills it from its design.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Facts {
    /// Distinct wraps.
    pub wraps: usize,
    /// Distinct capstan diameters.
    pub diameters: usize,
    /// Distinct drive voltages.
    pub voltages: usize,
    /// Cords (wrap × diameter × voltage × label groups).
    pub cords: usize,
    /// Runs.
    pub runs: usize,
    /// The most runs any cord has.
    pub max_runs_per_cord: usize,
    /// The largest spread of time within a run, s.
    pub max_time_spread_s: f64,
    /// The latest time of any row (at least 1 s), s.
    pub latest_time_s: f64,
    /// The span of the run numbers (last − first).
    pub run_span: f64,
    /// The span of the capstan diameters, mm.
    pub diameter_span_mm: f64,
    /// The span of the drive voltages, V.
    pub voltage_span_v: f64,
    /// The largest friction load T2 − T1 of any row (at least 0), N.
    pub max_load_n: f64,
    /// The largest wrap, rad.
    pub max_wrap_rad: f64,
}

/// 0.01 over a span (a 1 % change of mu across it), infinite when the span is zero.
pub fn one_percent_over(span: f64) -> f64 {
    if span > 0.0 {
        0.01 / span
    } else {
        f64::INFINITY
    }
}

/// How the fitted internal coordinate θ of a within-run effect maps to its catalogue value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scale {
    /// value = θ.
    Identity,
    /// value = θ² (θ = √value ≥ 0: smooth where the effect grows as √value, as a lift-off
    /// grows with √B).
    Square,
}

/// θ of a within-run effect: its range, its forward-difference step and its start values.
#[derive(Clone, Copy, Debug)]
pub struct Theta {
    /// θ's range on a data set: the effect's physical range.
    pub bounds: fn(&Facts) -> (f64, f64),
    /// θ → value.
    pub scale: Scale,
    /// Forward-difference step of θ.
    pub step: f64,
    /// Start values (catalogue values; several where the fit has more than one basin; none:
    /// the neutral value).
    pub starts: &'static [f64],
}

/// Which closed-form partial of the law ([`crate::FrictionLaw::partials_at`]) a within-run
/// effect's θ moves; `None` in an entry: the engine takes differences.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Partial {
    /// The tension exponent n.
    Exponent,
    /// √B, the bending stiffness's root.
    SqrtB,
    /// The T1 zero offset (shifts the true T1).
    T1Offset,
    /// The T2 zero offset (adds to the measured T2).
    T2Offset,
    /// The drift of mu with time.
    Drift,
    /// Contact heating, with the catalogue's load memory ([`crate::HEAT_TAU_S`]).
    Heating,
}

/// How a between-cord effect's slope of the cords' mu on its covariate becomes its value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Slope {
    /// value = slope / intercept: a fractional change of mu per unit of the covariate.
    Relative,
    /// value = e^slope (a T2 gain g adds ln g/β to the apparent mu).
    Exp,
}

/// A between-cord effect: the cords' mu regressed on a covariate of the cord.
#[derive(Clone, Copy, Debug)]
pub struct CordTest {
    /// The covariate at a cord's operating point (wrap, diameter, voltage).
    pub covariate: fn(&Operating) -> f64,
    /// Slope → value.
    pub slope: Slope,
}

/// The form of the parameter in a fit of the population model: the map from the fitter's
/// internal coordinate θ (any real) to the model value (bounds by reparametrisation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Transform {
    /// Unbounded: value = θ.
    Identity,
    /// Positive (fitted on the log scale): value = exp(θ).
    Log,
    /// Inside (lo, hi): value = lo + (hi − lo)/(1 + exp(−θ)).
    Logistic {
        /// Lower bound.
        lo: f64,
        /// Upper bound.
        hi: f64,
    },
}

impl Transform {
    /// Model value of θ.
    pub fn value(self, theta: f64) -> f64 {
        match self {
            Transform::Identity => theta,
            Transform::Log => exp(theta),
            Transform::Logistic { lo, hi } => lo + (hi - lo) / (1.0 + exp(-theta)),
        }
    }

    /// d value / d θ.
    pub fn derivative(self, theta: f64) -> f64 {
        match self {
            Transform::Identity => 1.0,
            Transform::Log => exp(theta),
            Transform::Logistic { lo, hi } => {
                let s = 1.0 / (1.0 + exp(-theta));
                (hi - lo) * s * (1.0 - s)
            }
        }
    }

    /// θ of a model value (clamped into the transform's range).
    pub fn internal(self, value: f64) -> f64 {
        match self {
            Transform::Identity => value,
            Transform::Log => log(value.max(1e-300)),
            Transform::Logistic { lo, hi } => {
                let s = ((value - lo) / (hi - lo)).clamp(1e-12, 1.0 - 1e-12);
                log(s / (1.0 - s))
            }
        }
    }
}

/// How an effect enters the population model the analysis fits.
#[derive(Clone, Copy, Debug)]
pub struct Population {
    /// The model scalar it moves (the fitter's parameter name, e.g. `heat_per_ns`).
    pub scalar: &'static str,
    /// The catalogue value per unit of the scalar (contact heating: τ, its value being h·τ).
    pub value_per_scalar: f64,
    /// Its transform in the population fit.
    pub transform: Transform,
    /// The smallest value the population model takes it at, if any.
    pub floor: Option<f64>,
}

/// The span of the design a case's size is spread over.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Span {
    /// None (the size is the value).
    One,
    /// A run's time, in 100 s.
    Time100s,
    /// The runs (runs − 1).
    Runs,
    /// The diameters, mm.
    Diameters,
    /// The drive voltages, V.
    Voltages,
}

/// What a generated case planting this effect needs of its design.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CaseDesign {
    /// Wraps from 270° to 720°.
    pub wide_wraps: bool,
    /// Two or three drive voltages.
    pub voltages: bool,
    /// Two diameters.
    pub diameters: bool,
    /// At least this many runs per cord.
    pub min_runs: u32,
}

/// How the generated cases draw this effect's size.
#[derive(Clone, Copy, Debug)]
pub struct Cases {
    /// The range of the drawn change at a size that matters.
    pub care: (f64, f64),
    /// The range of the drawn change for the small class (below it).
    pub small: (f64, f64),
    /// The change takes a random sign.
    pub signed: bool,
    /// The change (signed) and the design's span → the value.
    pub value: fn(f64, f64) -> f64,
    /// The span.
    pub span: Span,
    /// What the design needs.
    pub design: CaseDesign,
}

/// Everything the project knows about one effect of the catalogue.
///
/// The entry is the effect: its name on the command line, its unit, where in the data it
/// shows, and the functions that switch it on in a model and read it back.
///
/// ```
/// use capstan_physics::{Effect, EffectKind, Level, Model, Operating};
///
/// let entry = EffectKind::T2Offset.entry();
/// assert_eq!((entry.name, entry.parameter, entry.unit), ("t2_offset", Some("offset_n"), "N"));
/// assert_eq!(entry.level, Level::WithinRun);
///
/// // `capstan simulate --effect t2_offset=-0.5` parses the same words.
/// let effect: Effect = "t2_offset=-0.5".parse().unwrap();
/// let clean = Model::euler_eytelwein(0.12);
/// let offset = clean.with_effect(effect);
/// assert_eq!((entry.read)(&offset), -0.5);
/// assert_eq!((entry.read)(&clean), entry.neutral);
///
/// // The T2 sensor now reads half a newton low at every tension: a zero offset.
/// let op = Operating::from_wrap_deg(360.0);
/// for t1_n in [0.5, 5.0, 20.0] {
///     let shift_n = offset.predict_t2_n(t1_n, &op) - clean.predict_t2_n(t1_n, &op);
///     assert!((shift_n + 0.5).abs() < 1e-12);
/// }
///
/// // A size outside what a real rig can hold is refused, with the entry's range.
/// let (lo, hi) = entry.physical;
/// assert!(lo <= -0.5 && -0.5 <= hi && hi < 9.0);
/// assert!("t2_offset=9".parse::<Effect>().is_err());
/// ```
///
/// Whether a data set can show an effect is part of its entry too:
///
/// ```
/// use capstan_physics::{EffectKind, Facts};
///
/// // The thesis design: 5 wraps × 2 diameters at one drive voltage, 6 runs per cord.
/// let thesis = Facts { wraps: 5, diameters: 2, voltages: 1, cords: 10, runs: 60,
///                      max_runs_per_cord: 6, ..Facts::default() };
/// let speed = EffectKind::SpeedDependence.entry();
/// assert_eq!(speed.column, Some("drive_v"));
/// assert_eq!((speed.untestable)(&thesis), Some("a single drive voltage"));
/// // A second voltage makes it testable.
/// assert_eq!((speed.untestable)(&Facts { voltages: 2, ..thesis }), None);
/// ```
#[derive(Clone, Copy, Debug)]
pub struct EffectEntry {
    /// Which effect.
    pub kind: EffectKind,
    /// The catalogue name (command line, JSON, tests).
    pub name: &'static str,
    /// Its parameter's name (`None` for `none`).
    pub parameter: Option<&'static str>,
    /// The parameter's unit ("" for a ratio).
    pub unit: &'static str,
    /// The parameter value at which the effect vanishes.
    pub neutral: f64,
    /// The values a real rig can hold (inclusive), in its units: what `capstan simulate
    /// --effect` accepts. The fits have their own bounds (`theta`, `population`).
    pub physical: (f64, f64),
    /// Where in the data it shows.
    pub level: Level,
    /// What it is, physically (the report's and the verdicts' words).
    pub title: &'static str,
    /// Its name in a few words, for a figure's axis or a table's row (not an identifier).
    pub label: &'static str,
    /// A note the report adds when the effect is named (what the design cannot resolve of it).
    pub named_note: Option<&'static str>,
    /// The data column it needs beyond wrap, T1 and T2.
    pub column: Option<&'static str>,
    /// Why the design cannot test it, if it cannot (beyond a missing column).
    pub untestable: fn(&Facts) -> Option<&'static str>,
    /// Switch it on in a model at a value (overwrites that one parameter).
    pub apply: fn(&mut Model, f64),
    /// Its value in a model.
    pub read: fn(&Model) -> f64,
    /// Put in place what the effect needs at any value, zero included (heating: its memory).
    pub prepare: fn(&mut Model),
    /// Within-run effects: θ.
    pub theta: Theta,
    /// Within-run effects: the closed-form partial, if the law has one.
    pub partial: Option<Partial>,
    /// Between-cord effects: the regression.
    pub cord: Option<CordTest>,
    /// The half-width of its region of practical equivalence with no effect, in its units.
    pub relevance: fn(&Facts) -> f64,
    /// How the population model carries it.
    pub population: Population,
    /// How generated cases plant it.
    pub cases: Cases,
}

impl EffectEntry {
    /// The value of θ.
    ///
    /// ```
    /// use capstan_physics::EffectKind;
    ///
    /// // Bending stiffness is fitted as θ = √b, smooth where a lift-off grows with √b.
    /// let bending = EffectKind::BendingStiffness.entry();
    /// let b_nm2 = bending.value_of_theta(2e-3);
    /// assert!((b_nm2 - 4e-6).abs() < 1e-18);
    /// assert!((bending.theta_of_value(b_nm2) - 2e-3).abs() < 1e-15);
    /// assert!((bending.derivative_of_theta(2e-3) - 4e-3).abs() < 1e-15);
    /// // An offset is fitted as itself.
    /// assert_eq!(EffectKind::T1Offset.entry().value_of_theta(-0.3), -0.3);
    /// ```
    pub fn value_of_theta(&self, theta: f64) -> f64 {
        match self.theta.scale {
            Scale::Identity => theta,
            Scale::Square => theta * theta,
        }
    }

    /// d value / d θ.
    pub fn derivative_of_theta(&self, theta: f64) -> f64 {
        match self.theta.scale {
            Scale::Identity => 1.0,
            Scale::Square => 2.0 * theta,
        }
    }

    /// θ of a value (not clamped).
    pub fn theta_of_value(&self, value: f64) -> f64 {
        match self.theta.scale {
            Scale::Identity => value,
            Scale::Square => crate::math::sqrt(value.max(0.0)),
        }
    }
}

/// No condition of its own.
pub(crate) fn always(_: &Facts) -> Option<&'static str> {
    None
}

/// Nothing to prepare.
pub(crate) fn nothing(_: &mut Model) {}

/// θ not fitted within runs.
pub(crate) fn no_range(_: &Facts) -> (f64, f64) {
    (0.0, 0.0)
}

/// The value is the drawn change itself.
pub(crate) fn as_drawn(change: f64, _: f64) -> f64 {
    change
}

/// The drawn change spread over the design's span.
pub(crate) fn over_span(change: f64, span: f64) -> f64 {
    change / span
}
