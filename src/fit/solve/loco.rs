//! Leave one group (cord) out: refit on the others, predict the held-out group with the
//! population values (u = 0).

use super::result::Fit;
use crate::fit::obs::Observations;
use crate::fit::par::par_map;
use crate::fit::stats::jackknife_se;
use serde::Serialize;

/// Result of a leave-one-group-out run.
#[derive(Clone, Debug, Serialize)]
pub struct Loco {
    /// Held-out prediction of every row (its cord left out, population values), N.
    pub t2_n: Vec<f64>,
    /// Pooled RMSE over the rows with a held-out prediction, N.
    pub rmse: f64,
    /// Fitted values per fold (fold g = group g held out).
    pub fold_values: Vec<Vec<(&'static str, f64)>>,
}

impl Loco {
    /// Jackknife standard error of each fitted value over the folds.
    pub fn jackknife_se(&self) -> Vec<(&'static str, f64)> {
        let Some(first) = self.fold_values.first() else {
            return Vec::new();
        };
        (0..first.len())
            .map(|k| {
                let vals: Vec<f64> = self.fold_values.iter().map(|f| f[k].1).collect();
                (first[k].0, jackknife_se(&vals))
            })
            .collect()
    }
}

/// Leave each group out in turn: `refit(training_runs)` fits on the others, and the held-out
/// rows are predicted by the population model (u = 0). Folds run on up to `threads` threads.
pub fn loco<F>(obs: &Observations, threads: usize, refit: F) -> Loco
where
    F: Fn(&[usize]) -> Fit + Sync,
{
    let groups: Vec<usize> = (0..obs.groups.len()).collect();
    let folds = par_map(&groups, threads, |&g| {
        let fit = refit(&obs.runs_without_group(g));
        (fit.predict(obs, &obs.runs_of_group(g), false), fit.values())
    });
    let mut t2 = vec![f64::NAN; obs.rows.len()];
    let mut fold_values = Vec::new();
    for (pred, values) in folds {
        for (t, p) in t2.iter_mut().zip(pred) {
            if p.is_finite() && !t.is_finite() {
                *t = p;
            }
        }
        fold_values.push(values);
    }
    Loco {
        rmse: obs.rmse_t2(&t2),
        t2_n: t2,
        fold_values,
    }
}
