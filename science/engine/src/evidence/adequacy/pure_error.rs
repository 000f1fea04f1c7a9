//! The lack-of-fit test against the replicate runs' pure error, its p from sign flips of
//! whole runs (see the parent module's docs).

use super::super::design::Design;
use super::LackOfFit;
use capstan_rng::Rng;

/// Sign-flip replications of the lack-of-fit statistic.
const FLIPS: usize = 1999;

/// The smallest p the wild bootstrap can give: no flip as large, 1/(FLIPS + 1).
pub const P_FLOOR: f64 = 1.0 / (FLIPS as f64 + 1.0);

/// The pure-error lack-of-fit test (None without at least 4 replicated cells).
///
/// F = MS_LOF/MS_PE as in Draper & Smith, but its p comes from flipping the sign of whole
/// runs' residual vectors (a wild cluster bootstrap with Rademacher weights, Cameron, Gelbach
/// & Miller 2008): the runs' residuals are correlated from step to step (a run's tare, the
/// wander of its mu), which makes the cell means of a cord move together and the nominal F
/// distribution far too narrow; flipping whole runs keeps that correlation and destroys only a
/// pattern the runs share.
/// The lack-of-fit test alone, on standardised residuals `z` (residual × √weight per row) of
/// a model with `k` shared parameters: the replicate runs' pure error against what the cells
/// share (sign flips of whole runs). `None` without at least four replicated cells. Used by
/// `capstan discover` to ask whether a proposed term resolves what the catalogue leaves.
pub fn lack_of_fit(d: &Design, z: &[f64], k: usize) -> Option<LackOfFit> {
    pure_error(d, z, k).filter(|l| [l.f, l.p, l.systematic_ratio].iter().all(|v| v.is_finite()))
}

pub(super) fn pure_error(d: &Design, z: &[f64], k: usize) -> Option<LackOfFit> {
    let signed = |signs: &[f64], out: &mut [f64]| {
        for (u, rows) in d.units.iter().enumerate() {
            for &i in rows {
                out[i] = z[i] * signs[u];
            }
        }
    };
    pure_error_with(d, k, &signed)
}

/// The residuals made from every run's sign (all +1: the observed ones), written to `out`.
pub(crate) type Signed<'a> = &'a dyn Fn(&[f64], &mut [f64]);

/// [`pure_error`] of the residuals `signed` makes for every run's sign: the flips go through
/// whatever the residuals were made by, e.g. every cord's own parameters fitted to the flipped
/// runs again ([`crate::evidence::cords`]).
pub(crate) fn pure_error_with(d: &Design, k: usize, signed: Signed<'_>) -> Option<LackOfFit> {
    let mut z = vec![0.0; d.n()];
    signed(&vec![1.0; d.units.len()], &mut z);
    let n_cells = d.cell.iter().flatten().map(|&c| c + 1).max().unwrap_or(0);
    let mut cnt = vec![0usize; n_cells];
    let mut cord_of_cell = vec![usize::MAX; n_cells];
    for (u, rows) in d.units.iter().enumerate() {
        for &i in rows {
            if let Some(c) = d.cell[i] {
                cnt[c] += 1;
                cord_of_cell[c] = d.unit_cord[u];
            }
        }
    }
    let used: Vec<bool> = cnt.iter().map(|&c| c >= 2).collect();
    let n_used = used.iter().filter(|&&u| u).count();
    if n_used < 4 {
        return None;
    }
    // The rows that enter, with their cell.
    let entries: Vec<(usize, usize)> = (0..d.n())
        .filter_map(|i| d.cell[i].filter(|&c| used[c]).map(|c| (i, c)))
        .collect();
    let ss_lof = |z: &[f64]| {
        let mut sum = vec![0.0; n_cells];
        for &(i, c) in &entries {
            sum[c] += z[i];
        }
        (0..n_cells)
            .filter(|&c| used[c])
            .map(|c| sum[c] * sum[c] / cnt[c] as f64)
            .sum::<f64>()
    };
    let observed = ss_lof(&z);
    let mut mean = vec![0.0; n_cells];
    for &(i, c) in &entries {
        mean[c] += z[i] / cnt[c] as f64;
    }
    let ss_pe: f64 = entries.iter().map(|&(i, c)| (z[i] - mean[c]).powi(2)).sum();
    let df_pe: f64 = (0..n_cells)
        .filter(|&c| used[c])
        .map(|c| (cnt[c] - 1) as f64)
        .sum();
    let cords: std::collections::HashSet<usize> = (0..n_cells)
        .filter(|&c| used[c])
        .map(|c| cord_of_cell[c])
        .collect();
    // No more cell means than the fitted parameters (each cord's own, and `k`): the lack of
    // fit has nothing to test, whatever F reads.
    let saturated = (n_used as f64 - cords.len() as f64 - k as f64) < 1.0;
    let df_lof = (n_used as f64 - cords.len() as f64 - k as f64).max(1.0);
    let ms_pe = ss_pe / df_pe.max(1.0);
    let buf = std::cell::RefCell::new(vec![0.0; d.n()]);
    let (above, null_mean) = flips(d.units.len(), observed, &|signs| {
        let mut b = buf.borrow_mut();
        signed(signs, &mut b);
        ss_lof(&b)
    });
    let n_obs = entries.len() as f64;
    let systematic = ((observed - null_mean).max(0.0) / n_obs).sqrt();
    Some(LackOfFit {
        cells: n_used,
        f: (observed / df_lof) / ms_pe,
        df_lof,
        df_pe,
        p: (above + 1) as f64 / (FLIPS + 1) as f64,
        p_at_floor: above == 0,
        systematic_ratio: systematic / ms_pe.sqrt(),
        saturated,
    })
}

/// The lack of fit's sum of squares of the residuals made with each run's sign.
type SignedLof<'a> = &'a dyn Fn(&[f64]) -> f64;

/// [`FLIPS`] Rademacher flips of whole runs, from a fixed seed (the answer is reproducible):
/// how many give a lack of fit `ss_lof` at least `observed`, and their mean.
fn flips(runs: usize, observed: f64, ss_lof: SignedLof<'_>) -> (usize, f64) {
    let mut rng = Rng::new(0x01ac_0f17);
    let (mut above, mut total) = (0usize, 0.0);
    let mut signs = vec![1.0; runs];
    for _ in 0..FLIPS {
        for s in signs.iter_mut() {
            *s = if rng.next_u64() >> 63 == 0 { 1.0 } else { -1.0 };
        }
        let t = ss_lof(&signs);
        total += t;
        if t >= observed {
            above += 1;
        }
    }
    (above, total / FLIPS as f64)
}
