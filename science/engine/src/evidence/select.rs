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
use capstan_physics::EffectKind;

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
        se_if_defined(with, j, g),
        -chi2 + n.ln(),
        chi2,
        g - 1.0,
    );
    e.overdispersion = c_hat;
    e.edge_interval = edge_interval(with, j, g);
    e.relevant = practically_relevant(kind, e.value, d);
    e
}

/// The cluster-robust standard error of parameter `j`, where it means one: not from one run
/// (a sandwich over one cluster is 0, whatever the data), and not at an edge of the
/// parameter's range (a fit pinned there has no curvature to measure: bending stiffness at
/// b = 0 came out "± 0", which then "excluded" the effect). NaN otherwise: "not identified"
/// in words, null in JSON.
fn se_if_defined(fit: &WithinFit, j: usize, runs: f64) -> f64 {
    if runs < 2.0 || at_edge(fit, j) {
        f64::NAN
    } else {
        fit.se_robust(j)
    }
}

/// θ of parameter `j` sits on an edge of its range.
fn at_edge(fit: &WithinFit, j: usize) -> bool {
    let m = &fit.maps[j];
    let tol = 1e-6 * (m.hi - m.lo);
    let theta = fit.theta[j];
    (theta - m.lo).abs() <= tol || (m.hi - theta).abs() <= tol
}

/// For a parameter on an edge of its range (from two runs up): its 95 % interval in values,
/// the cluster-robust interval of θ (whose predictions move with θ even where the value,
/// θ², does not: bending stiffness at b = 0) cut to θ's range and mapped to values.
fn edge_interval(fit: &WithinFit, j: usize, runs: f64) -> Option<(f64, f64)> {
    if runs < 2.0 || !at_edge(fit, j) {
        return None;
    }
    let k = fit.k();
    let se_theta = fit.cov_robust[j * k + j].max(0.0).sqrt();
    if !se_theta.is_finite() {
        return None;
    }
    let m = &fit.maps[j];
    let ends = [-1.96, 1.96].map(|z| m.value((fit.theta[j] + z * se_theta).clamp(m.lo, m.hi)));
    Some((ends[0].min(ends[1]), ends[0].max(ends[1])))
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

/// What every step of the selection needs: the data, the weights, the threads, and when a
/// candidate counts as supported.
struct Selector<'a> {
    d: &'a Design,
    w: &'a Weights,
    threads: usize,
    supported: &'a (dyn Fn(&Evidence) -> bool + Sync),
}

/// What the first round learns about every candidate alone (added to every run's own mu, no
/// other effect).
#[derive(Default)]
struct Alone {
    /// Each candidate's θ when fitted alone (from all its starts): later rounds start there.
    theta: Vec<(EffectKind, f64)>,
    /// Each candidate's evidence alone, marked supported or not.
    evidence: Vec<Evidence>,
    /// Each candidate alone as a one-effect set (the alternatives when one effect is selected).
    fits: Vec<Swap>,
}

impl Alone {
    /// The first round's `fits` (each candidate added to the null) and their `evidence`.
    fn of(
        fits: &[WithinFit],
        evidence: &[Evidence],
        supported: &(dyn Fn(&Evidence) -> bool + Sync),
    ) -> Alone {
        let mut evidence = evidence.to_vec();
        for e in &mut evidence {
            e.supported = supported(e);
        }
        Alone {
            theta: fits.iter().map(|f| (f.maps[0].kind, f.theta[0])).collect(),
            evidence,
            fits: fits
                .iter()
                .map(|f| Swap {
                    slot: 0,
                    kind: f.maps[0].kind,
                    wrss: f.wrss,
                    value: f.value(0),
                })
                .collect(),
        }
    }

    /// `k`'s θ alone, where the first round fitted it.
    fn start(&self, k: EffectKind) -> Option<f64> {
        self.theta.iter().find(|a| a.0 == k).map(|a| a.1)
    }
}

/// The set grown one effect at a time, and what its rounds found.
struct Grown {
    /// The set when no supported candidate is left (or the cap is reached).
    current: WithinFit,
    /// The order in which effects were added, with their ΔBIC when added.
    path: Vec<(EffectKind, f64)>,
    /// The last round's evidence of each candidate added to the set then.
    last: Vec<Evidence>,
    /// The set `last` was computed against (it is reused when the selection ends there).
    last_for: Vec<EffectKind>,
    alone: Alone,
}

impl Selector<'_> {
    /// Rounds of forward selection from `null`: each adds the best-fitting supported candidate
    /// and drops any earlier effect it made redundant.
    fn grow(&self, null: WithinFit, candidates: &[EffectKind]) -> Grown {
        let (d, w) = (self.d, self.w);
        let mut g = Grown {
            current: null,
            path: Vec::new(),
            last: Vec::new(),
            last_for: Vec::new(),
            alone: Alone::default(),
        };
        // An effect that a later one made redundant does not come back (stepwise selection can
        // otherwise cycle), so the loop ends after at most two rounds per candidate.
        let mut retired: Vec<EffectKind> = Vec::new();
        for _round in 0..=2 * candidates.len() {
            if g.current.k() >= MAX_WITHIN {
                // Structure beyond this many effects at once is left to the adequacy check.
                break;
            }
            let pool: Vec<EffectKind> = candidates
                .iter()
                .copied()
                .filter(|&k| !g.current.maps.iter().any(|m| m.kind == k) && !retired.contains(&k))
                .collect();
            let fits: Vec<WithinFit> = par(&pool, self.threads, |&k| {
                add(d, &g.current, k, w, g.alone.start(k))
            });
            g.last = fits
                .iter()
                .map(|f| evidence(d, &g.current, f, f.k() - 1))
                .collect();
            g.last_for = kinds(&g.current);
            if g.alone.theta.is_empty() {
                g.alone = Alone::of(&fits, &g.last, self.supported);
            }
            // Among the supported candidates the best fit comes in: each one's overdispersion
            // decides whether it is supported, not which of two rival shapes the data prefer.
            let best = (0..fits.len())
                .filter(|&i| (self.supported)(&g.last[i]))
                .min_by(|&a, &b| fits[a].wrss.total_cmp(&fits[b].wrss));
            let Some(b) = best else { break };
            g.path.push((pool[b], g.last[b].delta_bic));
            let grown = fits.into_iter().nth(b).expect("index in range");
            g.current = self.drop_redundant(grown, &mut retired);
        }
        g
    }

    /// `current` less each earlier effect that its newest one makes redundant (the weakest
    /// unsupported first, until every one is supported); those that leave are `retired`.
    fn drop_redundant(&self, mut current: WithinFit, retired: &mut Vec<EffectKind>) -> WithinFit {
        let (d, w) = (self.d, self.w);
        while current.k() > 1 {
            let earlier: Vec<usize> = (0..current.k() - 1).collect();
            let drops: Vec<(WithinFit, Evidence)> = par(&earlier, self.threads, |&j| {
                let less = drop(d, &current, j, w);
                let e = evidence(d, &less, &current, j);
                (less, e)
            });
            let weakest = (0..drops.len())
                .filter(|&j| !(self.supported)(&drops[j].1))
                .max_by(|&a, &b| drops[a].1.delta_bic.total_cmp(&drops[b].1.delta_bic));
            match weakest {
                Some(j) => {
                    retired.push(current.maps[j].kind);
                    current = drops.into_iter().nth(j).expect("index in range").0;
                }
                None => break,
            }
        }
        current
    }

    /// Every candidate's evidence given the final set `fit`, marked supported or not: the
    /// selected effects each given the others, and every other candidate added to `fit` (the
    /// last round's, unless it was against another set: the selection stopped at its cap, or
    /// an effect left; then recomputed in the same batch of fits).
    fn final_evidence(
        &self,
        fit: &WithinFit,
        candidates: &[EffectKind],
        last: Vec<Evidence>,
        last_for: &[EffectKind],
        alone: &Alone,
    ) -> Vec<Evidence> {
        let (d, w) = (self.d, self.w);
        let recompute = last_for != kinds(fit) || last.len() + fit.k() < candidates.len();
        let mut jobs: Vec<Option<EffectKind>> = (0..fit.k()).map(|_| None).collect();
        if recompute {
            jobs.extend(
                candidates
                    .iter()
                    .filter(|&&k| !fit.maps.iter().any(|m| m.kind == k))
                    .map(|&k| Some(k)),
            );
        }
        let mut evidence: Vec<Evidence> = par(
            &(0..jobs.len()).collect::<Vec<_>>(),
            self.threads,
            |&x| match jobs[x] {
                None => {
                    let less = drop(d, fit, x, w);
                    let mut e = evidence(d, &less, fit, x);
                    e.selected = true;
                    e
                }
                Some(k) => {
                    let f = add(d, fit, k, w, alone.start(k));
                    evidence(d, fit, &f, f.k() - 1)
                }
            },
        );
        if !recompute {
            evidence.extend(last);
        }
        for e in &mut evidence {
            e.supported = (self.supported)(e);
        }
        evidence
    }
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
    let s = Selector {
        d,
        w,
        threads,
        supported: &supported,
    };
    let g = s.grow(null, candidates);
    let (fit, mut alternatives) = swaps(
        d,
        g.current,
        candidates,
        w,
        &supported,
        &g.alone.theta,
        threads,
    );
    if fit.k() == 1 {
        // One effect: its alternatives are the other candidates alone.
        alternatives = g
            .alone
            .fits
            .iter()
            .filter(|a| a.kind != fit.maps[0].kind)
            .copied()
            .collect();
    }
    let evidence = s.final_evidence(&fit, candidates, g.last, &g.last_for, &g.alone);
    WithinSelection {
        fit,
        evidence,
        path: g.path,
        alone: g.alone.evidence,
        swaps: alternatives,
    }
}
