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
    /// Fitted values per fold that converged (in fold order).
    pub fold_values: Vec<Vec<(&'static str, f64)>>,
    /// The folds whose fit did not converge: (the group held out, why). Their rows have no
    /// held-out prediction and their values are not in `fold_values`: the analysis goes on
    /// without them.
    pub did_not_converge: Vec<(usize, String)>,
}

impl Loco {
    /// No fold run (the in-sample fit they would start from did not converge): every cord is
    /// listed as not converged.
    pub fn skipped(obs: &Observations) -> Loco {
        Loco {
            t2_n: vec![f64::NAN; obs.rows.len()],
            rmse: f64::NAN,
            fold_values: Vec::new(),
            did_not_converge: (0..obs.groups.len())
                .map(|g| {
                    (
                        g,
                        "not run: the in-sample fit it would start from did not converge"
                            .to_string(),
                    )
                })
                .collect(),
        }
    }

    /// Jackknife standard error of each fitted value over the folds (a grouped jackknife
    /// when the folds hold several groups).
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

/// The most folds: with more groups than this, fold k leaves out the groups g with
/// g mod [`MAX_FOLDS`] = k (every group is still held out once, predicted by a fit without
/// it), so the number of refits, and the work, stays bounded whatever the number of cords.
pub const MAX_FOLDS: usize = 12;

/// The folds of `groups` groups: each fold's held-out groups.
pub fn folds(groups: usize) -> Vec<Vec<usize>> {
    let k = groups.min(MAX_FOLDS);
    (0..k).map(|f| (f..groups).step_by(k).collect()).collect()
}

/// Leave each group out in turn (with more than [`MAX_FOLDS`] groups, one fold of them at a
/// time): `refit(training_runs)` fits on the others, and the held-out rows are predicted by
/// the population model (u = 0). Folds run on up to `threads` threads. A fold whose fit does
/// not converge is left out (and its groups listed).
pub fn loco<F>(obs: &Observations, threads: usize, refit: F) -> Loco
where
    F: Fn(&[usize]) -> Fit + Sync,
{
    loco_over(obs, threads, &folds(obs.groups.len()), refit)
}

/// [`loco`] with the folds given: each a set of groups left out together.
pub fn loco_over<F>(obs: &Observations, threads: usize, folds: &[Vec<usize>], refit: F) -> Loco
where
    F: Fn(&[usize]) -> Fit + Sync,
{
    let results = par_map(folds, threads, |held: &Vec<usize>| {
        let train: Vec<usize> = (0..obs.runs.len())
            .filter(|&r| !held.contains(&obs.rows[obs.runs[r][0]].group))
            .collect();
        let fit = refit(&train);
        let test: Vec<usize> = held.iter().flat_map(|&g| obs.runs_of_group(g)).collect();
        match fit.stopped {
            None => Ok((fit.predict(obs, &test, false), fit.values())),
            Some(why) => Err((held.clone(), why)),
        }
    });
    let mut t2 = vec![f64::NAN; obs.rows.len()];
    let mut fold_values = Vec::new();
    let mut did_not_converge = Vec::new();
    for fold in results {
        let (pred, values) = match fold {
            Ok(f) => f,
            Err((held, why)) => {
                did_not_converge.extend(held.into_iter().map(|g| (g, why.clone())));
                continue;
            }
        };
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
        did_not_converge,
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn folds_hold_every_group_once_and_are_bounded() {
        assert_eq!(super::folds(3), vec![vec![0], vec![1], vec![2]]);
        let f = super::folds(305);
        assert_eq!(super::folds(12).len(), 12);
        assert_eq!(super::folds(13)[0], vec![0, 12]);
        assert_eq!(f.len(), super::MAX_FOLDS);
        let mut all: Vec<usize> = f.concat();
        all.sort();
        assert_eq!(all, (0..305).collect::<Vec<_>>());
    }
}
