//! The search and its answer.

use crate::answer::{
    decline, proposed, verdict_words, DataInfo, Declined, Discovery, NotTestable, Proposed, Rival,
    ScreenRow, Search,
};
use crate::columns::Base;
use crate::heldout::{self, Ratio};
use crate::joint;
use crate::library::{Sign, LIBRARY};
use crate::screen::{self, between_evidence, sign_ok, within_evidence, Level, Projector, Runs};
use crate::stability::{self, Candidate};
use capstan_data::Dataset;
use capstan_engine::evidence::adequacy::{lack_of_fit, LackOfFit};
use capstan_engine::evidence::within::WithinFit;
use capstan_engine::evidence::{self, Assessment, RIVAL_GAP};
use capstan_friction::EffectKind;
use std::time::Instant;

/// A proposed term must leave no lack of fit against the replicate runs at this level.
pub const LOF_ALPHA: f64 = 0.01;

/// Fewest cords for the stability (whole-cord resamples) and the held-out gain (leave one
/// cord out, jackknife over cords): below it neither is computed, and nothing is proposed.
pub const MIN_CORDS: usize = 3;

/// The default [`Options::max_r2_model`]: VIF 100.
pub const MAX_R2_MODEL: f64 = 0.99;

/// How to search.
#[derive(Clone, Copy, Debug)]
pub struct Options {
    /// The engine's options (thresholds, threads).
    pub engine: evidence::Options,
    /// Extended-BIC γ: the bar is ΔBIC + 2γ·ln(p) < −threshold for the first of p terms tried.
    pub gamma: f64,
    /// Most terms proposed.
    pub max_terms: usize,
    /// Cord resamples of the stability.
    pub resamples: usize,
    /// Least stability a proposed term needs.
    pub min_stability: f64,
    /// The joint search: a term may take the place of a within-run catalogue effect.
    pub joint: bool,
    /// A within-run term whose column the model's columns explain beyond this share
    /// (1 − 1/VIF) is not separable from them at this design: it is screened and shown, never
    /// proposed.
    pub max_r2_model: f64,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            engine: evidence::Options::default(),
            gamma: 1.0,
            max_terms: 2,
            resamples: 100,
            min_stability: 0.5,
            joint: true,
            max_r2_model: MAX_R2_MODEL,
        }
    }
}

/// Search `data` (runs the engine's assessment first).
pub fn discover(data: &Dataset, opts: &Options, progress: &mut dyn FnMut(&str, f64)) -> Discovery {
    let t0 = Instant::now();
    progress("catalogue", 0.0);
    let a = evidence::assess(data, &opts.engine);
    discover_assessed(data, &a, opts, t0, progress)
}

/// The covariate per run of a selected between-level catalogue effect: its entry's cord
/// covariate, or the run number (from 0) for an effect between runs.
fn catalogue_covariate(a: &Assessment, kind: EffectKind) -> Option<Vec<f64>> {
    let d = &a.design;
    let entry = kind.entry();
    let v = |u: usize| {
        let c = &d.cords[d.unit_cord[u]];
        let op = capstan_friction::Operating {
            wrap_rad: c.wrap_deg.to_radians(),
            diameter_mm: c.diameter_mm,
            drive_v: c.drive_v,
            run: d.unit_run[u],
            time_s: 0.0,
            load_memory_ns: 0.0,
        };
        match (entry.cord, entry.level) {
            (Some(test), _) => Some((test.covariate)(&op)),
            (None, capstan_friction::entry::Level::BetweenRun) => Some(d.unit_run[u] - 1.0),
            _ => None,
        }
    };
    (0..d.units.len()).map(v).collect()
}

/// The model as the search grows it.
struct State {
    shared: Vec<Vec<f64>>,
    covs: Vec<Vec<f64>>,
    /// Residuals projected off the runs' mu and the shared columns.
    e: Vec<f64>,
    used: Vec<usize>,
}

/// One testable term's column or run-level g.
struct Testable {
    term: usize,
    column: Option<Vec<f64>>,
    g_run: Option<Vec<f64>>,
}

fn classify(base: &Base) -> (Vec<Testable>, Vec<NotTestable>) {
    let (mut ok, mut not) = (Vec::new(), Vec::new());
    let proj0 = Projector::new(base, &[]);
    for (j, t) in LIBRARY.iter().enumerate() {
        if let Some(g) = screen::run_level_g(base, t) {
            let spread = g.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
                - g.iter().cloned().fold(f64::INFINITY, f64::min);
            if spread > 1e-12 {
                ok.push(Testable {
                    term: j,
                    column: None,
                    g_run: Some(g),
                });
            } else {
                not.push(NotTestable {
                    name: t.name,
                    reason: "its variable does not vary in these data",
                });
            }
            continue;
        }
        let x = base.column(t);
        let xt = proj0.project(base, &x);
        let raw: f64 = x.iter().zip(&base.w).map(|(v, w)| w * v * v).sum();
        let left: f64 = xt.iter().zip(&base.w).map(|(v, w)| w * v * v).sum();
        if raw > 0.0 && left > 1e-9 * raw {
            ok.push(Testable {
                term: j,
                column: Some(x),
                g_run: None,
            });
        } else {
            not.push(NotTestable {
                name: t.name,
                reason:
                    "its column is all absorbed by every run's own mu (no spread of its variable)",
            });
        }
    }
    (ok, not)
}

/// Search given the engine's assessment `a` of `data`.
pub fn discover_assessed(
    data: &Dataset,
    a: &Assessment,
    opts: &Options,
    t0: Instant,
    progress: &mut dyn FnMut(&str, f64),
) -> Discovery {
    let d = &a.design;
    progress("linearise", 0.2);
    let base0 = Base::new(d, &a.fit, &a.weights.w);
    let threshold = opts.engine.within_threshold.max(0.0);
    let (testable0, not_testable) = classify(&base0);
    let alts = if opts.joint {
        joint::alternatives(a)
    } else {
        Vec::new()
    };
    let p = testable0.len().max(1) as f64;
    // The models tried at each step: every term added, and every term in place of each
    // within-run catalogue effect (the joint search); extended BIC pays for all of them.
    let models = p * (1 + alts.len()) as f64;
    let bar_of = |step: usize| {
        let k = step as f64;
        -threshold - 2.0 * opts.gamma * ((models - k + 1.0) / k).max(1.0).ln()
    };
    let cord_checks = (d.cords.len() < MIN_CORDS).then(|| {
        format!(
            "stability and the held-out gain cannot be computed from {} cord{}: whole cords are resampled and held out, and that needs at least {MIN_CORDS}",
            d.cords.len(),
            if d.cords.len() == 1 { "" } else { "s" }
        )
    });
    let covs0: Vec<Vec<f64>> = a
        .selected
        .iter()
        .filter_map(|&k| catalogue_covariate(a, k))
        .collect();
    let (swap, screen0) = choose_swap((&base0, &testable0, &covs0), (&alts, a), bar_of(1), opts);
    let (base, testable, fit_used): (&Base, Vec<Testable>, &WithinFit) = match swap {
        Some(s) => (
            &alts[s.alt].base,
            classify(&alts[s.alt].base).0,
            &alts[s.alt].fit,
        ),
        None => (&base0, testable0, &a.fit),
    };
    let runs = runs_of(a, fit_used);
    let mut st = state_of(base, &covs0);
    let lof_before = a.adequacy.lack_of_fit.clone();
    // After a term, any significant lack of fit keeps "unexplained" (the spike's rule: a
    // partial mimic leaves the replicates disagreeing with the model, whatever its size).
    let lof_open = |l: &Option<LackOfFit>| l.as_ref().is_some_and(|l| l.p < LOF_ALPHA);
    let mut terms: Vec<Proposed> = Vec::new();
    let mut declined: Vec<Declined> = Vec::new();
    let mut first_screen = Vec::new();
    let mut partial = false;
    for step in 1..=opts.max_terms {
        progress("screen", 0.3 + 0.2 * (step - 1) as f64);
        let proj = Projector::new(base, &st.shared);
        let screens = screen_all(base, &testable, &proj, &st, &runs);
        if step == 1 {
            first_screen = screen0
                .iter()
                .map(|s| ScreenRow {
                    name: LIBRARY[s.term].name,
                    level: s.level,
                    delta_bic: s.delta_bic,
                    theta: s.theta,
                    se: Some(s.se).filter(|v| v.is_finite()),
                    sign_ok: s.sign_ok,
                    r2_model: s.r2_model,
                    replicate: s.replicate.clone(),
                })
                .collect();
        }
        let bar = bar_of(step);
        // The first step of a swap takes the swap's term (it beat every addition).
        let forced = swap.filter(|_| step == 1).map(|s| s.term);
        // The pick: the best term with its physical sign, separable from the model, and (past
        // the bar) shared by the replicate runs; a term past the bar that the replicate runs do
        // not share is declined and the search goes on to the next.
        let shared_ok = |s: &screen::Screen| s.replicate.as_ref().is_none_or(|r| r.delta_bic < bar);
        let mut pick = None;
        for s in screens
            .iter()
            .filter(|s| s.sign_ok && s.r2_model <= opts.max_r2_model)
            .filter(|s| forced.is_none_or(|f| f == s.term))
        {
            if s.delta_bic < bar && !shared_ok(s) {
                declined.push(decline(&LIBRARY[s.term], s, None, None, format!(
                    "the replicate runs do not share it enough: on the replicate cells' means its ΔBIC is {:.1} (bar {bar:.1}); the rest of what it fits is run-to-run wander",
                    s.replicate.as_ref().map_or(f64::NAN, |r| r.delta_bic)
                )));
                continue;
            }
            pick = Some(s.clone());
            break;
        }
        let Some(best) = pick else { break };
        let t = &LIBRARY[best.term];
        if best.delta_bic >= bar {
            if best.delta_bic < -threshold {
                declined.push(decline(t, &best, None, None, format!(
                    "ΔBIC {:.1} passes the engine's bar ({:.0}) but not the search's ({bar:.1}): with {models:.0} models tried at each step, that much is expected by chance",
                    best.delta_bic, -threshold
                )));
            }
            break;
        }
        if let Some(why) = &cord_checks {
            declined.push(decline(t, &best, None, None, why.clone()));
            break;
        }
        progress("stability", 0.4 + 0.2 * (step - 1) as f64);
        let cands: Vec<Candidate> = testable
            .iter()
            .filter(|c| !st.used.contains(&c.term))
            .map(|c| Candidate {
                term: c.term,
                column: c.column.clone(),
                g_run: c.g_run.clone(),
                c_hat: screens
                    .iter()
                    .find(|s| s.term == c.term)
                    .map_or(1.0, |s| s.c_hat),
                sign_ok: match LIBRARY[c.term].sign {
                    Sign::Free => |_| true,
                    Sign::NonNegative => |t| t >= 0.0,
                },
            })
            .collect();
        let problem = stability::Problem {
            base,
            shared: &st.shared,
            e: &base.e,
            candidates: &cands,
            runs: &runs,
            covs: &st.covs,
            bar,
        };
        let stab =
            stability::stability(&problem, best.term, opts.resamples, 0x26_57ab + step as u64);
        progress("held-out cords", 0.5 + 0.2 * (step - 1) as f64);
        let tst = testable.iter().find(|c| c.term == best.term).unwrap();
        // Against the engine's catalogue when the term displaced one of its effects.
        let without = forced.map(|_| heldout::shape_sse(&base0, &base0.b));
        let ratio = held_out(base, fit_used, &st, tst, without);
        let Some(ratio) = ratio else {
            declined.push(decline(
                t,
                &best,
                Some(stab),
                None,
                "its held-out gain could not be computed (too few cords)".into(),
            ));
            break;
        };
        if stab < opts.min_stability {
            declined.push(decline(
                t,
                &best,
                Some(stab),
                Some(ratio),
                format!(
                "unstable: the search picks it in {:.0} % of whole-cord resamples (needs {:.0} %)",
                100.0 * stab, 100.0 * opts.min_stability
            ),
            ));
            break;
        }
        if ratio.value >= 1.0 {
            declined.push(decline(
                t,
                &best,
                Some(stab),
                Some(ratio.clone()),
                format!(
                    "does not help held-out cords: RMSE ratio {:.3} [{:.3}, {:.3}]",
                    ratio.value, ratio.ci95.lo, ratio.ci95.hi
                ),
            ));
            break;
        }
        // Lack of fit with the term in (within-run terms change what the replicates share).
        let proj_x = tst.column.as_ref().map(|x| proj.project(base, x));
        let lof_after = match &proj_x {
            Some(xt) => {
                let z: Vec<f64> = (0..d.n())
                    .map(|i| (st.e[i] - best.theta * xt[i]) * base.w[i].sqrt())
                    .collect();
                lack_of_fit(d, &z, st.shared.len() + 1)
            }
            None => lof_before.clone(),
        };
        if proj_x.is_some() && lof_open(&lof_after) {
            partial = true;
            declined.push(decline(t, &best, Some(stab), Some(ratio), format!(
                "a partial mimic: with it the lack of fit against the replicate runs stays (p = {:.3}, systematic part {:.2}× the noise)",
                lof_after.as_ref().map_or(f64::NAN, |l| l.p),
                lof_after.as_ref().map_or(f64::NAN, |l| l.systematic_ratio)
            )));
            break;
        }
        let rivals = rivals_of(base, &proj, &screens, &best, &testable, threshold);
        let displaced = forced.and(swap).map(|s| joint::Displaced {
            effect: alts[s.alt].dropped.name(),
            effect_delta_bic: alts[s.alt].dropped_delta_bic,
            delta_bic_swap: s.delta_bic,
        });
        terms.push(proposed(
            t,
            &best,
            (stab, ratio),
            lof_after,
            rivals,
            displaced,
        ));
        // Grow the model.
        match (&tst.column, proj_x) {
            (Some(x), Some(xt)) => {
                for (e, v) in st.e.iter_mut().zip(&xt) {
                    *e -= best.theta * v;
                }
                st.shared.push(x.clone());
            }
            _ => st.covs.push(tst.g_run.clone().unwrap_or_default()),
        }
        st.used.push(best.term);
    }
    progress("done", 1.0);
    // A swap's term that was declined says what it was tried in place of.
    if let Some(sw) = swap {
        let x = &alts[sw.alt];
        if let Some(dec) = declined
            .iter_mut()
            .find(|x| x.name == LIBRARY[sw.term].name)
        {
            dec.reason = format!(
                "tried in place of the catalogue's {} (ΔBIC of the swap {:.1}; {} alone {:.1}): {}",
                x.dropped.name(),
                sw.delta_bic,
                x.dropped.name(),
                x.dropped_delta_bic,
                dec.reason
            );
            dec.displaced = Some(joint::Displaced {
                effect: x.dropped.name(),
                effect_delta_bic: x.dropped_delta_bic,
                delta_bic_swap: sw.delta_bic,
            });
        }
    }
    let base_open = a.adequacy.unexplained;
    let last_lof = terms.iter().rev().find_map(|t| t.lack_of_fit_after.clone());
    let unexplained_after = if terms.is_empty() {
        base_open
    } else {
        partial
            || !a.adequacy.at_physical_limit.is_empty()
            || lof_open(&last_lof.or(lof_before.clone()))
    };
    let residual_pattern = if unexplained_after {
        Some(a.adequacy.pattern.unwrap_or("cells"))
    } else {
        None
    };
    let verdict = verdict_words(&terms, unexplained_after, residual_pattern, &declined);
    Discovery {
        data: DataInfo {
            source: data.source.clone(),
            rows: d.n(),
            structure: d.structure.clone(),
        },
        catalogue_effects: a.selected.iter().map(|k| k.name()).collect(),
        terms,
        unexplained_after,
        residual_pattern,
        verdict,
        lack_of_fit_before: lof_before,
        declined,
        not_testable,
        search: Search {
            library_size: LIBRARY.len(),
            tried: p as usize,
            threshold,
            gamma: opts.gamma,
            first_bar: bar_of(1),
            models_per_step: models,
            displaceable: alts.iter().map(|x| x.dropped.name()).collect(),
            resamples: cord_checks.is_none().then_some(opts.resamples),
            cords: d.cords.len(),
            cord_checks,
            min_stability: opts.min_stability,
            screen: first_screen,
        },
        elapsed_s: t0.elapsed().as_secs_f64(),
    }
}

/// The runs' ln mu under `fit`, for the between-level tests.
fn runs_of(a: &Assessment, fit: &WithinFit) -> Runs {
    let d = &a.design;
    Runs {
        cord: d.unit_cord.clone(),
        cords: d.cords.len(),
        ln_mu: fit.mu.iter().map(|m| m.max(1e-6).ln()).collect(),
    }
}

/// The search's state on the model linearised in `base`, before any term.
fn state_of(base: &Base, covs: &[Vec<f64>]) -> State {
    let shared = base.b.clone();
    let e = Projector::new(base, &shared).project(base, &base.e);
    State {
        shared,
        covs: covs.to_vec(),
        e,
        used: Vec::new(),
    }
}

/// The joint search's first step: the best swap of a catalogue effect for a library term, if
/// one beats every addition (see [`joint`]).
fn choose_swap(
    (base0, testable0, covs0): (&Base, &[Testable], &[Vec<f64>]),
    (alts, a): (&[joint::Alternative<'_>], &Assessment),
    bar: f64,
    opts: &Options,
) -> (Option<joint::Swap>, Vec<screen::Screen>) {
    let st0 = state_of(base0, covs0);
    let proj0 = Projector::new(base0, &st0.shared);
    let sc0 = screen_all(base0, testable0, &proj0, &st0, &runs_of(a, &a.fit));
    if alts.is_empty() {
        return (None, sc0);
    }
    let best_addition = sc0
        .iter()
        .find(|s| {
            s.sign_ok
                && s.r2_model <= opts.max_r2_model
                && s.replicate.as_ref().is_none_or(|r| r.delta_bic < bar)
        })
        .map_or(f64::INFINITY, |s| s.delta_bic);
    let screens: Vec<Vec<screen::Screen>> = alts
        .iter()
        .map(|alt| {
            let (t, _) = classify(&alt.base);
            let st = state_of(&alt.base, covs0);
            let proj = Projector::new(&alt.base, &st.shared);
            screen_all(&alt.base, &t, &proj, &st, &runs_of(a, &alt.fit))
        })
        .collect();
    let swap = joint::best_swap(alts, &screens, bar, opts.max_r2_model, best_addition);
    (swap, sc0)
}

/// Every testable, unused term's screen, best (lowest ΔBIC) first.
fn screen_all(
    base: &Base,
    testable: &[Testable],
    proj: &Projector,
    st: &State,
    runs: &Runs,
) -> Vec<screen::Screen> {
    let mut out: Vec<screen::Screen> = testable
        .iter()
        .filter(|c| !st.used.contains(&c.term))
        .filter_map(|c| {
            let t = &LIBRARY[c.term];
            let mut r2 = 0.0;
            let mut replicate = None;
            let (level, (theta, se, dbic, c_hat)) = match (&c.column, &c.g_run) {
                (Some(x), _) => {
                    let xt = proj.project(base, x);
                    let xa = screen::off_run_mu(base, x);
                    let norm =
                        |v: &[f64]| v.iter().zip(&base.w).map(|(v, w)| w * v * v).sum::<f64>();
                    r2 = 1.0 - norm(&xt) / norm(&xa).max(1e-300);
                    replicate = crate::replicate::replicate_evidence(base, &xt, &st.e);
                    (
                        Level::WithinRun,
                        within_evidence(base, &xt, &st.e, st.shared.len())?,
                    )
                }
                (None, Some(g)) => {
                    let (th, se, db) = between_evidence(runs, g, &st.covs)?;
                    (Level::Between, (th, se, db, 1.0))
                }
                _ => return None,
            };
            ([theta, dbic].iter().all(|v| v.is_finite()) && !se.is_infinite()).then(|| {
                screen::Screen {
                    term: c.term,
                    level,
                    theta,
                    se,
                    delta_bic: dbic,
                    c_hat,
                    sign_ok: sign_ok(t, theta),
                    r2_model: r2,
                    replicate,
                }
            })
        })
        .collect();
    out.sort_by(|a, b| a.delta_bic.total_cmp(&b.delta_bic));
    out
}

/// The held-out ratio matched to the term's level.
fn held_out(
    base: &Base,
    fit: &WithinFit,
    st: &State,
    c: &Testable,
    without: Option<Vec<f64>>,
) -> Option<Ratio> {
    let rows = heldout::rows_per_cord(base);
    match (&c.column, &c.g_run) {
        (Some(x), _) => {
            let without = without.unwrap_or_else(|| heldout::shape_sse(base, &st.shared));
            let mut cols = st.shared.clone();
            cols.push(x.clone());
            let with = heldout::shape_sse(base, &cols);
            heldout::ratio(
                &with,
                &without,
                &rows,
                "each held-out run keeps its own mu; the shape comes from the other cords",
            )
        }
        (None, Some(g)) => {
            let x0: Vec<Vec<f64>> = (0..g.len())
                .map(|u| {
                    std::iter::once(1.0)
                        .chain(st.covs.iter().map(|cv| cv[u]))
                        .collect()
                })
                .collect();
            let x1: Vec<Vec<f64>> = x0
                .iter()
                .zip(g)
                .map(|(r, gv)| {
                    let mut r = r.clone();
                    r.push(*gv);
                    r
                })
                .collect();
            let without = heldout::population_sse(base, fit, &x0);
            let with = heldout::population_sse(base, fit, &x1);
            heldout::ratio(
                &with,
                &without,
                &rows,
                "the held-out cord's mu predicted from the other cords",
            )
        }
        _ => None,
    }
}

fn rivals_of(
    base: &Base,
    proj: &Projector,
    screens: &[screen::Screen],
    best: &screen::Screen,
    testable: &[Testable],
    threshold: f64,
) -> Vec<Rival> {
    let col = |term: usize| {
        testable
            .iter()
            .find(|c| c.term == term)
            .and_then(|c| c.column.as_ref())
            .map(|x| proj.project(base, x))
    };
    let xb = col(best.term);
    screens
        .iter()
        .filter(|s| s.term != best.term && s.sign_ok)
        .filter(|s| s.delta_bic < -threshold && s.delta_bic - best.delta_bic <= RIVAL_GAP)
        .map(|s| {
            let correlation = match (&xb, col(s.term)) {
                (Some(a), Some(b)) => {
                    let w = &base.w;
                    let ab: f64 = (0..a.len()).map(|i| w[i] * a[i] * b[i]).sum();
                    let aa: f64 = (0..a.len()).map(|i| w[i] * a[i] * a[i]).sum();
                    let bb: f64 = (0..a.len()).map(|i| w[i] * b[i] * b[i]).sum();
                    Some(ab / (aa * bb).sqrt())
                }
                _ => None,
            };
            Rival {
                name: LIBRARY[s.term].name,
                depends_on: LIBRARY[s.term].depends_on,
                delta_bic: s.delta_bic,
                correlation,
            }
        })
        .collect()
}
