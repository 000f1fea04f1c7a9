//! The planted-truth scorer: run generated cases ([`super::cases`]), compare the answer (the
//! verdict layer's, as `capstan diagnose` renders it) with the planted truth, and compute the
//! acceptance figures. The diagnose suite scores by it, and so does `capstan analyze
//! --validate` ([`super::validate`]), on the same rule ([`Outcome::correct`]).
//!
//! * single effects at sizes that matter: named (the found set is exactly the effect, nothing
//!   unexplained) in ≥ 90 %, the parameter within 25 % for ≥ 90 % of those;
//! * pairs: both named and nothing else in ≥ 75 %;
//! * outside the catalogue: `unexplained` in ≥ 80 %, and never a single confident name with
//!   the lack of fit ignored (a found set without the unexplained flag counts as a miss);
//! * clean: anything named, or unexplained, in ≤ 5 %.

use crate::cases::{Case, Class};
use capstan_engine::diagnose::Diagnosis;
use capstan_physics::{Effect, EffectKind};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

pub use crate::figures::{Metrics, Targets};

/// What a diagnosis said about one case.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// The case's class.
    pub class: Class,
    /// The planted catalogue effects.
    pub truth: Vec<Effect>,
    /// The planted physics outside the catalogue.
    pub outside: Option<&'static str>,
    /// The effects named (strongest first).
    pub found: Vec<Effect>,
    /// The unexplained flag.
    pub unexplained: bool,
    /// The residual pattern reported.
    pub pattern: Option<&'static str>,
    /// The rivals reported: (found effect, rival, ΔBIC of the set with the rival).
    pub rivals: Vec<(EffectKind, EffectKind, f64)>,
    /// One line about the case.
    pub describe: String,
    /// The top candidates, for messages.
    pub candidates: String,
    /// Rows.
    pub rows: usize,
    /// Diagnosis wall time, s.
    pub elapsed_s: f64,
    /// Runs the firmware stopped, and the design's runs ([`Case::runs_short`]).
    pub runs_short: (usize, usize),
}

impl Outcome {
    /// The sorted kinds named.
    pub fn found_kinds(&self) -> Vec<EffectKind> {
        let mut k: Vec<EffectKind> = self.found.iter().map(|e| e.kind).collect();
        k.sort();
        k
    }

    /// The sorted kinds planted.
    pub fn truth_kinds(&self) -> Vec<EffectKind> {
        let mut k: Vec<EffectKind> = self.truth.iter().map(|e| e.kind).collect();
        k.sort();
        k
    }

    /// The answer is right for its class (see the module docs).
    pub fn correct(&self) -> bool {
        match self.class {
            Class::Outside => self.unexplained,
            _ => !self.unexplained && self.found_kinds() == self.truth_kinds(),
        }
    }

    /// A clean set's alarm: anything named, or structure flagged.
    pub fn alarm(&self) -> bool {
        self.unexplained || !self.found.is_empty()
    }

    /// The planted effects not among those named.
    pub fn missed(&self) -> Vec<EffectKind> {
        let found = self.found_kinds();
        self.truth_kinds()
            .into_iter()
            .filter(|k| !found.contains(k))
            .collect()
    }

    /// Every planted effect's value within 25 % (of its departure from neutral for n, gain).
    pub fn parameters_ok(&self) -> bool {
        self.truth.iter().all(|t| {
            self.found
                .iter()
                .find(|f| f.kind == t.kind)
                .is_some_and(|f| parameter_ok(*t, *f))
        })
    }
}

/// Is the estimate within 25 % of the truth? For `n` and `gain` (neutral 1), 25 % of the
/// departure from 1; for the others (neutral 0), 25 % of the value.
pub fn parameter_ok(truth: Effect, found: Effect) -> bool {
    let neutral = truth.kind.neutral_value();
    ((found.value - truth.value) / (truth.value - neutral)).abs() <= 0.25
}

/// `f` over `items` on `threads` threads, results in input order.
pub fn par<T: Sync, R: Send>(items: &[T], threads: usize, f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    let next = AtomicUsize::new(0);
    let out: Mutex<Vec<Option<R>>> = Mutex::new((0..items.len()).map(|_| None).collect());
    std::thread::scope(|s| {
        for _ in 0..threads.max(1) {
            s.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some(item) = items.get(i) else { break };
                let r = f(item);
                if let Ok(mut v) = out.lock() {
                    v[i] = Some(r);
                }
            });
        }
    });
    out.into_inner()
        .unwrap_or_default()
        .into_iter()
        .flatten()
        .collect()
}

/// Simulate every case (firmware in the loop) on `threads` threads; data sets in case order.
/// A case the simulator refuses is an error naming it.
pub fn generate(
    cases: &[Case],
    threads: usize,
) -> Result<Vec<capstan_data::Dataset>, crate::ValidationError> {
    par(cases, threads, |c| {
        c.generate()
            .map(|x| x.0)
            .map_err(|cause| crate::ValidationError::NotSimulated {
                case: format!("case {}", c.describe()),
                cause,
            })
    })
    .into_iter()
    .collect()
}

/// Diagnose every generated data set with `diagnose`; outcomes in case order.
pub fn evaluate(
    cases: &[Case],
    data: &[capstan_data::Dataset],
    threads: usize,
    diagnose: impl Fn(&capstan_data::Dataset) -> Diagnosis + Sync,
) -> Vec<Outcome> {
    let pairs: Vec<(&Case, &capstan_data::Dataset)> = cases.iter().zip(data).collect();
    par(&pairs, threads, |(c, d)| outcome(c, d, &diagnose))
}

/// Simulate and diagnose every case (see [`generate`], [`evaluate`]).
pub fn run(
    cases: &[Case],
    threads: usize,
    diagnose: impl Fn(&capstan_data::Dataset) -> Diagnosis + Sync,
) -> Result<Vec<Outcome>, crate::ValidationError> {
    let data = generate(cases, threads)?;
    Ok(evaluate(cases, &data, threads, diagnose))
}

fn outcome(
    case: &Case,
    data: &capstan_data::Dataset,
    diagnose: &dyn Fn(&capstan_data::Dataset) -> Diagnosis,
) -> Outcome {
    Outcome {
        runs_short: case.runs_short(data),
        ..judge(case, data.pairs.len(), &diagnose(data))
    }
}

/// The outcome of the answer `d` on `case` (whose data have `rows` rows).
pub fn judge(case: &Case, rows: usize, d: &Diagnosis) -> Outcome {
    Outcome {
        class: case.class,
        truth: case.effects.clone(),
        outside: case.outside.map(|o| o.0),
        found: d.found_effects(),
        unexplained: d.unexplained,
        pattern: d.residual_pattern,
        rivals: d
            .rivals
            .iter()
            .map(|r| (r.instead_of_kind, r.kind, r.delta_bic))
            .collect(),
        describe: case.describe(),
        candidates: d
            .candidates
            .iter()
            .take(4)
            .map(|c| {
                format!(
                    "{}={:.4e} ({:.1}{})",
                    c.effect,
                    c.value,
                    c.delta_bic,
                    if c.selected { "*" } else { "" }
                )
            })
            .collect::<Vec<_>>()
            .join(", "),
        rows,
        elapsed_s: d.elapsed_s,
        runs_short: (0, 0),
    }
}

/// Per effect: (kind, named exactly, cases) over single cases of `class`.
pub fn per_effect(outcomes: &[Outcome], class: Class) -> Vec<(EffectKind, usize, usize)> {
    EffectKind::ALL
        .into_iter()
        .skip(1)
        .map(|k| {
            let of: Vec<&Outcome> = outcomes
                .iter()
                .filter(|o| o.class == class && o.truth_kinds() == [k])
                .collect();
            (k, of.iter().filter(|o| o.correct()).count(), of.len())
        })
        .collect()
}
