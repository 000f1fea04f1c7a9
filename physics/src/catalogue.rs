//! The effect catalogue: the single departures from Euler-Eytelwein the rig can show, one
//! entry each ([`EffectEntry`]), next to the law that carries them ([`crate::FrictionLaw`],
//! [`crate::SensorArtefacts`]).
//!
//! Names and parameters are fixed (they appear on the command line, in JSON and in tests):
//!
//! | effect | parameter | neutral | level |
//! |---|---|---|---|
//! | `none` | - | - | - |
//! | `pressure_friction` | `n` | 1 | within runs |
//! | `bending_stiffness` | `b_nm2` | 0 | within runs |
//! | `t1_offset` | `offset_n` | 0 | within runs |
//! | `t2_offset` | `offset_n` | 0 | within runs |
//! | `sensor_gain` | `gain` | 1 | between cords |
//! | `thermal_drift` | `mu_change_per_100s` | 0 | within runs |
//! | `wear` | `mu_change_per_run` | 0 | between runs |
//! | `diameter_dependence` | `mu_change_per_mm` | 0 | between cords |
//! | `speed_dependence` | `mu_change_per_v` | 0 | between cords |
//! | `contact_heating` | `heat_per_n` | 0 | within runs |
//!
//! `contact_heating` is friction that falls with the friction load T2 − T1 the contact
//! carries: mu·exp(−h·H) with H the load remembered over [`HEAT_TAU_S`] (see
//! [`crate::LoadMemory`]). Its parameter is h·τ, the steady-state loss of ln mu per newton of
//! load (1/N); the memory is short against any conditioning window, so the data see
//! mu·exp(−heat_per_n·(T2 − T1)).
//!
//! To add an effect: a variant, its entry below (in the variant's place), and its law (with, for
//! a new scalar of the model, its row in [`crate::scalars::SCALARS`], which the fitter reads).

use crate::entry::{
    always, as_drawn, no_range, nothing, one_percent_over, over_span, CaseDesign, Cases, CordTest,
    EffectEntry, Facts, Level, Partial, Population, Scale, Slope, Span, Theta, Transform,
};
use crate::math::{log, sqrt};
use crate::{Operating, REF_DIAMETER_MM, REF_DRIVE_V};

/// Memory time of the catalogue's `contact_heating`, s: shorter than the settling before any
/// conditioning window, so a window sees the steady state of the load it carries.
pub const HEAT_TAU_S: f64 = 0.25;

/// One kind of departure from Euler-Eytelwein: the key of its [`EffectEntry`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum EffectKind {
    /// Euler-Eytelwein holds.
    None,
    /// dT/dθ = k·Tⁿ with n < 1.
    PressureFriction,
    /// The cord lifts off at low tension.
    BendingStiffness,
    /// Zero offset on the T1 sensor.
    T1Offset,
    /// Zero offset on the T2 sensor.
    T2Offset,
    /// T2 gain error relative to T1.
    SensorGain,
    /// mu drifts with time in a run.
    ThermalDrift,
    /// mu changes from run to run.
    Wear,
    /// mu depends on capstan diameter.
    DiameterDependence,
    /// mu depends on drive voltage.
    SpeedDependence,
    /// mu falls with the friction load T2 − T1 (contact heating with a short memory).
    ContactHeating,
}

impl EffectKind {
    /// Every effect, `none` first (the catalogue's order).
    pub const ALL: [EffectKind; CATALOGUE.len()] = {
        let mut all = [EffectKind::None; CATALOGUE.len()];
        let mut i = 0;
        while i < all.len() {
            all[i] = CATALOGUE[i].kind;
            i += 1;
        }
        all
    };

    /// Its entry.
    pub fn entry(self) -> &'static EffectEntry {
        &ENTRIES[self as usize]
    }
}

/// The catalogue, in the order of [`EffectKind`].
pub static ENTRIES: [EffectEntry; CATALOGUE.len()] = CATALOGUE;

/// A model scalar the population fit moves, unbounded.
const fn free(scalar: &'static str) -> Population {
    Population {
        scalar,
        value_per_scalar: 1.0,
        transform: Transform::Identity,
        floor: None,
    }
}

/// An effect with no θ (judged between runs or cords).
const NO_THETA: Theta = Theta {
    bounds: no_range,
    scale: Scale::Identity,
    step: 1e-6,
    starts: &[],
};

/// θ in a fixed range, the value itself.
const fn theta(lo_hi: fn(&Facts) -> (f64, f64), step: f64, starts: &'static [f64]) -> Theta {
    Theta {
        bounds: lo_hi,
        scale: Scale::Identity,
        step,
        starts,
    }
}

/// A size drawn as it is, with a random sign or not.
const fn drawn(care: (f64, f64), small: (f64, f64), signed: bool) -> Cases {
    Cases {
        care,
        small,
        signed,
        value: as_drawn,
        span: Span::One,
        design: CaseDesign {
            wide_wraps: false,
            voltages: false,
            diameters: false,
            min_runs: 0,
        },
    }
}

/// A signed change of mu across a span of the design.
const fn across(care: (f64, f64), small: (f64, f64), span: Span, design: CaseDesign) -> Cases {
    Cases {
        care,
        small,
        signed: true,
        value: over_span,
        span,
        design,
    }
}

/// The design needs nothing special.
const PLAIN: CaseDesign = CaseDesign {
    wide_wraps: false,
    voltages: false,
    diameters: false,
    min_runs: 0,
};

fn few_cords(f: &Facts) -> Option<&'static str> {
    (f.cords < 3).then_some("fewer than 3 cords")
}

/// Every entry. Between-cord effects are judged against the cord-to-cord scatter of mu
/// (thesis: ~4 %) with a design's ten-odd cords: below ~10 % they are at the detection limit,
/// so the generated cases' sizes that matter start at 12 %.
const CATALOGUE: [EffectEntry; 11] = [
    EffectEntry {
        kind: EffectKind::None,
        name: "none",
        parameter: None,
        unit: "",
        neutral: 0.0,
        // none takes no value.
        physical: (0.0, 0.0),
        level: Level::WithinRun,
        title: "Euler-Eytelwein",
        label: "Euler-Eytelwein",
        named_note: None,
        column: None,
        untestable: always,
        apply: |_, _| {},
        read: |_| 0.0,
        prepare: nothing,
        theta: NO_THETA,
        partial: None,
        cord: None,
        relevance: |_| f64::INFINITY,
        population: free("mu"),
        cases: drawn((0.0, 0.0), (0.0, 0.0), false),
    },
    // Howell's power law for polymer cords has n < 1 (n > 1 would be friction growing faster
    // than pressure).
    EffectEntry {
        kind: EffectKind::PressureFriction,
        name: "pressure_friction",
        parameter: Some("n"),
        unit: "",
        neutral: 1.0,
        // a pressure exponent: 1 is Amontons, polymers on metal 0.67-1.
        physical: (0.4, 1.0),
        level: Level::WithinRun,
        title: "pressure-dependent friction (Howell's power law dT/dθ = k·Tⁿ, n < 1)",
        label: "pressure-dependent friction",
        named_note: None,
        column: None,
        untestable: always,
        apply: |m, v| m.law.tension_exponent = v,
        read: |m| m.law.tension_exponent,
        prepare: nothing,
        theta: theta(|_| (0.4, 1.0), 1e-6, &[0.97, 0.8]),
        partial: Some(Partial::Exponent),
        cord: None,
        relevance: |_| 0.01,
        population: Population {
            transform: Transform::Logistic { lo: 0.3, hi: 1.0 },
            ..free("n")
        },
        cases: Cases {
            value: |change, _| 1.0 - change,
            ..drawn((0.07, 0.2), (0.02, 0.05), false)
        },
    },
    // θ = √B (√(N m²)): the lift-off loss grows as √B, so θ is smooth at B = 0; a cord's
    // bending stiffness is positive and below a steel rod's (10⁻³ N m²). Relevant from
    // 2·10⁻⁶ N m² (B ≥ 0: the region of equivalence is [0, 2·10⁻⁶]).
    EffectEntry {
        kind: EffectKind::BendingStiffness,
        name: "bending_stiffness",
        parameter: Some("b_nm2"),
        unit: "N m²",
        neutral: 0.0,
        // N m²: a 1 mm steel wire is ~1e-3; a textile cord far less.
        physical: (0.0, 1e-3),
        level: Level::WithinRun,
        title: "bending stiffness (the cord lifts off the capstan at low tension)",
        label: "bending stiffness",
        named_note: None,
        column: Some("capstan_diameter_mm"),
        untestable: always,
        apply: |m, v| m.law.bending_b_nm2 = v,
        read: |m| m.law.bending_b_nm2,
        prepare: nothing,
        theta: Theta {
            bounds: |_| (0.0, sqrt(1e-3)),
            scale: Scale::Square,
            step: 1e-7,
            starts: &[5e-6, 8e-5],
        },
        partial: Some(Partial::SqrtB),
        cord: None,
        relevance: |_| 2e-6,
        population: Population {
            transform: Transform::Log,
            floor: Some(1e-8),
            ..free("b_nm2")
        },
        cases: Cases {
            design: CaseDesign {
                diameters: true,
                ..PLAIN
            },
            ..drawn((3e-5, 1.5e-4), (5e-6, 1.5e-5), false)
        },
    },
    // Zero offsets are within ±3 N (T1) and ±5 N (T2) on a rig whose sensors end at ~55 N;
    // relevant from 0.02 N (about one ADC count, 0.015 N).
    EffectEntry {
        kind: EffectKind::T1Offset,
        name: "t1_offset",
        parameter: Some("offset_n"),
        unit: "N",
        neutral: 0.0,
        // N: the firmware faults a reading below -3 N.
        physical: (-3.0, 3.0),
        level: Level::WithinRun,
        title: "a loss or zero offset on the T1 (servo) path",
        label: "T1 offset or loss",
        named_note: None,
        column: None,
        untestable: always,
        apply: |m, v| m.sensors.t1_offset_n = v,
        read: |m| m.sensors.t1_offset_n,
        prepare: nothing,
        theta: theta(|_| (-3.0, 3.0), 1e-6, &[0.0, 0.3, -0.3]),
        partial: Some(Partial::T1Offset),
        cord: None,
        relevance: |_| 0.02,
        population: free("t1_offset_n"),
        cases: drawn((0.2, 1.0), (0.04, 0.12), true),
    },
    EffectEntry {
        kind: EffectKind::T2Offset,
        name: "t2_offset",
        parameter: Some("offset_n"),
        unit: "N",
        neutral: 0.0,
        // N: below −3 N the sensor reads below the firmware's negative-force limit at rest and
        // no run starts (from about −1.2 N the low levels of some runs fault already, as they
        // would on the rig).
        physical: (-3.0, 5.0),
        level: Level::WithinRun,
        title: "an additive offset on T2, a sensor zero or a constant load-side loss",
        label: "T2 offset",
        named_note: None,
        column: None,
        untestable: always,
        apply: |m, v| m.sensors.t2_offset_n = v,
        read: |m| m.sensors.t2_offset_n,
        prepare: nothing,
        theta: theta(|_| (-5.0, 5.0), 1e-6, &[]),
        partial: Some(Partial::T2Offset),
        cord: None,
        relevance: |_| 0.02,
        population: free("t2_offset_n"),
        cases: drawn((0.3, 1.2), (0.08, 0.2), true),
    },
    // A T2 gain g adds ln g/β to the apparent mu: it shows only across wraps.
    EffectEntry {
        kind: EffectKind::SensorGain,
        name: "sensor_gain",
        parameter: Some("gain"),
        unit: "",
        neutral: 1.0,
        // a load cell amplifier off by a factor of two at most.
        physical: (0.5, 2.0),
        level: Level::BetweenCord,
        title: "a gain error of the T2 sensor relative to T1",
        label: "T2 sensor gain",
        named_note: None,
        column: None,
        untestable: |f| {
            if f.wraps < 2 {
                Some("a single wrap (a gain error only shows across wraps)")
            } else {
                few_cords(f)
            }
        },
        apply: |m, v| m.sensors.t2_gain = v,
        read: |m| m.sensors.t2_gain,
        prepare: nothing,
        theta: NO_THETA,
        partial: None,
        cord: Some(CordTest {
            covariate: |op| 1.0 / op.wrap_rad,
            slope: Slope::Exp,
        }),
        relevance: |_| 0.01,
        population: Population {
            transform: Transform::Log,
            floor: Some(0.1),
            ..free("t2_gain")
        },
        cases: Cases {
            value: |change, _| 1.0 + change,
            design: CaseDesign {
                wide_wraps: true,
                ..PLAIN
            },
            ..drawn((0.12, 0.3), (0.03, 0.06), true)
        },
    },
    // A drift changes mu by at most 80 % over the data's latest time.
    EffectEntry {
        kind: EffectKind::ThermalDrift,
        name: "thermal_drift",
        parameter: Some("mu_change_per_100s"),
        unit: "1/(100 s)",
        neutral: 0.0,
        // mu changing by at most half per 100 s.
        physical: (-0.5, 0.5),
        level: Level::WithinRun,
        title: "a drift of mu with time since the trigger",
        label: "drift with time",
        named_note: None,
        column: Some("time_s"),
        untestable: |f| {
            (f.max_time_spread_s <= 0.0).then_some("no time spread within runs")
        },
        apply: |m, v| m.law.mu_change_per_100s = v,
        read: |m| m.law.mu_change_per_100s,
        prepare: nothing,
        theta: theta(
            |f| {
                let t_max = f.latest_time_s;
                (-0.8 * 100.0 / t_max, 0.8 * 100.0 / t_max)
            },
            1e-6,
            &[],
        ),
        partial: Some(Partial::Drift),
        cord: None,
        relevance: |f| 100.0 * one_percent_over(f.max_time_spread_s),
        population: free("mu_change_per_100s"),
        cases: across((0.08, 0.25), (0.02, 0.05), Span::Time100s, PLAIN),
    },
    EffectEntry {
        kind: EffectKind::Wear,
        name: "wear",
        parameter: Some("mu_change_per_run"),
        unit: "1/run",
        neutral: 0.0,
        // mu changing by at most a tenth per run.
        physical: (-0.1, 0.1),
        level: Level::BetweenRun,
        title: "wear or polishing: mu changing from run to run",
        label: "wear (run to run)",
        named_note: None,
        column: Some("run"),
        untestable: |f| {
            if f.max_runs_per_cord < 2 {
                Some("one run per cord")
            } else {
                (f.runs < f.cords + 2).then_some("too few runs per cord")
            }
        },
        apply: |m, v| m.law.mu_change_per_run = v,
        read: |m| m.law.mu_change_per_run,
        prepare: nothing,
        theta: NO_THETA,
        partial: None,
        cord: None,
        relevance: |f| one_percent_over(f.run_span),
        population: free("mu_change_per_run"),
        cases: across(
            (0.08, 0.25),
            (0.02, 0.05),
            Span::Runs,
            CaseDesign {
                min_runs: 5,
                ..PLAIN
            },
        ),
    },
    EffectEntry {
        kind: EffectKind::DiameterDependence,
        name: "diameter_dependence",
        parameter: Some("mu_change_per_mm"),
        unit: "1/mm",
        neutral: 0.0,
        // at most half of mu across the thesis's 12.7 mm span.
        physical: (-0.04, 0.04),
        level: Level::BetweenCord,
        title: "a dependence of mu on the capstan diameter",
        label: "diameter dependence",
        named_note: None,
        column: Some("capstan_diameter_mm"),
        untestable: |f| {
            if f.diameters < 2 {
                Some("a single capstan diameter")
            } else {
                few_cords(f)
            }
        },
        apply: |m, v| m.law.mu_change_per_mm = v,
        read: |m| m.law.mu_change_per_mm,
        prepare: nothing,
        theta: NO_THETA,
        partial: None,
        cord: Some(CordTest {
            covariate: |op| op.diameter_mm - REF_DIAMETER_MM,
            slope: Slope::Relative,
        }),
        relevance: |f| one_percent_over(f.diameter_span_mm),
        population: free("mu_change_per_mm"),
        cases: across(
            (0.12, 0.3),
            (0.03, 0.06),
            Span::Diameters,
            CaseDesign {
                diameters: true,
                ..PLAIN
            },
        ),
    },
    EffectEntry {
        kind: EffectKind::SpeedDependence,
        name: "speed_dependence",
        parameter: Some("mu_change_per_v"),
        unit: "1/V",
        neutral: 0.0,
        // at most all of mu across a 10 V span.
        physical: (-0.1, 0.1),
        level: Level::BetweenCord,
        title: "a dependence of mu on the drive voltage (speed)",
        label: "speed dependence",
        named_note: None,
        column: Some("drive_v"),
        untestable: |f| {
            if f.voltages < 2 {
                Some("a single drive voltage")
            } else {
                few_cords(f)
            }
        },
        apply: |m, v| m.law.mu_change_per_v = v,
        read: |m| m.law.mu_change_per_v,
        prepare: nothing,
        theta: NO_THETA,
        partial: None,
        cord: Some(CordTest {
            covariate: |op| op.drive_v - REF_DRIVE_V,
            slope: Slope::Relative,
        }),
        relevance: |f| one_percent_over(f.voltage_span_v),
        population: free("mu_change_per_v"),
        cases: across(
            (0.12, 0.3),
            (0.03, 0.06),
            Span::Voltages,
            CaseDesign {
                voltages: true,
                ..PLAIN
            },
        ),
    },
    // Heating lowers friction: h ≥ 0, ln mu lost per newton of friction load, up to 0.1/N.
    // Relevant when it changes mu by 1 % at the data's largest friction load. The cases draw
    // the fraction mu falls by at a friction load of 30 N.
    EffectEntry {
        kind: EffectKind::ContactHeating,
        name: "contact_heating",
        parameter: Some("heat_per_n"),
        unit: "1/N",
        neutral: 0.0,
        // the population fit's bounds: ln mu falls by at most 0.1 per newton.
        physical: (0.0, 0.1),
        level: Level::WithinRun,
        title: "contact heating: mu falling with the friction load T2 − T1 the contact carries",
        label: "contact heating",
        named_note: Some("Contact heating is fitted with the catalogue's short load memory (τ = 0.25 s): window means taken ≥ 1 s after each change cannot resolve a memory shorter than the settling, so a contact temperature that settles within a second cannot be told from a friction law that depends on the load itself. Logging the samples inside each dwell would show the transient."),
        column: None,
        untestable: always,
        apply: |m, v| {
            if v == 0.0 {
                // Without heating the memory time means nothing: leave it.
                m.law.heat_per_ns = 0.0;
            } else {
                m.law.heat_per_ns = v / HEAT_TAU_S;
                m.law.heat_tau_s = HEAT_TAU_S;
            }
        },
        read: |m| m.law.heat_per_ns * m.law.heat_tau_s,
        prepare: |m| m.law.heat_tau_s = HEAT_TAU_S,
        theta: theta(|_| (0.0, 0.1), 1e-7, &[0.0, 0.01]),
        partial: Some(Partial::Heating),
        cord: None,
        relevance: |f| one_percent_over(f.max_load_n),
        population: Population {
            value_per_scalar: HEAT_TAU_S,
            transform: Transform::Log,
            ..free("heat_per_ns")
        },
        cases: Cases {
            value: |drop, _| -log(1.0 - drop) / 30.0,
            ..drawn((0.1, 0.35), (0.02, 0.06), false)
        },
    },
];

/// Why a design cannot tell two effects apart, for the pairs whose reason is known.
#[derive(Clone, Copy, Debug)]
pub enum Rivalry {
    /// In runs whose tension only rises (no reason otherwise).
    OneWay(&'static str),
    /// They differ in how the wrap amplifies them: the sentence is `before`, e^(μβ) at the
    /// smallest and largest wrap ("{:.1} to {:.1}"), then `after`.
    Amplified {
        /// Before the numbers.
        before: &'static str,
        /// After them.
        after: &'static str,
    },
}

/// The known rivalries, looked up in either order.
pub static RIVALRIES: [(EffectKind, EffectKind, Rivalry); 3] = [
    (
        EffectKind::ThermalDrift,
        EffectKind::ContactHeating,
        Rivalry::OneWay("in runs whose tension only rises, time and the friction load grow together; runs that step up and back down separate them"),
    ),
    (
        EffectKind::PressureFriction,
        EffectKind::ContactHeating,
        Rivalry::OneWay("in runs whose tension only rises, the friction load's history follows the tension; runs that step up and back down separate them"),
    ),
    (
        EffectKind::T1Offset,
        EffectKind::T2Offset,
        Rivalry::Amplified {
            before: "a T1 and a T2 zero offset differ only in how the wrap amplifies them: a T1 offset by e^(μβ), ",
            after: " on these wraps, a T2 offset not at all",
        },
    ),
];

/// The rivalry of `a` and `b`, if known.
pub fn rivalry(a: EffectKind, b: EffectKind) -> Option<Rivalry> {
    RIVALRIES
        .iter()
        .find(|r| (r.0 == a && r.1 == b) || (r.0 == b && r.1 == a))
        .map(|r| r.2)
}

/// The point of [`Operating`] a cord-level covariate is read at.
pub fn cord_point(wrap_deg: f64, diameter_mm: f64, drive_v: f64) -> Operating {
    Operating {
        wrap_rad: wrap_deg.to_radians(),
        diameter_mm,
        drive_v,
        ..Operating::from_wrap_deg(wrap_deg)
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::Model;

    #[test]
    fn entries_sit_in_the_order_of_their_kinds() {
        for (i, e) in ENTRIES.iter().enumerate() {
            assert_eq!(e.kind as usize, i, "{}", e.name);
            assert_eq!(EffectKind::ALL[i], e.kind);
        }
    }

    #[test]
    fn the_heating_note_names_the_memory_time() {
        let note = EffectKind::ContactHeating.entry().named_note.unwrap();
        let tau = std::format!("(τ = {} s)", HEAT_TAU_S);
        assert!(note.contains(&tau), "{note}");
    }

    #[test]
    fn theta_maps_round_trip() {
        for e in &ENTRIES {
            for v in [0.0, 0.25, 1e-4] {
                let t = e.theta_of_value(v);
                assert!((e.value_of_theta(t) - v).abs() < 1e-15, "{}", e.name);
            }
        }
    }

    #[test]
    fn a_model_prepared_for_heating_keeps_every_other_parameter() {
        let mut m = Model::euler_eytelwein(0.1);
        (EffectKind::ContactHeating.entry().prepare)(&mut m);
        assert_eq!(m.law.heat_tau_s, HEAT_TAU_S);
        assert_eq!(m.law.heat_per_ns, 0.0);
    }
}
