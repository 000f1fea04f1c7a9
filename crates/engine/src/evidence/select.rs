//! Forward selection of the within-run effects: start from every run's own mu (Euler-Eytelwein
//! in shape), add the best-fitting of the candidates supported given those already in, drop any earlier one that no longer is, and report every candidate's evidence
//! given the final set (the selected ones by dropping each, the others by adding each).
//!
//! The evidence of one parameter is a quasi-likelihood ratio: the weighted likelihood ratio
//! LR = n·ln(WRSS_without / WRSS_with), divided by the parameter's overdispersion ĉ (its
//! cluster-robust variance over its model-based variance, runs as clusters, at least 1), put
//! on the χ²₁ scale through the F(1, G − 1) distribution (ĉ is estimated from G runs), and
//! ΔBIC = −χ² + ln n.

use super::candidates::{practically_relevant, ThetaMap};
use super::design::Design;
use super::within::{fit_multistart, Weights, WithinFit};
use super::Evidence;
use crate::fit::stats::chi2_of_f;
use capstan_friction::EffectKind;

/// Most within-run effects named at once. Data that want more than three catalogue effects at
/// once are better described as holding something the catalogue does not have: what is left
/// after three goes to the adequacy check, which then says so (and the fits stay fast).
pub const MAX_WITHIN: usize = 3;

/// Evidence for parameter `j` of `with` against `without` (the same set without it).
fn evidence(d: &Design, without: &WithinFit, with: &WithinFit, j: usize) -> Evidence {
    let n = d.n() as f64;
    let g = d.units.len() as f64;
    let lr = (n * (without.wrss / with.wrss).ln()).max(0.0);
    let c_hat = with.c_hat(j);
    let chi2 = chi2_of_f(lr / c_hat, 1.0, (g - 1.0).max(1.0));
    let kind = with.maps[j].kind;
    let mut e = Evidence::new(
        kind,
        with.value(j),
        with.se_robust(j),
        -chi2 + n.ln(),
        chi2,
        g - 1.0,
    );
    e.overdispersion = c_hat;
    e.relevant = practically_relevant(kind, e.value, d);
    e
}

/// `fit`'s set with `kind` added, the others warm. Its θ starts from `start` if given (its
/// value when it was fitted alone), else from each of its start values.
fn add(
    d: &Design,
    fit: &WithinFit,
    kind: EffectKind,
    w: &Weights,
    start: Option<f64>,
) -> WithinFit {
    let mut maps = fit.maps.clone();
    maps.push(ThetaMap::for_kind(kind, d));
    let mut theta = fit.theta.clone();
    match start {
        Some(t) => {
            theta.push(t);
            super::within::fit(d, &maps, &theta, &fit.mu, w)
        }
        None => {
            theta.push(0.0);
            fit_multistart(d, &maps, &theta, &fit.mu, w)
        }
    }
}

/// `fit`'s set without parameter `j` (warm start).
fn drop(d: &Design, fit: &WithinFit, j: usize, w: &Weights) -> WithinFit {
    let keep: Vec<usize> = (0..fit.k()).filter(|&x| x != j).collect();
    let maps: Vec<ThetaMap> = keep.iter().map(|&x| fit.maps[x]).collect();
    let theta: Vec<f64> = keep.iter().map(|&x| fit.theta[x]).collect();
    super::within::fit(d, &maps, &theta, &fit.mu, w)
}

/// Stepwise refinement by swaps: replace one selected effect by an unselected one when the
/// set then fits better and every member is still supported. Forward selection's first pick
/// is the single effect that best mimics the whole truth (a power law standing in for heating
/// plus a T1 loss, say); a swap lets the pair that is really there win on fit.
fn swaps(
    d: &Design,
    mut current: WithinFit,
    candidates: &[EffectKind],
    w: &Weights,
    supported: &(dyn Fn(&Evidence) -> bool + Sync),
    alone: &[(EffectKind, f64)],
    threads: usize,
) -> (WithinFit, Vec<Swap>) {
    // Two passes may each take a swap; a third only fits the final set's alternatives.
    for pass in 0..3 {
        // One effect alone is already the best-fitting single one: only sets can improve.
        let k = current.k();
        if k < 2 {
            break;
        }
        let options: Vec<(usize, EffectKind)> = (0..k)
            .flat_map(|j| {
                candidates
                    .iter()
                    .copied()
                    .filter(|c| !current.maps.iter().any(|m| m.kind == *c))
                    .map(move |c| (j, c))
            })
            .collect();
        let fits: Vec<WithinFit> = par(&options, threads, |&(j, c)| {
            let mut maps = current.maps.clone();
            let mut theta = current.theta.clone();
            maps[j] = ThetaMap::for_kind(c, d);
            theta[j] = alone
                .iter()
                .find(|a| a.0 == c)
                .map_or(maps[j].theta(c.neutral_value()), |a| a.1);
            super::within::fit(d, &maps, &theta, &current.mu, w)
        });
        let mut better: Vec<usize> = (0..fits.len())
            .filter(|&i| fits[i].wrss < current.wrss * (1.0 - 1e-9))
            .collect();
        better.sort_by(|&a, &b| fits[a].wrss.total_cmp(&fits[b].wrss));
        let accepted = better.into_iter().filter(|_| pass < 2).find(|&i| {
            let cand = &fits[i];
            let members: Vec<usize> = (0..cand.k()).collect();
            par(&members, threads, |&j| {
                let less = drop(d, cand, j, w);
                supported(&evidence(d, &less, cand, j))
            })
            .into_iter()
            .all(|s| s)
        });
        let Some(b) = accepted else {
            // No swap is taken: these fits are the final set's alternatives.
            let alternatives = options
                .iter()
                .zip(&fits)
                .map(|(&(slot, kind), f)| Swap {
                    slot,
                    kind,
                    wrss: f.wrss,
                    value: f.value(slot),
                })
                .collect();
            return (current, alternatives);
        };
        current = fits.into_iter().nth(b).expect("index in range");
    }
    (current, Vec::new())
}

/// The final set with one of its within-run effects replaced by another candidate.
#[derive(Clone, Copy, Debug)]
pub struct Swap {
    /// The position (θ index) of the selected effect replaced.
    pub slot: usize,
    /// The candidate in its place.
    pub kind: EffectKind,
    /// WRSS of that set.
    pub wrss: f64,
    /// The candidate's fitted catalogue value there.
    pub value: f64,
}

/// The effects of a fit, in θ order.
fn kinds(f: &WithinFit) -> Vec<EffectKind> {
    f.maps.iter().map(|m| m.kind).collect()
}

/// Run `f` over `items` on up to `threads` threads, results in input order.
fn par<T: Sync, R: Send>(items: &[T], threads: usize, f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    crate::fit::par::par_map(items, threads, f)
}

/// The result of the within-run selection.
pub struct WithinSelection {
    /// The final fit (the selected effects, in the order they came in).
    pub fit: WithinFit,
    /// Every testable candidate's evidence given the final set.
    pub evidence: Vec<Evidence>,
    /// The order in which effects were added, with their ΔBIC when added.
    pub path: Vec<(EffectKind, f64)>,
    /// Every candidate's evidence alone (added to every run's own mu, no other effect).
    pub alone: Vec<Evidence>,
    /// The final set with each selected effect replaced by each other candidate, where known
    /// (every such set when one effect is selected; the swap search's last pass otherwise).
    pub swaps: Vec<Swap>,
}

/// Forward selection from `null` over `candidates`. A candidate is supported when it is
/// practically relevant and its ΔBIC is below −`threshold`.
pub fn forward(
    d: &Design,
    null: WithinFit,
    candidates: &[EffectKind],
    w: &Weights,
    threshold: f64,
    threads: usize,
) -> WithinSelection {
    let supported = |e: &Evidence| e.relevant && e.delta_bic < -threshold;
    let mut last: Vec<Evidence> = Vec::new();
    // The set `last` was computed against (it is reused when the selection ends there).
    let mut last_for: Vec<EffectKind> = Vec::new();
    let mut current = null;
    let mut path = Vec::new();
    // An effect that a later one made redundant does not come back (stepwise selection can
    // otherwise cycle), so the loop ends after at most two rounds per candidate.
    let mut retired: Vec<EffectKind> = Vec::new();
    // Each candidate's θ when fitted alone (from all its starts): later rounds start there.
    let mut alone: Vec<(EffectKind, f64)> = Vec::new();
    let mut alone_evidence: Vec<Evidence> = Vec::new();
    let mut alone_fits: Vec<Swap> = Vec::new();
    let start_of =
        |alone: &[(EffectKind, f64)], k: EffectKind| alone.iter().find(|a| a.0 == k).map(|a| a.1);
    for _round in 0..=2 * candidates.len() {
        if current.k() >= MAX_WITHIN {
            // Structure beyond this many effects at once is left to the adequacy check.
            break;
        }
        let pool: Vec<EffectKind> = candidates
            .iter()
            .copied()
            .filter(|&k| !current.maps.iter().any(|m| m.kind == k) && !retired.contains(&k))
            .collect();
        let fits: Vec<WithinFit> = par(&pool, threads, |&k| {
            add(d, &current, k, w, start_of(&alone, k))
        });
        if alone.is_empty() {
            alone = fits.iter().map(|f| (f.maps[0].kind, f.theta[0])).collect();
            alone_fits = fits
                .iter()
                .map(|f| Swap {
                    slot: 0,
                    kind: f.maps[0].kind,
                    wrss: f.wrss,
                    value: f.value(0),
                })
                .collect();
        }
        let first_round = alone_evidence.is_empty();
        last = fits
            .iter()
            .map(|f| evidence(d, &current, f, f.k() - 1))
            .collect();
        last_for = kinds(&current);
        if first_round {
            alone_evidence = last.clone();
            for e in &mut alone_evidence {
                e.supported = supported(e);
            }
        }
        // Among the supported candidates the best fit comes in: each one's overdispersion
        // decides whether it is supported, not which of two rival shapes the data prefer.
        let best = (0..fits.len())
            .filter(|&i| supported(&last[i]))
            .min_by(|&a, &b| fits[a].wrss.total_cmp(&fits[b].wrss));
        let Some(b) = best else { break };
        path.push((pool[b], last[b].delta_bic));
        current = fits.into_iter().nth(b).expect("index in range");
        // An earlier effect that the new one makes redundant leaves again.
        while current.k() > 1 {
            let earlier: Vec<usize> = (0..current.k() - 1).collect();
            let drops: Vec<(WithinFit, Evidence)> = par(&earlier, threads, |&j| {
                let less = drop(d, &current, j, w);
                let e = evidence(d, &less, &current, j);
                (less, e)
            });
            let weakest = (0..drops.len())
                .filter(|&j| !supported(&drops[j].1))
                .max_by(|&a, &b| drops[a].1.delta_bic.total_cmp(&drops[b].1.delta_bic));
            match weakest {
                Some(j) => {
                    retired.push(current.maps[j].kind);
                    current = drops.into_iter().nth(j).expect("index in range").0;
                }
                None => break,
            }
        }
    }
    let (fit, mut alternatives) = swaps(d, current, candidates, w, &supported, &alone, threads);
    current = fit;
    if current.k() == 1 {
        // One effect: its alternatives are the other candidates alone.
        alternatives = alone_fits
            .into_iter()
            .filter(|a| a.kind != current.maps[0].kind)
            .collect();
    }
    // The selected effects, each given the others, and every other candidate added to the
    // final set (recomputed if the last round's were against another set: the selection
    // stopped at its cap, or an effect left): one batch of fits.
    let recompute = last_for != kinds(&current) || last.len() + current.k() < candidates.len();
    let mut jobs: Vec<Option<EffectKind>> = (0..current.k()).map(|_| None).collect();
    if recompute {
        jobs.extend(
            candidates
                .iter()
                .filter(|&&k| !current.maps.iter().any(|m| m.kind == k))
                .map(|&k| Some(k)),
        );
    }
    let mut evidence: Vec<Evidence> =
        par(
            &(0..jobs.len()).collect::<Vec<_>>(),
            threads,
            |&x| match jobs[x] {
                None => {
                    let less = drop(d, &current, x, w);
                    let mut e = evidence(d, &less, &current, x);
                    e.selected = true;
                    e
                }
                Some(k) => {
                    let f = add(d, &current, k, w, start_of(&alone, k));
                    evidence(d, &current, &f, f.k() - 1)
                }
            },
        );
    if !recompute {
        evidence.extend(last);
    }
    for e in &mut evidence {
        e.supported = supported(e);
    }
    WithinSelection {
        fit: current,
        evidence,
        path,
        alone: alone_evidence,
        swaps: alternatives,
    }
}
