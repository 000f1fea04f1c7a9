//! The candidates the engine can name: every effect of the catalogue, at the level of the data
//! where it shows, with the internal coordinate θ it is fitted in, its start values, when it
//! is testable, and the size below which it is practically equivalent to no effect.

use super::design::Design;
use capstan_physics::{Effect, EffectKind, Facts, Model};
use serde::Serialize;

/// Where in the data an effect shows, and so against which scatter it is judged.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Level {
    /// The shape of T2 against T1, time and wrap inside runs (every run has its own mu).
    WithinRun,
    /// The runs' mu against a covariate that varies between cords (cord scatter as error).
    BetweenCord,
    /// The runs' mu against the run number within cords (run scatter as error).
    BetweenRun,
}

impl Level {
    /// Words for the human summary.
    pub fn words(self) -> &'static str {
        match self {
            Level::WithinRun => "shape within runs",
            Level::BetweenCord => "between cords",
            Level::BetweenRun => "between runs",
        }
    }
}

impl From<capstan_physics::Level> for Level {
    fn from(l: capstan_physics::Level) -> Self {
        match l {
            capstan_physics::Level::WithinRun => Level::WithinRun,
            capstan_physics::Level::BetweenCord => Level::BetweenCord,
            capstan_physics::Level::BetweenRun => Level::BetweenRun,
        }
    }
}

/// The level at which an effect is judged (its entry's).
pub fn level(kind: EffectKind) -> Level {
    kind.entry().level.into()
}

/// The effects of the catalogue at `level`, in its order (`none` aside).
pub fn at_level(at: Level) -> Vec<EffectKind> {
    EffectKind::ALL
        .into_iter()
        .skip(1)
        .filter(|&k| level(k) == at)
        .collect()
}

/// What the design of `d` offers, for the entries' conditions, ranges and sizes.
pub fn facts(d: &Design) -> Facts {
    let span = |v: Vec<f64>| v.last().copied().unwrap_or(0.0) - v.first().copied().unwrap_or(0.0);
    Facts {
        wraps: d.wraps().len(),
        diameters: d.diameters().len(),
        voltages: d.voltages().len(),
        cords: d.cords.len(),
        runs: d.units.len(),
        max_runs_per_cord: d.max_runs_per_cord(),
        max_time_spread_s: d.max_time_spread_s(),
        latest_time_s: d.op.iter().map(|o| o.time_s).fold(1.0, f64::max),
        run_span: span(crate::fit::stats::distinct(d.unit_run.iter().copied())),
        diameter_span_mm: span(d.diameters()),
        voltage_span_v: span(d.voltages()),
        max_load_n: (0..d.n()).map(|i| d.t2[i] - d.t1[i]).fold(0.0f64, f64::max),
        max_wrap_rad: d.op.iter().map(|o| o.wrap_rad).fold(0.0, f64::max),
    }
}

/// How a within-run effect's θ maps to its catalogue value, and θ's bounds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThetaMap {
    /// The effect.
    pub kind: EffectKind,
    /// Lower bound of θ.
    pub lo: f64,
    /// Upper bound of θ.
    pub hi: f64,
}

impl ThetaMap {
    /// θ's range for `kind` on this data set: the effect's physical range (its entry's).
    /// Each effect means one physical thing, and outside its range it is not that thing. A
    /// best fit on the edge of that range means the effect does not explain the data
    /// ([`ThetaMap::at_physical_limit`]).
    pub fn for_kind(kind: EffectKind, d: &Design) -> ThetaMap {
        let (lo, hi) = (kind.entry().theta.bounds)(&facts(d));
        ThetaMap { kind, lo, hi }
    }

    /// Does θ sit on the edge of the effect's physical range (a bound other than its neutral
    /// value)?
    pub fn at_physical_limit(&self, theta: f64) -> bool {
        let neutral = self.theta(self.kind.neutral_value());
        let tol = 1e-6 * (self.hi - self.lo);
        let on = |b: f64| (theta - b).abs() <= tol && (b - neutral).abs() > tol;
        on(self.lo) || on(self.hi)
    }

    /// Catalogue value of θ.
    pub fn value(&self, theta: f64) -> f64 {
        self.kind.entry().value_of_theta(theta)
    }

    /// d value / d θ.
    pub fn derivative(&self, theta: f64) -> f64 {
        self.kind.entry().derivative_of_theta(theta)
    }

    /// θ of a catalogue value (clamped into the bounds).
    pub fn theta(&self, value: f64) -> f64 {
        self.kind
            .entry()
            .theta_of_value(value)
            .clamp(self.lo, self.hi)
    }

    /// Forward-difference step of θ.
    pub fn step(&self) -> f64 {
        self.kind.entry().theta.step
    }

    /// Start values of θ (several for the effects whose fits have more than one basin).
    pub fn starts(&self) -> Vec<f64> {
        let e = self.kind.entry();
        let v: Vec<f64> = if e.theta.starts.is_empty() {
            vec![e.neutral]
        } else {
            e.theta.starts.to_vec()
        };
        v.into_iter().map(|x| self.theta(x)).collect()
    }
}

/// The model of one run: Euler-Eytelwein at `mu` with the effects at θ.
pub fn run_model(maps: &[ThetaMap], mu: f64, theta: &[f64]) -> Model {
    let mut m = Model::euler_eytelwein(mu);
    for (map, &t) in maps.iter().zip(theta) {
        Effect {
            kind: map.kind,
            value: map.value(t),
        }
        .apply(&mut m);
    }
    m
}

/// Why `kind` cannot be tested on `d`, if it cannot: a missing column, its entry's own
/// condition, or too few rows.
pub fn untestable(kind: EffectKind, d: &Design) -> Option<String> {
    if let Some(col) = kind.required_column() {
        if !d.columns.has(col) {
            return Some(format!("no `{col}` column"));
        }
    }
    if let Some(why) = (kind.entry().untestable)(&facts(d)) {
        return Some(why.into());
    }
    (d.positive_rows() < 3).then(|| "fewer than 3 rows with T1 and T2 above zero".into())
}

/// The half-width of the region of practical equivalence with no effect, in the catalogue's
/// units (a departure from the neutral value smaller than this is below what the rig can
/// resolve or what would matter; each entry says how much that is).
pub fn relevance_width(kind: EffectKind, d: &Design) -> f64 {
    (kind.entry().relevance)(&facts(d))
}

/// Does the interval [lo, hi] lie inside the region of practical equivalence with no effect?
pub fn inside_equivalence(kind: EffectKind, lo: f64, hi: f64, d: &Design) -> bool {
    let n = kind.neutral_value();
    let w = relevance_width(kind, d);
    lo.is_finite() && hi.is_finite() && (lo - n).abs() < w && (hi - n).abs() < w
}

/// Is an effect of this size more than the rig can resolve (outside the region of practical
/// equivalence, [`relevance_width`])?
pub fn practically_relevant(kind: EffectKind, value: f64, d: &Design) -> bool {
    value.is_finite() && (value - kind.neutral_value()).abs() >= relevance_width(kind, d)
}

/// Does the robust 95 % interval of an estimate lie inside the region of practical
/// equivalence (so the data exclude a size that matters: two one-sided tests)?
pub fn excluded(kind: EffectKind, value: f64, se: f64, d: &Design) -> bool {
    se.is_finite() && (value - kind.neutral_value()).abs() + 1.96 * se < relevance_width(kind, d)
}
