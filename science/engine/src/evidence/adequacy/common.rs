//! Is what is left shared by the cords? The residuals beyond every cord's own parameters,
//! averaged per step over the cords (the step profile they share), against sign flips of whole
//! cords: a pattern every cord has survives the flips' average, a departure of each cord's own
//! does not. Cords are the units, so the test is exact for exchangeable cords (every sign
//! pattern up to [`EXACT_CORDS`] cords, a fixed set of random ones beyond).

use super::super::design::Design;
use serde::Serialize;

/// Every sign pattern is enumerated up to this many cords.
const EXACT_CORDS: usize = 12;
/// Random sign patterns beyond.
const MC_FLIPS: usize = 3999;

/// The step profile the cords share, against sign flips of whole cords.
#[derive(Clone, Debug, Serialize)]
pub struct CommonProfile {
    /// Cords.
    pub cords: usize,
    /// Steps seen on at least two cords.
    pub steps: usize,
    /// p: the share of sign patterns whose profile is at least as large.
    pub p: f64,
    /// RMS per observation of the shared profile beyond what the flips give, over the pure
    /// error's RMS (the lack of fit's scale).
    pub systematic_ratio: f64,
}

/// The shared step profile of the standardised residuals `z` (None with fewer than
/// `min_cords` cords with cells, or fewer than two steps shared).
pub fn common_profile(d: &Design, z: &[f64], min_cords: usize) -> Option<CommonProfile> {
    let n_cells = d.cell_step.len();
    let g = d.cords.len();
    if n_cells == 0 || g < min_cords {
        return None;
    }
    let (mut sum, mut cnt, mut sq) = (
        vec![0.0; n_cells],
        vec![0usize; n_cells],
        vec![0.0; n_cells],
    );
    let mut cord_of_cell = vec![0usize; n_cells];
    for (u, rows) in d.units.iter().enumerate() {
        for &i in rows {
            if let Some(c) = d.cell[i] {
                sum[c] += z[i];
                sq[c] += z[i] * z[i];
                cnt[c] += 1;
                cord_of_cell[c] = d.unit_cord[u];
            }
        }
    }
    // Steps by key, each with the cells (one per cord) that hold it.
    let mut keys: Vec<i64> = d.cell_step.clone();
    keys.sort_unstable();
    keys.dedup();
    let step_of = |c: usize| keys.binary_search(&d.cell_step[c]).unwrap_or(0);
    let mut cells_of: Vec<Vec<usize>> = vec![Vec::new(); keys.len()];
    for c in 0..n_cells {
        if cnt[c] > 0 {
            cells_of[step_of(c)].push(c);
        }
    }
    cells_of.retain(|v| v.len() >= 2);
    let used_cords = {
        let mut seen = vec![false; g];
        for c in cells_of.iter().flatten() {
            seen[cord_of_cell[*c]] = true;
        }
        seen.iter().filter(|&&s| s).count()
    };
    if cells_of.len() < 2 || used_cords < min_cords {
        return None;
    }
    let stat = |sign: &dyn Fn(usize) -> f64| -> f64 {
        cells_of
            .iter()
            .map(|cells| {
                let (s, n) = cells.iter().fold((0.0, 0usize), |(s, n), &c| {
                    (s + sign(cord_of_cell[c]) * sum[c], n + cnt[c])
                });
                s * s / n as f64
            })
            .sum()
    };
    let observed = stat(&|_| 1.0);
    let patterns: Vec<Vec<f64>> = if g <= EXACT_CORDS {
        (0..1u64 << g)
            .map(|m| {
                (0..g)
                    .map(|c| if m >> c & 1 == 1 { -1.0 } else { 1.0 })
                    .collect()
            })
            .collect()
    } else {
        let mut rng = capstan_rng::Rng::new(0xc0_33_0f);
        std::iter::once(vec![1.0; g])
            .chain((0..MC_FLIPS).map(|_| {
                (0..g)
                    .map(|_| if rng.next_u64() >> 63 == 0 { 1.0 } else { -1.0 })
                    .collect()
            }))
            .collect()
    };
    let tol = 1e-12 * observed.abs();
    let (mut above, mut total) = (0usize, 0.0);
    for s in &patterns {
        let t = stat(&|c| s[c]);
        total += t;
        if t >= observed - tol {
            above += 1;
        }
    }
    let null_mean = total / patterns.len() as f64;
    // Pure error: the rows around their cell's mean.
    let (ss_pe, df_pe) = (0..n_cells)
        .filter(|&c| cnt[c] >= 2)
        .fold((0.0, 0.0), |(s, f), c| {
            (
                s + sq[c] - sum[c] * sum[c] / cnt[c] as f64,
                f + (cnt[c] - 1) as f64,
            )
        });
    let n_obs: usize = cells_of.iter().flatten().map(|&c| cnt[c]).sum();
    let ms_pe = ss_pe / df_pe.max(1.0);
    let systematic = ((observed - null_mean).max(0.0) / n_obs as f64).sqrt();
    Some(CommonProfile {
        cords: used_cords,
        steps: cells_of.len(),
        p: above as f64 / patterns.len() as f64,
        systematic_ratio: if ms_pe > 0.0 {
            systematic / ms_pe.sqrt()
        } else {
            f64::NAN
        },
    })
}
