//! `capstan analyze --validate`: the whole analysis on data sets where the truth was planted,
//! generated end to end by the firmware-in-the-loop simulator with the thesis rig's noise
//! (`crate::truth::cases`): no effect; each mechanism the report can name, twice; the
//! two-mechanism truth the thesis data suggest (contact heating + a T1-path loss); and physics
//! the report cannot name (direction hysteresis, an S-shaped T2 calibration error, a friction
//! regime change). 40 data sets per seed.
//!
//! Targets: the causes named equal the causes planted in ≥ 90 % of the sets with catalogue
//! truths (clean ones included); a cause named, or structure flagged, on a clean set in ≤ 5 %;
//! structure outside the catalogue reported as unexplained in ≥ 80 % of those sets. Each set is
//! scored by the diagnose suite's scorer ([`crate::score::judge`]) on the verdicts the analysis
//! renders.

use crate::cases::{draw_case, Case, Class};
use crate::{score, ValidationError};
use capstan_engine::analysis::{run, Options};
use serde::Serialize;

/// The planted cases of `seed`: 8 clean, 2 of each catalogue mechanism, 6 heating + T1-path
/// loss, 6 outside the catalogue.
pub fn cases(seed: u64) -> Vec<Case> {
    let mut v: Vec<Case> = (0..8).map(|i| draw_case(seed, Class::Clean, i)).collect();
    v.extend((0..20).map(|i| draw_case(seed, Class::Single, i)));
    // Every fifth pair is the thesis's heating + T1-path loss.
    v.extend((0..6).map(|i| draw_case(seed, Class::Pair, 5 * i)));
    v.extend((0..6).map(|i| draw_case(seed, Class::Outside, i)));
    v
}

/// What the analysis named on one planted data set.
#[derive(Clone, Debug, Serialize)]
pub struct Outcome {
    /// The case.
    pub case: String,
    /// Planted catalogue effects.
    pub planted: Vec<&'static str>,
    /// Planted physics outside the catalogue.
    pub outside: Option<&'static str>,
    /// The causes the report names.
    pub named: Vec<&'static str>,
    /// The report says structure is left unexplained.
    pub unexplained: bool,
    /// The answer is right: the named causes are the planted ones and nothing is flagged, or,
    /// for physics outside the catalogue, the structure is flagged unexplained.
    pub correct: bool,
    /// A cause named or structure flagged (an alarm on a clean set).
    #[serde(skip)]
    pub alarm: bool,
    /// Wall time of the analysis, s.
    pub elapsed_s: f64,
}

/// The validation's figures.
#[derive(Clone, Debug, Serialize)]
pub struct Validation {
    /// Master seed.
    pub seed: u64,
    /// Every data set.
    pub outcomes: Vec<Outcome>,
    /// Sets with catalogue truths (clean included) named exactly.
    pub named_exactly: (usize, usize),
    /// Clean sets with a cause named or structure flagged.
    pub clean_alarms: (usize, usize),
    /// Sets outside the catalogue flagged unexplained.
    pub outside_flagged: (usize, usize),
}

impl Validation {
    /// Why the figures miss the targets (empty: they meet them).
    pub fn failures(&self) -> Vec<String> {
        let f = |x: (usize, usize)| x.0 as f64 / x.1.max(1) as f64;
        let mut why = Vec::new();
        if f(self.named_exactly) < 0.9 {
            why.push(format!(
                "causes named exactly in {}/{} < 90 %",
                self.named_exactly.0, self.named_exactly.1
            ));
        }
        if f(self.clean_alarms) > 0.05 {
            why.push(format!(
                "clean sets with an alarm {}/{} > 5 %",
                self.clean_alarms.0, self.clean_alarms.1
            ));
        }
        if f(self.outside_flagged) < 0.8 {
            why.push(format!(
                "outside the catalogue flagged in {}/{} < 80 %",
                self.outside_flagged.0, self.outside_flagged.1
            ));
        }
        why
    }
}

fn analyse(case: &Case, opts: Options) -> Result<Outcome, ValidationError> {
    let (data, _) = case.generate().map_err(|cause| ValidationError::Case {
        case: case.describe(),
        cause,
    })?;
    let t = std::time::Instant::now();
    let a = run(&data, opts).map_err(ValidationError::Analysis)?;
    // The causes the report names are the verdict layer's named effects, which the analysis
    // renders as its diagnosis too.
    let o = score::judge(case, data.pairs.len(), &a.evidence);
    Ok(Outcome {
        case: o.describe.clone(),
        planted: o.truth_kinds().iter().map(|k| k.name()).collect(),
        outside: o.outside,
        named: o.found_kinds().iter().map(|k| k.name()).collect(),
        unexplained: o.unexplained,
        correct: o.correct(),
        alarm: o.alarm(),
        elapsed_s: t.elapsed().as_secs_f64(),
    })
}

/// Run the whole analysis on every planted case of `seed` (`every`: take every this-many-th
/// case, 1 for all), `threads` cases at a time.
pub fn validate(seed: u64, every: usize, threads: usize) -> Result<Validation, ValidationError> {
    let cs: Vec<Case> = cases(seed)
        .into_iter()
        .enumerate()
        .filter(|(i, _)| i % every.max(1) == 0)
        .map(|x| x.1)
        .collect();
    let opts = Options {
        threads: 1,
        ..Options::default()
    };
    let results = capstan_engine::fit::par::par_map(&cs, threads, |c| analyse(c, opts));
    let outcomes: Vec<Outcome> = results.into_iter().collect::<Result<_, _>>()?;
    let count = |f: &dyn Fn(&Outcome) -> bool, keep: &dyn Fn(&Outcome) -> bool| {
        let of: Vec<&Outcome> = outcomes.iter().filter(|o| keep(o)).collect();
        (of.iter().filter(|o| f(o)).count(), of.len())
    };
    let catalogue = |o: &Outcome| o.outside.is_none();
    Ok(Validation {
        seed,
        named_exactly: count(&|o| o.correct, &catalogue),
        clean_alarms: count(&|o| o.alarm, &|o| {
            o.outside.is_none() && o.planted.is_empty()
        }),
        outside_flagged: count(&|o| o.unexplained, &|o| o.outside.is_some()),
        outcomes,
    })
}
