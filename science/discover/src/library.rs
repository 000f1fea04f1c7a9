//! The library: candidate terms beyond the catalogue, one entry of data each.
//!
//! Every term has one parameter θ, and θ = 0 is the catalogue model. A term acts in one of
//! four places (its [`Form`]):
//!
//! * **mu**: mu → mu·(1 + θ·g(row)) (an exponential form mu·exp(−θ·g′) enters as g = −g′, the
//!   same to first order);
//! * **the T1 reading / the tension path**: the tension that reaches the capstan is
//!   T1c = T1m + θ·g(row);
//! * **the T2 reading**: T2m = T2 + o2 + θ·g(T2);
//! * **the friction law along the wrap** (adhesion): dT/dφ = mu·T + a·R.
//!
//! g is built from the data's own variables (T1, T2, the load T2 − T1, wrap β, diameter D and
//! R = D/2, time, run, step, step direction, drive voltage) and the design's means (β̄, D̄).
//! Memory terms use the *model's* loads along each run, never the measured T2 of earlier steps
//! (that would let a held-out cord's own responses predict it). Units: N, mm, rad, s.
//! `docs/README-discover.md` gives every entry's physical reading and source.

use serde::Serialize;

/// Where a term acts (the JSON's `acts_on`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ActsOn {
    /// The friction coefficient.
    Mu,
    /// The T1 sensor's reading.
    T1Reading,
    /// The T2 sensor's reading.
    T2Reading,
    /// The tension on its way to the capstan (or along the wrap).
    Tension,
}

impl ActsOn {
    /// Its name in the JSON.
    pub fn name(self) -> &'static str {
        match self {
            ActsOn::Mu => "mu",
            ActsOn::T1Reading => "t1_reading",
            ActsOn::T2Reading => "t2_reading",
            ActsOn::Tension => "tension",
        }
    }
}

/// A variable a term depends on (the JSON's `depends_on`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Var {
    /// T1.
    T1,
    /// T2.
    T2,
    /// The load T2 − T1.
    Load,
    /// The wrap angle.
    Wrap,
    /// The capstan diameter.
    Diameter,
    /// Time since the trigger.
    Time,
    /// The run on a cord.
    Run,
    /// The step inside a run.
    Step,
    /// The direction of the last step.
    StepDirection,
    /// The drive voltage.
    DriveV,
}

impl Var {
    /// Its name in the JSON.
    pub fn name(self) -> &'static str {
        match self {
            Var::T1 => "t1",
            Var::T2 => "t2",
            Var::Load => "load",
            Var::Wrap => "wrap",
            Var::Diameter => "diameter",
            Var::Time => "time",
            Var::Run => "run",
            Var::Step => "step",
            Var::StepDirection => "step_direction",
            Var::DriveV => "drive_v",
        }
    }
}

/// The physical sign a term's parameter must keep (outside it, it is not that physics).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Sign {
    /// Either sign.
    Free,
    /// θ ≥ 0.
    NonNegative,
}

/// The row's quantities a term's g reads (the catalogue fit's, per row).
#[derive(Clone, Copy, Debug, Default)]
pub struct Row {
    /// Measured T1, N.
    pub t1: f64,
    /// The catalogue model's true T2, N.
    pub t2: f64,
    /// The model's load T2 − T1 (true tensions), N.
    pub load: f64,
    /// Wrap, rad; the design's mean wrap.
    pub wrap: f64,
    /// The design's mean wrap (over cords), rad.
    pub wrap_mean: f64,
    /// Capstan diameter, mm.
    pub diameter: f64,
    /// The design's mean diameter (over cords), mm.
    pub diameter_mean: f64,
    /// Time since the run's first row, s.
    pub time_in_run: f64,
    /// Run on its cord (1-based).
    pub run: f64,
    /// The tension fell from the previous step.
    pub falling: bool,
    /// Drive voltage, V; and the design's mean.
    pub drive_v: f64,
    /// The design's mean drive voltage, V.
    pub drive_v_mean: f64,
    /// The model's friction work of the earlier steps of the run, kN s.
    pub work_before_kns: f64,
    /// The model's load at the previous step of the run (0 at the first), N.
    pub load_prev: f64,
    /// The design's geometric-mean measured T1 (over rows with T1 > 0), N; a centred term's
    /// centre when its column is built at one ([`centred`]).
    pub t1_ref: f64,
}

/// The spacing of the centres tried for a centred term, in ln T1 (half the bump's SD of 0.5).
pub const CENTRE_STEP_LN: f64 = 0.25;

/// A term with a centre in T1 (`mu_tension_bump`), profiled over [`centres`]
/// (`crate::centred`).
pub fn centred(t: &Term) -> bool {
    t.name == "mu_tension_bump"
}

/// The `n` centres tried for a centred term on a design of geometric-mean T1 `t1_ref` (N):
/// t1_ref·e^{(k − (n−1)/2)·[`CENTRE_STEP_LN`]}, k = 0 … n − 1.
pub fn centres(t1_ref: f64, n: usize) -> impl Iterator<Item = f64> {
    let mid = (n.max(1) - 1) as f64 / 2.0;
    (0..n.max(1)).map(move |k| t1_ref * ((k as f64 - mid) * CENTRE_STEP_LN).exp())
}

/// How θ enters the model (first order in θ is what the search uses).
#[derive(Clone, Copy, Debug)]
pub enum Form {
    /// mu → mu·(1 + θ·g).
    Mu(fn(&Row) -> f64),
    /// T1c = T1m + θ·g.
    T1(fn(&Row) -> f64),
    /// T2m = T2 + o2 + θ·g(T2).
    T2(fn(&Row) -> f64),
    /// dT/dφ = mu·T + θ·R: T2 = (T1c + θR/mu)·e^{mu β} − θR/mu.
    Adhesion,
}

/// One library term: everything about it in one place.
#[derive(Clone, Copy, Debug)]
pub struct Term {
    /// Name (the JSON's `name`).
    pub name: &'static str,
    /// Formula, θ = 0 is off.
    pub formula: &'static str,
    /// The parameter's name.
    pub parameter: &'static str,
    /// The parameter's units.
    pub units: &'static str,
    /// Where it acts.
    pub acts_on: ActsOn,
    /// What it depends on.
    pub depends_on: &'static [Var],
    /// Its physical sign.
    pub sign: Sign,
    /// What it would mean on the rig.
    pub reading: &'static str,
    /// Where the physics comes from.
    pub source: &'static str,
    /// How it enters the model.
    pub form: Form,
}

const TURN: f64 = 2.0 * std::f64::consts::PI;

fn pos(x: f64) -> f64 {
    x.max(0.0)
}

fn mean_tension(r: &Row) -> f64 {
    0.5 * (r.t1 + r.t2)
}

/// The library, in the order the docs list it.
pub const LIBRARY: &[Term] = &[
    Term {
        name: "mu_wrap_linear",
        formula: "mu·(1 + k·(β − β̄)/β̄)",
        parameter: "k",
        units: "1",
        acts_on: ActsOn::Mu,
        depends_on: &[Var::Wrap],
        sign: Sign::Free,
        reading: "friction is not the same for every wrap",
        source: "empirical; the thesis's mu per wrap (Table 3)",
        form: Form::Mu(|r| (r.wrap - r.wrap_mean) / r.wrap_mean),
    },
    Term {
        name: "cord_on_cord",
        formula: "mu·(1 + k·(β − 2π)₊/β)",
        parameter: "k",
        units: "1",
        acts_on: ActsOn::Mu,
        depends_on: &[Var::Wrap],
        sign: Sign::Free,
        reading: "beyond one full turn the cord lies on or against itself",
        source: "rope-on-rope contact on multi-turn capstans (the issue-26 spike's reading; no closed form)",
        form: Form::Mu(|r| pos(r.wrap - TURN) / r.wrap),
    },
    Term {
        name: "helix_wrap",
        formula: "mu·cos α, tan α = d_c·(β − 2π)₊/(2πRβ)",
        parameter: "d_c²",
        units: "mm²",
        acts_on: ActsOn::Mu,
        depends_on: &[Var::Wrap, Var::Diameter],
        sign: Sign::NonNegative,
        reading: "every turn beyond the first shifts the cord by one cord diameter (a helix)",
        source: "Konyukhov's generalised Euler-Eytelwein for a rope on a helix (mu·cos α), as the spike cites",
        form: Form::Mu(|r| {
            let x = pos(r.wrap - TURN) / (TURN * 0.5 * r.diameter * r.wrap);
            -0.5 * x * x
        }),
    },
    Term {
        name: "pressure_linear",
        formula: "mu·exp(−k·T̄/R), T̄ = (T1 + T2)/2",
        parameter: "k",
        units: "mm/N",
        acts_on: ActsOn::Mu,
        depends_on: &[Var::T1, Var::T2, Var::Diameter],
        sign: Sign::Free,
        reading: "friction changes with the line pressure T/R on the capstan",
        source: "polymer friction falling with pressure (Howell 1954, linearised)",
        form: Form::Mu(|r| -mean_tension(r) / (0.5 * r.diameter)),
    },
    Term {
        name: "heat_flux",
        formula: "mu·exp(−k·(T2 − T1)/(R·β))",
        parameter: "k",
        units: "mm/N",
        acts_on: ActsOn::Mu,
        depends_on: &[Var::Load, Var::Diameter, Var::Wrap],
        sign: Sign::NonNegative,
        reading: "heating by the friction power per area of contact",
        source: "flash-temperature scaling (Archard 1959; Bowden and Tabor)",
        form: Form::Mu(|r| -r.load / (0.5 * r.diameter * r.wrap)),
    },
    Term {
        name: "heat_per_radius",
        formula: "mu·exp(−k·(T2 − T1)·D̄/D)",
        parameter: "k",
        units: "1/N",
        acts_on: ActsOn::Mu,
        depends_on: &[Var::Load, Var::Diameter],
        sign: Sign::NonNegative,
        reading: "more heating on the smaller capstan (less metal to take the heat)",
        source: "contact heating (catalogue) with a heat path that scales as 1/R",
        form: Form::Mu(|r| -r.load * r.diameter_mean / r.diameter),
    },
    Term {
        name: "heat_per_wrap",
        formula: "mu·exp(−k·(T2 − T1)·β̄/β)",
        parameter: "k",
        units: "1/N",
        acts_on: ActsOn::Mu,
        depends_on: &[Var::Load, Var::Wrap],
        sign: Sign::NonNegative,
        reading: "heating per length of contact",
        source: "contact heating (catalogue) spread over the contact length Rβ",
        form: Form::Mu(|r| -r.load * r.wrap_mean / r.wrap),
    },
    Term {
        name: "conformity",
        formula: "mu·T̄/(T̄ + T_c)",
        parameter: "T_c",
        units: "N",
        acts_on: ActsOn::Mu,
        depends_on: &[Var::T1, Var::T2],
        sign: Sign::NonNegative,
        reading: "the cord conforms to the capstan as tension grows (the thesis's fast rise)",
        source: "the thesis's own reading of its low-tension data",
        form: Form::Mu(|r| -1.0 / mean_tension(r).max(0.05)),
    },
    Term {
        name: "mu_tension_bump",
        formula: "mu·(1 + c·exp(−(ln(T1/T₀))²/(2·0.5²))), T₀ = T̃1 the design's geometric-mean T1 (or the best-fitting of n centres T̃1·e^{k/4} with `bump_centres` = n)",
        parameter: "c",
        units: "1",
        acts_on: ActsOn::Mu,
        depends_on: &[Var::T1],
        sign: Sign::Free,
        reading: "friction is higher (c > 0) or lower over a band of tensions around T₀ (a factor of about 1.6 either side): a contact regime between the cord's conforming at low tension and its softening at high tension",
        source: "the thesis's fast rise at low tension (conformity) meeting polymer friction falling with pressure (Howell 1954): a maximum between them",
        form: Form::Mu(|r| {
            let z = (r.t1.max(0.05) / r.t1_ref).ln() / 0.5;
            (-0.5 * z * z).exp()
        }),
    },
    Term {
        name: "load_memory_cum",
        formula: "mu·exp(−k·Σ_{earlier steps} L̂·Δt / 1 kN s)",
        parameter: "k",
        units: "1",
        acts_on: ActsOn::Mu,
        depends_on: &[Var::Load, Var::Time, Var::Step],
        sign: Sign::NonNegative,
        reading: "the capstan warms with the friction work done earlier in the run",
        source: "the thesis's mild warming; frictional heating of the drum",
        form: Form::Mu(|r| -r.work_before_kns),
    },
    Term {
        name: "load_memory_prev",
        formula: "mu·exp(−k·L̂_{previous step})",
        parameter: "k",
        units: "1/N",
        acts_on: ActsOn::Mu,
        depends_on: &[Var::Load, Var::Step],
        sign: Sign::NonNegative,
        reading: "thermal lag of one step",
        source: "contact heating (catalogue) with a longer memory",
        form: Form::Mu(|r| -r.load_prev),
    },
    Term {
        name: "settling",
        formula: "mu·(1 − c·e^{−t/10 s}), t from the run's first row",
        parameter: "c",
        units: "1",
        acts_on: ActsOn::Mu,
        depends_on: &[Var::Time, Var::Step],
        sign: Sign::Free,
        reading: "the contact settles after a run starts (time, not tension)",
        source: "run-in of polymer contacts (creep of the junctions)",
        form: Form::Mu(|r| -(-r.time_in_run / 10.0).exp()),
    },
    Term {
        name: "run_in",
        formula: "mu·(1 + c·[run = 1])",
        parameter: "c",
        units: "1",
        acts_on: ActsOn::Mu,
        depends_on: &[Var::Run],
        sign: Sign::Free,
        reading: "a new cord's first run differs from the later ones",
        source: "running-in of a fresh surface",
        form: Form::Mu(|r| if r.run <= 1.0 { 1.0 } else { 0.0 }),
    },
    Term {
        name: "wear_log",
        formula: "mu·(1 + c·ln run)",
        parameter: "c",
        units: "1",
        acts_on: ActsOn::Mu,
        depends_on: &[Var::Run],
        sign: Sign::Free,
        reading: "wear (or polishing) that saturates with the runs",
        source: "wear (catalogue) with a saturating law",
        form: Form::Mu(|r| r.run.max(1.0).ln()),
    },
    Term {
        name: "hysteresis",
        formula: "mu·(1 + c·[the tension fell])",
        parameter: "c",
        units: "1",
        acts_on: ActsOn::Mu,
        depends_on: &[Var::StepDirection],
        sign: Sign::Free,
        reading: "friction depends on the direction of the last change (stick-slip memory)",
        source: "frictional hysteresis of the cord (rising and falling steps)",
        form: Form::Mu(|r| if r.falling { 1.0 } else { 0.0 }),
    },
    Term {
        name: "mu_drive_log",
        formula: "mu·(1 + c·ln(V/V̄))",
        parameter: "c",
        units: "1",
        acts_on: ActsOn::Mu,
        depends_on: &[Var::DriveV],
        sign: Sign::Free,
        reading: "friction changes with sliding speed, logarithmically (rate-and-state)",
        source: "Dieterich-Ruina rate dependence; the catalogue's speed effect is linear in V",
        form: Form::Mu(|r| (r.drive_v / r.drive_v_mean).ln()),
    },
    Term {
        name: "t2_curvature",
        formula: "T2m = T2 + o2 + c·T2²/10 N",
        parameter: "c",
        units: "1",
        acts_on: ActsOn::T2Reading,
        depends_on: &[Var::T2],
        sign: Sign::Free,
        reading: "a bowed T2 calibration",
        source: "load-cell non-linearity (datasheet class)",
        form: Form::T2(|r| r.t2 * r.t2 / 10.0),
    },
    Term {
        name: "t2_cubic",
        formula: "T2m = T2 + o2 + c·(T2/10 N)³",
        parameter: "c",
        units: "N",
        acts_on: ActsOn::T2Reading,
        depends_on: &[Var::T2],
        sign: Sign::Free,
        reading: "an odd (S-like) T2 calibration error",
        source: "load-cell non-linearity (datasheet class)",
        form: Form::T2(|r| (r.t2 / 10.0).powi(3)),
    },
    Term {
        name: "t2_offset_wrap",
        formula: "T2m = T2 + o2 + c·(β − β̄)/2π",
        parameter: "c",
        units: "N/turn",
        acts_on: ActsOn::T2Reading,
        depends_on: &[Var::Wrap],
        sign: Sign::Free,
        reading: "the T2 sensor is re-mounted at another angle for every wrap; its zero moves",
        source: "the thesis's set-up (a new mounting per wrap)",
        form: Form::T2(|r| (r.wrap - r.wrap_mean) / TURN),
    },
    Term {
        name: "t2_offset_diameter",
        formula: "T2m = T2 + o2 + c·(D − D̄)/D̄",
        parameter: "c",
        units: "N",
        acts_on: ActsOn::T2Reading,
        depends_on: &[Var::Diameter],
        sign: Sign::Free,
        reading: "a T2 tare per capstan session",
        source: "the thesis's set-up (one session per capstan)",
        form: Form::T2(|r| (r.diameter - r.diameter_mean) / r.diameter_mean),
    },
    Term {
        name: "t2_lowforce",
        formula: "T2m = T2 + o2 + c·(1 − e^{−T2/1 N})",
        parameter: "c",
        units: "N",
        acts_on: ActsOn::T2Reading,
        depends_on: &[Var::T2],
        sign: Sign::Free,
        reading: "the T2 hook seats, or a dead band, at low force",
        source: "fixture compliance at small loads",
        form: Form::T2(|r| 1.0 - (-r.t2.max(0.0)).exp()),
    },
    Term {
        name: "t1_offset_diameter",
        formula: "T1c = T1m − c·(D − D̄)/D̄",
        parameter: "c",
        units: "N",
        acts_on: ActsOn::T1Reading,
        depends_on: &[Var::T1, Var::Diameter],
        sign: Sign::Free,
        reading: "the T1 tare differs between capstan sessions",
        source: "the thesis's set-up (one session per capstan)",
        form: Form::T1(|r| -(r.diameter - r.diameter_mean) / r.diameter_mean),
    },
    Term {
        name: "t1_curvature",
        formula: "T1c = T1m + c·T1m²/10 N",
        parameter: "c",
        units: "1",
        acts_on: ActsOn::T1Reading,
        depends_on: &[Var::T1],
        sign: Sign::Free,
        reading: "a bowed T1 calibration",
        source: "load-cell non-linearity (datasheet class)",
        form: Form::T1(|r| r.t1 * r.t1 / 10.0),
    },
    Term {
        name: "t1_lowforce",
        formula: "T1c = T1m − c·(1 − e^{−T1m/1 N})",
        parameter: "c",
        units: "N",
        acts_on: ActsOn::T1Reading,
        depends_on: &[Var::T1],
        sign: Sign::Free,
        reading: "the T1 hook seats, or a dead band, at low force",
        source: "fixture compliance at small loads",
        form: Form::T1(|r| -(1.0 - (-r.t1.max(0.0)).exp())),
    },
    Term {
        name: "path_loss_wrap",
        formula: "T1c = T1m − ℓ·β/2π",
        parameter: "ℓ",
        units: "N/turn",
        acts_on: ActsOn::Tension,
        depends_on: &[Var::T1, Var::Wrap],
        sign: Sign::NonNegative,
        reading: "a loss before the capstan that grows with the wrap (the guide's angle)",
        source: "friction at the guide pulley, whose wrap changes with the set-up",
        form: Form::T1(|r| -r.wrap / TURN),
    },
    Term {
        name: "path_loss_crossing",
        formula: "T1c = T1m·(1 − c·[β > 2π])",
        parameter: "c",
        units: "1",
        acts_on: ActsOn::Tension,
        depends_on: &[Var::T1, Var::Wrap],
        sign: Sign::NonNegative,
        reading: "the incoming cord rubs the outgoing strand once the wrap exceeds a turn",
        source: "strand crossing on multi-turn capstans",
        form: Form::T1(|r| if r.wrap > TURN + 1e-9 { -r.t1 } else { 0.0 }),
    },
    Term {
        name: "path_loss_bend",
        formula: "T1c = T1m − ℓ·(D̄/D)²",
        parameter: "ℓ",
        units: "N",
        acts_on: ActsOn::Tension,
        depends_on: &[Var::T1, Var::Diameter],
        sign: Sign::NonNegative,
        reading: "bending hysteresis where the cord bends onto the capstan, ∝ B/R²",
        source: "the bending energy of an elastic cord on a drum, ∝ B/R²",
        form: Form::T1(|r| -(r.diameter_mean / r.diameter).powi(2)),
    },
    Term {
        name: "path_loss_prop_diam",
        formula: "T1c = T1m·(1 − c·(D̄/D − 1))",
        parameter: "c",
        units: "1",
        acts_on: ActsOn::Tension,
        depends_on: &[Var::T1, Var::Diameter],
        sign: Sign::Free,
        reading: "a proportional entry loss that differs by capstan",
        source: "empirical; a capstan-specific entry friction",
        form: Form::T1(|r| -r.t1 * (r.diameter_mean / r.diameter - 1.0)),
    },
    Term {
        name: "adhesion",
        formula: "dT/dφ = mu·T + a·R ⇒ T2 = (T1c + aR/mu)·e^{mu β} − aR/mu",
        parameter: "a",
        units: "N/mm",
        acts_on: ActsOn::Tension,
        depends_on: &[Var::T1, Var::Wrap, Var::Diameter],
        sign: Sign::NonNegative,
        reading: "a pressure-independent adhesive shear per length of contact (two-term friction)",
        source: "Bowden and Tabor's two-term (adhesion + load) friction, integrated along the wrap",
        form: Form::Adhesion,
    },
];

/// The term called `name`.
pub fn term(name: &str) -> Option<&'static Term> {
    LIBRARY.iter().find(|t| t.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_every_term_says_what_it_depends_on() {
        for (i, t) in LIBRARY.iter().enumerate() {
            assert!(!t.depends_on.is_empty(), "{}", t.name);
            assert!(!t.reading.is_empty() && !t.source.is_empty());
            assert!(
                LIBRARY[i + 1..].iter().all(|u| u.name != t.name),
                "{}",
                t.name
            );
        }
        assert!(LIBRARY.len() >= 25);
    }

    #[test]
    fn every_term_is_off_at_the_design_mean_or_zero_and_finite() {
        let r = Row {
            t1: 3.0,
            t2: 20.0,
            load: 17.0,
            wrap: 4.0 * std::f64::consts::PI,
            wrap_mean: 3.0 * std::f64::consts::PI,
            diameter: 12.7,
            diameter_mean: 19.05,
            time_in_run: 30.0,
            run: 2.0,
            falling: false,
            drive_v: 10.0,
            drive_v_mean: 10.0,
            work_before_kns: 0.3,
            load_prev: 12.0,
            t1_ref: 4.6,
        };
        for t in LIBRARY {
            let g = match t.form {
                Form::Mu(f) | Form::T1(f) | Form::T2(f) => f(&r),
                Form::Adhesion => 1.0,
            };
            assert!(g.is_finite(), "{}", t.name);
        }
    }
}
