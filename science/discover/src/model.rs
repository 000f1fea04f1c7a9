//! The search's model: the library terms these data can test, the state the search grows
//! (shared columns, run-level covariates, residuals), and the screen of every term over it —
//! on the catalogue's model, or on each joint alternative without one catalogue effect.

use crate::answer::NotTestable;
use crate::columns::Base;
use crate::joint;
use crate::library::{Row, Var, LIBRARY};
use crate::replicate::{replicate_evidence, Gate};
use crate::screen::{self, between_evidence, sign_ok, within_evidence, Level, Projector, Runs};
use capstan_engine::evidence::within::WithinFit;
use capstan_engine::evidence::Assessment;
use capstan_physics::EffectKind;

/// The covariate per run of a selected between-level catalogue effect: its entry's cord
/// covariate, or the run number (from 0) for an effect between runs.
pub(crate) fn catalogue_covariate(a: &Assessment, kind: EffectKind) -> Option<Vec<f64>> {
    let d = &a.design;
    let entry = kind.entry();
    let v = |u: usize| {
        let c = &d.cords[d.unit_cord[u]];
        let op = capstan_physics::Operating {
            wrap_rad: c.wrap_deg.to_radians(),
            diameter_mm: c.diameter_mm,
            drive_v: c.drive_v,
            run: d.unit_run[u],
            time_s: 0.0,
            load_memory_ns: 0.0,
        };
        match (entry.cord, entry.level) {
            (Some(test), _) => Some((test.covariate)(&op)),
            (None, capstan_physics::entry::Level::BetweenRun) => Some(d.unit_run[u] - 1.0),
            _ => None,
        }
    };
    (0..d.units.len()).map(v).collect()
}

/// The model as the search grows it.
pub(crate) struct State {
    /// The model's within-run columns (the catalogue's, then the terms added).
    pub(crate) shared: Vec<Vec<f64>>,
    /// The run-level covariates (the catalogue's between-level effects, then the terms added).
    pub(crate) covs: Vec<Vec<f64>>,
    /// Residuals projected off the runs' mu and the shared columns.
    pub(crate) e: Vec<f64>,
    /// The library terms added.
    pub(crate) used: Vec<usize>,
    /// Their θ̂, in the same order.
    pub(crate) theta_used: Vec<f64>,
}

/// One testable term's column or run-level g.
#[derive(Clone)]
pub(crate) struct Testable {
    /// Library index.
    pub(crate) term: usize,
    /// Its within-run column (raw), or None for a between-level term.
    pub(crate) column: Option<Vec<f64>>,
    /// Its g per run, for a between-level term.
    pub(crate) g_run: Option<Vec<f64>>,
    /// The centre in T1 its column is built at, N (a centred term: [`crate::library::centred`]).
    pub(crate) centre: Option<f64>,
}

/// The models the search tries for the terms `testable` at each step: one per term, one per
/// centre tried (`centres`) of a centred term.
pub(crate) fn models_of(testable: &[Testable], centres: usize) -> usize {
    testable
        .iter()
        .map(|c| c.centre.map_or(1, |_| centres.max(1)))
        .sum()
}

/// The terms these data can test, and why each other cannot be. A term is tested only where
/// every variable it depends on varies (with one capstan diameter, `t2_offset_diameter` is
/// zero but for round-off and `heat_per_radius` is the catalogue's contact heating: its ΔBIC
/// and θ would be round-off or another term's), and where its column, each run's mu projected
/// out, is neither null nor the catalogue's own within-run columns.
pub(crate) fn classify(base: &Base, centres: usize) -> (Vec<Testable>, Vec<NotTestable>) {
    let (mut ok, mut not) = (Vec::new(), Vec::new());
    let proj0 = Projector::new(base, &[]);
    let proj_b = (!base.b.is_empty()).then(|| Projector::new(base, &base.b));
    let norm = |v: &[f64]| v.iter().zip(&base.w).map(|(v, w)| w * v * v).sum::<f64>();
    for (j, t) in LIBRARY.iter().enumerate() {
        if let Some(reason) = t.depends_on.iter().find_map(|&v| fixed_variable(base, v)) {
            not.push(NotTestable {
                name: t.name,
                reason,
            });
            continue;
        }
        if let Some(g) = screen::run_level_g(base, t) {
            let spread = g.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
                - g.iter().cloned().fold(f64::INFINITY, f64::min);
            if spread > 1e-12 {
                ok.push(Testable {
                    term: j,
                    column: None,
                    g_run: Some(g),
                    centre: None,
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
        let left = norm(&proj0.project(base, &x));
        let reason = if !(norm(&x) > 0.0 && left > 1e-9 * norm(&x)) {
            Some("its column is all absorbed by every run's own mu (no spread of its variable)")
        } else if proj_b
            .as_ref()
            .is_some_and(|p| norm(&p.project(base, &x)) <= 1e-9 * left)
        {
            Some("its column within runs is the catalogue's (numerically collinear with the selected effects)")
        } else {
            None
        };
        match reason {
            Some(reason) => not.push(NotTestable {
                name: t.name,
                reason,
            }),
            None if crate::library::centred(t) => {
                let proj = proj_b.as_ref().unwrap_or(&proj0);
                let (x, c) = crate::centred::best_centre(base, t, proj, centres);
                ok.push(Testable {
                    term: j,
                    column: Some(x),
                    g_run: None,
                    centre: Some(c),
                })
            }
            None => ok.push(Testable {
                term: j,
                column: Some(x),
                g_run: None,
                centre: None,
            }),
        }
    }
    (ok, not)
}

/// Why a term that depends on `v` cannot be tested on these data (`v` does not vary), if so.
fn fixed_variable(base: &Base, v: Var) -> Option<&'static str> {
    let rows = &base.rows;
    let spread = |f: fn(&Row) -> f64| {
        let (lo, hi) = rows
            .iter()
            .map(f)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
                (lo.min(x), hi.max(x))
            });
        hi - lo > 1e-9 * lo.abs().max(hi.abs())
    };
    let (varies, reason) = match v {
        Var::T1 => (spread(|r| r.t1), "T1 does not vary in these data"),
        Var::T2 => (spread(|r| r.t2), "T2 does not vary in these data"),
        Var::Load => (spread(|r| r.load), "the load does not vary in these data"),
        Var::Wrap => (
            spread(|r| r.wrap),
            "one wrap angle in these data: its dependence on the wrap cannot be tested",
        ),
        Var::Diameter => (
            spread(|r| r.diameter),
            "one capstan diameter in these data: its dependence on the diameter cannot be tested",
        ),
        Var::DriveV => (
            spread(|r| r.drive_v),
            "one drive voltage in these data: its dependence on the drive voltage cannot be tested",
        ),
        Var::Run => (
            spread(|r| r.run),
            "one run per cord in these data: its dependence on the run cannot be tested",
        ),
        Var::Time => (
            spread(|r| r.time_in_run),
            "one step per run in these data: its dependence on time cannot be tested",
        ),
        Var::Step => (
            base.d.units.iter().any(|u| u.len() >= 2),
            "one step per run in these data: its dependence on the step cannot be tested",
        ),
        Var::StepDirection if base.d.falling.iter().all(|f| f.is_none()) => (
            false,
            "the step order is not known (no run, step or time column), so whether the tension rose or fell to a step cannot be told: its dependence on the step direction cannot be tested",
        ),
        Var::StepDirection => (
            rows.iter().any(|r| r.falling) && rows.iter().any(|r| !r.falling),
            "the tension never falls between steps in these data: its dependence on the step direction cannot be tested",
        ),
    };
    (!varies).then_some(reason)
}

/// The runs' ln mu under `fit`, for the between-level tests.
pub(crate) fn runs_of(a: &Assessment, fit: &WithinFit) -> Runs {
    let d = &a.design;
    Runs {
        cord: d.unit_cord.clone(),
        cords: d.cords.len(),
        ln_mu: fit.mu.iter().map(|m| m.max(1e-6).ln()).collect(),
    }
}

impl State {
    /// Add the term `c` at its fitted `theta` (`xt`: its column projected off the model, for
    /// a within-run term).
    pub(crate) fn grow(&mut self, c: &Testable, theta: f64, xt: Option<Vec<f64>>) {
        match (&c.column, xt) {
            (Some(x), Some(xt)) => {
                for (e, v) in self.e.iter_mut().zip(&xt) {
                    *e -= theta * v;
                }
                self.shared.push(x.clone());
            }
            _ => self.covs.push(c.g_run.clone().unwrap_or_default()),
        }
        self.used.push(c.term);
        self.theta_used.push(theta);
    }
}

/// The search's state on the model linearised in `base`, before any term.
pub(crate) fn state_of(base: &Base, covs: &[Vec<f64>]) -> State {
    let shared = base.b.clone();
    let e = Projector::new(base, &shared).project(base, &base.e);
    State {
        shared,
        covs: covs.to_vec(),
        e,
        used: Vec::new(),
        theta_used: Vec::new(),
    }
}

/// The joint search's first step: the best swap of a catalogue effect for a library term, if
/// one beats every addition (see [`joint`]).
pub(crate) fn choose_swap(
    (base0, testable0, covs0): (&Base, &[Testable], &[Vec<f64>]),
    (alts, a): (&[joint::Alternative<'_>], &Assessment),
    gate: Gate,
    (max_r2_model, centres): (f64, usize),
) -> (Option<joint::Swap>, Vec<screen::Screen>) {
    let st0 = state_of(base0, covs0);
    let proj0 = Projector::new(base0, &st0.shared);
    let sc0 = screen_all(base0, testable0, &proj0, &st0, &runs_of(a, &a.fit), gate);
    if alts.is_empty() {
        return (None, sc0);
    }
    let best_addition = sc0
        .iter()
        .find(|s| {
            s.sign_ok && s.r2_model <= max_r2_model && gate.lets_through(s.replicate.as_ref())
        })
        .map_or(f64::INFINITY, |s| s.delta_bic);
    let screens: Vec<Vec<screen::Screen>> = alts
        .iter()
        .map(|alt| {
            let (t, _) = classify(&alt.base, centres);
            let st = state_of(&alt.base, covs0);
            let proj = Projector::new(&alt.base, &st.shared);
            screen_all(&alt.base, &t, &proj, &st, &runs_of(a, &alt.fit), gate)
        })
        .collect();
    let swap = joint::best_swap(alts, &screens, gate, max_r2_model, best_addition);
    (swap, sc0)
}

/// Every testable, unused term's screen, best (lowest ΔBIC) first.
pub(crate) fn screen_all(
    base: &Base,
    testable: &[Testable],
    proj: &Projector,
    st: &State,
    runs: &Runs,
    gate: Gate,
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
                    let ev = within_evidence(base, &xt, &st.e, st.shared.len())?;
                    replicate = replicate_evidence(base, &xt, &st.e, ev.0, gate);
                    (Level::WithinRun, ev)
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
