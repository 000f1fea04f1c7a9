//! The candidates the engine can name: every effect of the catalogue, at the level of the data
//! where it shows, with the internal coordinate θ it is fitted in, its start values, when it
//! is testable, and the size below which it is practically equivalent to no effect.

use super::design::Design;
use capstan_friction::{Effect, EffectKind, Model};
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

/// The level at which an effect is judged.
pub fn level(kind: EffectKind) -> Level {
    match kind {
        EffectKind::SensorGain | EffectKind::DiameterDependence | EffectKind::SpeedDependence => {
            Level::BetweenCord
        }
        EffectKind::Wear => Level::BetweenRun,
        _ => Level::WithinRun,
    }
}

/// The effects judged within runs, in the catalogue's order.
pub const WITHIN: [EffectKind; 6] = [
    EffectKind::PressureFriction,
    EffectKind::BendingStiffness,
    EffectKind::T1Offset,
    EffectKind::T2Offset,
    EffectKind::ThermalDrift,
    EffectKind::ContactHeating,
];

/// The effects judged between cords or runs.
pub const BETWEEN: [EffectKind; 4] = [
    EffectKind::SensorGain,
    EffectKind::Wear,
    EffectKind::DiameterDependence,
    EffectKind::SpeedDependence,
];

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
    /// θ's range for `kind` on this data set: the effect's physical range. Each effect means
    /// one physical thing, and outside its range it is not that thing: Howell's law for
    /// polymer cords has n < 1 (n > 1 would be friction growing faster than pressure); heating
    /// lowers friction; a cord's bending stiffness is positive and below a steel rod's
    /// (10⁻³ N m²); zero offsets are within ±3 N (T1) and ±5 N (T2) on a rig whose sensors end at
    /// ~55 N; a drift changes mu by at most 80 % over the data's longest time. A best fit on
    /// the edge of that range means the effect does not explain the data
    /// ([`ThetaMap::at_physical_limit`]).
    pub fn for_kind(kind: EffectKind, d: &Design) -> ThetaMap {
        let (lo, hi) = match kind {
            EffectKind::PressureFriction => (0.4, 1.0),
            // θ = √B (√(N m²)): the lift-off loss grows as √B, so θ is smooth at B = 0.
            EffectKind::BendingStiffness => (0.0, 1e-3f64.sqrt()),
            EffectKind::T1Offset => (-3.0, 3.0),
            EffectKind::T2Offset => (-5.0, 5.0),
            EffectKind::ThermalDrift => {
                let t_max = d.op.iter().map(|o| o.time_s).fold(1.0, f64::max);
                (-0.8 * 100.0 / t_max, 0.8 * 100.0 / t_max)
            }
            // ln mu lost per newton of friction load.
            EffectKind::ContactHeating => (0.0, 0.1),
            _ => (0.0, 0.0),
        };
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
        match self.kind {
            EffectKind::BendingStiffness => theta * theta,
            _ => theta,
        }
    }

    /// d value / d θ.
    pub fn derivative(&self, theta: f64) -> f64 {
        match self.kind {
            EffectKind::BendingStiffness => 2.0 * theta,
            _ => 1.0,
        }
    }

    /// θ of a catalogue value (clamped into the bounds).
    pub fn theta(&self, value: f64) -> f64 {
        let t = match self.kind {
            EffectKind::BendingStiffness => value.max(0.0).sqrt(),
            _ => value,
        };
        t.clamp(self.lo, self.hi)
    }

    /// Forward-difference step of θ.
    pub fn step(&self) -> f64 {
        match self.kind {
            EffectKind::BendingStiffness => 1e-7,
            EffectKind::ContactHeating => 1e-7,
            _ => 1e-6,
        }
    }

    /// Start values of θ (several for the effects whose fits have more than one basin).
    pub fn starts(&self) -> Vec<f64> {
        let v: Vec<f64> = match self.kind {
            EffectKind::PressureFriction => vec![0.97, 0.8],
            EffectKind::BendingStiffness => vec![5e-6, 8e-5],
            EffectKind::T1Offset => vec![0.0, 0.3, -0.3],
            EffectKind::ContactHeating => vec![0.0, 0.01],
            _ => vec![self.kind.neutral_value()],
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

/// Why `kind` cannot be tested on `d`, if it cannot.
pub fn untestable(kind: EffectKind, d: &Design) -> Option<String> {
    if let Some(col) = kind.required_column() {
        if !d.columns.has(col) {
            return Some(format!("no `{col}` column"));
        }
    }
    let n_pos = d.positive_rows();
    match kind {
        EffectKind::DiameterDependence if d.diameters().len() < 2 => {
            Some("a single capstan diameter".into())
        }
        EffectKind::SpeedDependence if d.voltages().len() < 2 => {
            Some("a single drive voltage".into())
        }
        EffectKind::SensorGain if d.wraps().len() < 2 => {
            Some("a single wrap (a gain error only shows across wraps)".into())
        }
        EffectKind::Wear if d.max_runs_per_cord() < 2 => Some("one run per cord".into()),
        EffectKind::ThermalDrift if d.max_time_spread_s() <= 0.0 => {
            Some("no time spread within runs".into())
        }
        EffectKind::DiameterDependence | EffectKind::SpeedDependence | EffectKind::SensorGain
            if d.cords.len() < 3 =>
        {
            Some("fewer than 3 cords".into())
        }
        EffectKind::Wear if d.units.len() < d.cords.len() + 2 => {
            Some("too few runs per cord".into())
        }
        _ if n_pos < 3 => Some("fewer than 3 rows with T1 and T2 above zero".into()),
        _ => None,
    }
}

/// The half-width of the region of practical equivalence with no effect, in the catalogue's
/// units (a departure from the neutral value smaller than this is below what the rig can
/// resolve or what would matter): offsets 0.02 N (about one ADC count, 0.015 N), a gain 1 %, an
/// exponent 0.01, a bending stiffness 2·10⁻⁶ N m² (B ≥ 0: the region is [0, 2·10⁻⁶]), a heating
/// that changes mu by 1 % at the data's largest friction load, and a drift, wear, diameter or
/// speed dependence that changes mu by 1 % across the data set's span of time, runs,
/// diameters or voltages (infinite when that span is zero).
pub fn relevance_width(kind: EffectKind, d: &Design) -> f64 {
    let span = |v: Vec<f64>| v.last().copied().unwrap_or(0.0) - v.first().copied().unwrap_or(0.0);
    let per = |s: f64| if s > 0.0 { 0.01 / s } else { f64::INFINITY };
    match kind {
        EffectKind::None => f64::INFINITY,
        EffectKind::T1Offset | EffectKind::T2Offset => 0.02,
        EffectKind::SensorGain | EffectKind::PressureFriction => 0.01,
        EffectKind::BendingStiffness => 2e-6,
        EffectKind::ThermalDrift => 100.0 * per(d.max_time_spread_s()),
        EffectKind::ContactHeating => {
            per((0..d.n()).map(|i| d.t2[i] - d.t1[i]).fold(0.0f64, f64::max))
        }
        EffectKind::Wear => per(span(crate::fit::stats::distinct(
            d.unit_run.iter().copied(),
        ))),
        EffectKind::DiameterDependence => per(span(d.diameters())),
        EffectKind::SpeedDependence => per(span(d.voltages())),
    }
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
