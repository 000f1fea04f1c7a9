//! The held-out prediction of a new cord by the whole procedure: for every cord, the causes
//! are chosen again without it (the evidence engine on the other cords), the
//! population-averaged model with those causes is fitted to the other cords by least squares
//! in T2, and the cord is predicted by it. Selection outside the folds would flatter the
//! held-out figure (the causes were chosen knowing the cord); a new cord's own mu is unknown,
//! so it is predicted by the curve averaged over cords, not at the typical cord (u = 0) of the
//! mixed model, whose curve is not the mean of the cords' curves.
//!
//! A fold that fails (its fit does not converge, or its prediction is not finite) is never a
//! held-out success: its cords have no prediction and are named, with why.

use super::models;
use crate::evidence::{self, Options as EvidenceOptions};
use crate::fit::par::par_map;
use crate::fit::solve::{fit_fixed_with, loco::folds, Budget, Fit};
use crate::fit::Observations;
use capstan_data::Dataset;
use serde::Serialize;

/// Above this many rows the causes are chosen once on all the data, not again in every fold
/// (the engine's selection on a million rows takes seconds; ten of them would take the
/// analysis past its budget). The held-out figure then says so.
pub const SELECTION_IN_FOLDS_MAX_ROWS: usize = 20_000;

/// Work units a fold's population fit may spend per training row.
const UNITS_PER_ROW: u64 = 250;

/// One fold: the cords it held out, the causes chosen without them, and why it failed if it
/// did.
#[derive(Clone, Debug, Serialize)]
pub struct Fold {
    /// The cords held out (labels).
    pub cords: Vec<String>,
    /// The causes the engine named without them.
    pub causes: Vec<&'static str>,
    /// Why the fold failed (its cords have no held-out prediction), if it did.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub failed: Option<String>,
}

/// The whole procedure left out cord by cord.
#[derive(Clone, Debug)]
pub struct WholeLoco {
    /// Held-out prediction of every row, N (NaN for the rows of failed folds).
    pub t2_n: Vec<f64>,
    /// The folds.
    pub folds: Vec<Fold>,
    /// Where the causes were chosen: `inside every fold`, or outside with why.
    pub selection: String,
}

/// The rows of `ds` that `keep` takes (by row index), as a data set with the same columns
/// (its text columns too: the cord labels that tell its cords apart), its structure found again.
pub fn subset(
    ds: &Dataset,
    keep: impl Fn(usize) -> bool,
) -> Result<Dataset, capstan_data::DataError> {
    let rows: Vec<usize> = (0..ds.pairs.len()).filter(|&i| keep(i)).collect();
    let pairs: Vec<_> = rows.iter().map(|&i| ds.pairs[i].clone()).collect();
    let lines: Vec<u64> = rows.iter().map(|&i| ds.lines[i]).collect();
    let structure =
        capstan_data::Structure::infer(&pairs, &ds.header, &ds.label_columns, &lines, &ds.source)?;
    Ok(Dataset {
        source: ds.source.clone(),
        header: ds.header.clone(),
        extra_columns: ds.extra_columns.clone(),
        label_columns: ds.label_columns.clone(),
        pairs,
        lines,
        structure,
    })
}

/// The cords of groups `held` removed from `ds` (rows in file order), as a data set.
fn without(ds: &Dataset, obs: &Observations, held: &[usize]) -> Option<Dataset> {
    subset(ds, |i| !held.contains(&obs.rows[i].group)).ok()
}

/// The whole procedure without each cord (at most [`crate::fit::solve::loco::MAX_FOLDS`]
/// folds), on up to `threads` threads. `in_sample` is the engine's assessment of all the data
/// (its causes are used in every fold above [`SELECTION_IN_FOLDS_MAX_ROWS`] rows).
pub fn whole_procedure(
    ds: &Dataset,
    obs: &Observations,
    in_sample: &evidence::Assessment,
    opts: &EvidenceOptions,
    threads: usize,
) -> WholeLoco {
    let inside = obs.len() <= SELECTION_IN_FOLDS_MAX_ROWS;
    // Leaving one cord out needs two: with one there is no fold (and no held-out prediction).
    let fold_sets = if obs.groups.len() >= 2 {
        folds(obs.groups.len())
    } else {
        Vec::new()
    };
    let one = EvidenceOptions {
        threads: 1,
        ..*opts
    };
    let results = par_map(&fold_sets, threads, |held: &Vec<usize>| {
        fold(ds, obs, held, (inside, in_sample, &one))
    });
    let mut t2 = vec![f64::NAN; obs.len()];
    let mut out = Vec::new();
    for (held, (pred, f)) in fold_sets.iter().zip(results) {
        if f.failed.is_none() {
            for g in held {
                for i in obs.rows_of_group(*g) {
                    t2[i] = pred[i];
                }
            }
        }
        out.push(f);
    }
    WholeLoco {
        t2_n: t2,
        folds: out,
        selection: if inside {
            "inside every fold: the evidence engine chose the causes again without the held-out cord".into()
        } else {
            format!(
                "outside the folds: with {} rows (more than {SELECTION_IN_FOLDS_MAX_ROWS}) the causes are the ones chosen on all the data, so the held-out figure flatters the procedure slightly",
                obs.len()
            )
        },
    }
}

/// One fold: choose the causes without `held`, fit the population model to the rest, predict
/// `held`'s rows (NaN elsewhere).
fn fold(
    ds: &Dataset,
    obs: &Observations,
    held: &[usize],
    (inside, in_sample, opts): (bool, &evidence::Assessment, &EvidenceOptions),
) -> (Vec<f64>, Fold) {
    let labels: Vec<String> = held.iter().map(|&g| obs.groups[g].label.clone()).collect();
    let fail = |why: String, causes: Vec<&'static str>| {
        (
            vec![f64::NAN; obs.len()],
            Fold {
                cords: labels.clone(),
                causes,
                failed: Some(why),
            },
        )
    };
    let assessed;
    let a = if inside {
        let train = without(ds, obs, held).filter(|t| crate::analysis::enough_rows(t).is_ok());
        let Some(train) = train else {
            return fail(
                "the other cords are too few rows to analyse".into(),
                Vec::new(),
            );
        };
        assessed = evidence::assess(&train, opts);
        &assessed
    } else {
        in_sample
    };
    let causes: Vec<&'static str> = a.selected_evidence().iter().map(|e| e.effect).collect();
    let spec = models::population(a);
    let train: Vec<usize> = (0..obs.runs.len())
        .filter(|&r| !held.contains(&obs.rows[obs.runs[r][0]].group))
        .collect();
    let rows = obs.rows_of(&train).len();
    let budget = Budget::for_fit_within(rows, spec.free.len(), UNITS_PER_ROW * rows as u64);
    let fit: Fit = fit_fixed_with(&spec, obs, &train, None, &budget);
    if let Some(why) = fit.stopped {
        return fail(why, causes);
    }
    let test: Vec<usize> = held.iter().flat_map(|&g| obs.runs_of_group(g)).collect();
    let pred = fit.predict(obs, &test, false);
    let bad = obs
        .rows_of(&test)
        .into_iter()
        .find(|&i| !pred[i].is_finite());
    if let Some(i) = bad {
        let r = &obs.rows[i];
        return fail(
            format!(
                "its prediction is not finite (T1 = {} N at {}°)",
                r.t1_n,
                r.op.wrap_rad.to_degrees()
            ),
            causes,
        );
    }
    (
        pred,
        Fold {
            cords: labels,
            causes,
            failed: None,
        },
    )
}
