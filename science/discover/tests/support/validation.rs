//! Scoring `capstan discover` on planted sets (shared by tests/planted.rs and the examples
//! validate.rs and calibrate.rs; each uses part of it).
#![allow(dead_code)]

use capstan_data::Dataset;
use capstan_discover::{discover, Discovery, Options};
use capstan_validation::discover_cases::{self, DiscoverCase, Group, Variety, KINDS};
use std::collections::BTreeSet;

#[path = "control.rs"]
mod control;
pub use control::Control;

/// One set's outcome.
#[derive(Clone, Debug)]
pub struct Outcome {
    pub kind: &'static str,
    pub group: Group,
    /// A near-twin of what the model already has at this design (`Kind::twin`).
    pub twin: bool,
    /// The outside physics planted (a mixed set's draw), if any.
    pub planted: Option<&'static str>,
    pub size: f64,
    pub proposed: Vec<&'static str>,
    /// A proposed term has the right dependence.
    pub right: bool,
    /// ... or a rival of a proposed term has it.
    pub right_or_rival: bool,
    /// A mixed set's extra catalogue effect is in the answer's catalogue (the engine's selection
    /// with the proposed terms taken out of the data, where a term is proposed) and no proposed
    /// term took its place.
    pub effect_named: bool,
    /// A term proposed and the lack of fit resolved.
    pub confident: bool,
    /// The last term proposed is partial (the lack of fit stays, most of it removed; a later
    /// term may resolve what an earlier partial one left).
    pub partial: bool,
    pub unexplained_after: bool,
    /// The oracle (expressible kinds): the best ΔBIC of a library term of the right dependence
    /// in the first screen (given the catalogue as the engine selected it), with its physical
    /// sign and separable (VIF ≤ 100); None when no such term is testable.
    pub oracle_dbic: Option<f64>,
    /// ... and whether such a term passes the search's first bar and the replicate gate: the
    /// planted physics is detectable at all.
    pub oracle_detects: bool,
    pub elapsed_s: f64,
    /// A mixed set's control: the same set without its outside physics ([`control`]).
    pub control: Option<Control>,
    /// Runs of the design the firmware cut short or never logged (a planted T1 tare can make
    /// it read a slack cord at the first level and stop the run with `cord_break`, as it
    /// should), and the design's runs.
    pub runs_short: (usize, usize),
    /// Rows of the set.
    pub rows: usize,
    /// The set's kind and design, in words.
    pub label: String,
    pub describe: String,
}

impl Outcome {
    /// A null or inexpressible set with a term proposed: a false term.
    pub fn false_term(&self) -> bool {
        matches!(self.group, Group::Null | Group::Inexpressible) && !self.proposed.is_empty()
    }

    /// An expressible kind the design can tell apart (not a near-twin).
    pub fn distinguishable(&self) -> bool {
        self.group == Group::Expressible && !self.twin
    }

    /// A mixed set answered right: the effect named and the term found.
    pub fn mixed_ok(&self) -> bool {
        self.group == Group::Mixed && self.effect_named && self.right
    }

    /// A mixed set whose control (the same set without the outside physics) has the third
    /// effect named: the catalogue alone names it at this design.
    pub fn control_named(&self) -> bool {
        self.control.as_ref().is_some_and(|c| c.named)
    }
}

fn deps(d: &[capstan_discover::library::Var]) -> BTreeSet<&'static str> {
    d.iter().map(|v| v.name()).collect()
}

fn right_of(c: &DiscoverCase) -> impl Fn(BTreeSet<&'static str>) -> bool + '_ {
    move |set: BTreeSet<&'static str>| {
        c.right()
            .iter()
            .any(|r| r.iter().copied().collect::<BTreeSet<_>>() == set)
    }
}

pub fn score(c: &DiscoverCase, d: &Discovery) -> Outcome {
    let ok = right_of(c);
    let right = d.terms.iter().any(|t| ok(deps(t.depends_on)));
    let right_or_rival = right
        || d.terms
            .iter()
            .any(|t| t.rivals.iter().any(|r| ok(deps(r.depends_on))));
    // The answer's catalogue: the one the engine selects with the proposed terms taken out of
    // the data where that differs (the term's words say so), else the one it selected first.
    let catalogue = d
        .catalogue_given_terms
        .as_ref()
        .unwrap_or(&d.catalogue_effects);
    let effect_named = c.extra.is_some_and(|e| {
        let name = e.kind.name();
        catalogue.contains(&name)
            && d.terms
                .iter()
                .all(|t| t.displaced.as_ref().is_none_or(|x| x.effect != name))
    });
    // Where the terms of the right dependence stood in the first screen (a diagnostic).
    let right_terms: Vec<String> = d
        .search
        .screen
        .iter()
        .enumerate()
        .filter(|(_, r)| {
            capstan_discover::library::term(r.name).is_some_and(|t| ok(deps(t.depends_on)))
        })
        .map(|(i, r)| {
            format!(
                "#{} {} {:.1} rep {} r2 {:.2}",
                i + 1,
                r.name,
                r.delta_bic,
                r.replicate
                    .as_ref()
                    .map_or("-".into(), |x| format!("p {:.2e}", x.p)),
                r.r2_model
            )
        })
        .collect();
    let (oracle_dbic, oracle_detects) = oracle(c, d, &ok);
    let displaced: Vec<String> = d
        .terms
        .iter()
        .filter_map(|t| {
            t.displaced
                .as_ref()
                .map(|x| format!("{} for {}", t.name, x.effect))
        })
        .collect();
    Outcome {
        kind: c.kind.name,
        group: c.kind.group,
        twin: c.kind.twin.is_some(),
        planted: c.planted.map(|k| k.name),
        size: c.size,
        proposed: d.terms.iter().map(|t| t.name).collect(),
        right,
        right_or_rival,
        effect_named,
        // A term with nothing shown left (or nothing testable left) counts as confident.
        confident: !d.terms.is_empty() && d.unexplained_after != Some(true),
        partial: d.terms.last().is_some_and(|t| t.partial),
        unexplained_after: d.unexplained_after == Some(true),
        oracle_dbic,
        oracle_detects,
        elapsed_s: d.elapsed_s,
        control: None,
        runs_short: (0, 0),
        rows: d.data.rows,
        label: c.label(),
        describe: format!(
            "{} {:+.3}: oracle {:?} {} cat {:?} given terms {:?} lof {:?} | {:?} unexplained_after={:?} right {:?} displaced {:?} declined={:?}",
            c.label(),
            c.size,
            oracle_dbic.map(|x| (x * 10.0).round() / 10.0),
            if oracle_detects { "detects" } else { "misses" },
            d.catalogue_effects,
            d.catalogue_given_terms,
            d.lack_of_fit_before
                .as_ref()
                .map(|l| (l.p, l.systematic_ratio)),
            d.terms
                .iter()
                .map(|t| (
                    t.name,
                    t.lack_of_fit_after
                        .as_ref()
                        .map(|l| ((l.p * 1e4).round() / 1e4, (l.systematic_ratio * 100.0).round() / 100.0))
                ))
                .collect::<Vec<_>>(),
            d.unexplained_after,
            right_terms,
            displaced,
            d.declined
                .iter()
                .map(|x| (x.name, x.reason.clone()))
                .collect::<Vec<_>>()
        ),
    }
}

/// The oracle of a set: the best right-dependence term of the first screen that keeps its
/// physical sign and is separable from the catalogue (ΔBIC, before the search penalty), and
/// whether one passes the search's first bar and the replicate gate.
fn oracle(
    c: &DiscoverCase,
    d: &Discovery,
    ok: &dyn Fn(BTreeSet<&'static str>) -> bool,
) -> (Option<f64>, bool) {
    if !matches!(c.kind.group, Group::Expressible | Group::Mixed) {
        return (None, false);
    }
    let bar = d.search.first_bar;
    let right: Vec<_> = d
        .search
        .screen
        .iter()
        .filter(|r| r.sign_ok && r.r2_model <= Options::default().max_r2_model)
        .filter(|r| capstan_discover::library::term(r.name).is_some_and(|t| ok(deps(t.depends_on))))
        .collect();
    let best = right
        .iter()
        .map(|r| r.delta_bic)
        .fold(None, |m: Option<f64>, x| Some(m.map_or(x, |m| m.min(x))));
    let detects = right
        .iter()
        .any(|r| r.delta_bic < bar && r.replicate.as_ref().is_none_or(|x| x.passed));
    (best, detects)
}

/// The size scale of the planted physics (`CAPSTAN_DISCOVER_SCALE`, default 1): the power
/// curve multiplies every planted size by it.
pub fn size_scale() -> f64 {
    std::env::var("CAPSTAN_DISCOVER_SCALE")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1.0)
}

/// The designs (`CAPSTAN_DISCOVER_DESIGN`: `varied`, the default; `thesis`; `updown`, the
/// thesis's with every run up-down).
pub fn variety() -> Variety {
    match std::env::var("CAPSTAN_DISCOVER_DESIGN").as_deref() {
        Ok("thesis") => Variety::Thesis,
        Ok("updown") => Variety::ThesisUpDown,
        _ => Variety::Varied,
    }
}

/// The sets of `seed` (`per_kind` of every kind, `CAPSTAN_DISCOVER_KINDS` to keep some),
/// simulated; with `CAPSTAN_DISCOVER_CACHE=DIR` kept in DIR as pairs CSVs (read back exactly)
/// so that a calibration can be re-run without re-simulating.
pub fn sets(seed: u64, per_kind: usize, threads: usize) -> (Vec<DiscoverCase>, Vec<Dataset>) {
    sets_scaled(seed, per_kind, threads, size_scale())
}

/// [`sets`] with every planted size multiplied by `scale`.
pub fn sets_scaled(
    seed: u64,
    per_kind: usize,
    threads: usize,
    scale: f64,
) -> (Vec<DiscoverCase>, Vec<Dataset>) {
    let variety = variety();
    let mut cases = discover_cases::draw_all(seed, per_kind, variety);
    if scale != 1.0 {
        for c in cases.iter_mut() {
            c.scale(scale);
        }
    }
    if let Ok(only) = std::env::var("CAPSTAN_DISCOVER_KINDS") {
        let only: Vec<&str> = only.split(',').collect();
        cases.retain(|c| only.contains(&c.kind.name));
    }
    let data = simulate(seed, &cases, &tag(variety, scale), threads);
    (cases, data)
}

/// The cache tag of a design variety and size scale.
fn tag(variety: Variety, scale: f64) -> String {
    format!(
        "{}{}",
        match variety {
            Variety::Thesis => "",
            Variety::ThesisUpDown => "-updown",
            Variety::Varied => "-varied",
        },
        if scale == 1.0 {
            String::new()
        } else {
            format!("-x{scale}")
        }
    )
}

/// `cases` simulated (read back from `CAPSTAN_DISCOVER_CACHE` where kept there, under `tag`).
fn simulate(seed: u64, cases: &[DiscoverCase], tag: &str, threads: usize) -> Vec<Dataset> {
    let dir = std::env::var("CAPSTAN_DISCOVER_CACHE").ok();
    let path = |c: &DiscoverCase| {
        dir.as_ref()
            .map(|d| std::path::Path::new(d).join(format!("s{seed}-{}{tag}.csv", c.case.seed)))
    };
    let mut data: Vec<Option<Dataset>> = cases
        .iter()
        .map(|c| path(c).and_then(|p| capstan_data::load_pairs(&p).ok()))
        .collect();
    let todo: Vec<usize> = (0..cases.len()).filter(|&i| data[i].is_none()).collect();
    if !todo.is_empty() {
        let plain: Vec<_> = todo.iter().map(|&i| cases[i].case.clone()).collect();
        let made =
            capstan_validation::score::generate(&plain, threads).unwrap_or_else(|e| panic!("{e}"));
        for (&i, ds) in todo.iter().zip(made) {
            if let Some(p) = path(&cases[i]) {
                let _ = std::fs::create_dir_all(p.parent().expect("dir"));
                let _ = capstan_data::write_pairs(&p, &ds.pairs);
            }
            data[i] = Some(ds);
        }
    }
    data.into_iter().map(|d| d.expect("made")).collect()
}

/// The search's options as the environment sets them (the calibration's knobs).
pub fn options_from_env() -> Options {
    let mut opts = Options::default();
    let get = |k: &str| std::env::var(k).ok().map(|v| v.parse::<f64>().expect(k));
    if let Some(v) = get("CAPSTAN_DISCOVER_MAX_R2") {
        opts.max_r2_model = v;
    }
    if let Some(v) = get("CAPSTAN_DISCOVER_TRIES") {
        opts.max_tries = v as usize;
    }
    if let Some(v) = get("CAPSTAN_DISCOVER_PARTIAL") {
        opts.min_share_resolved = v;
    }
    if let Some(v) = get("CAPSTAN_DISCOVER_REPLICATE_ALPHA") {
        opts.replicate_alpha = v;
    }
    if std::env::var("CAPSTAN_DISCOVER_REPLICATE_RULE").is_ok_and(|v| v == "searchbar") {
        opts.replicate_rule = capstan_discover::replicate::ReplicateRule::SearchBar;
    }
    if let Some(v) = get("CAPSTAN_DISCOVER_RESTORE") {
        opts.restore = v != 0.0;
    }
    if std::env::var("CAPSTAN_DISCOVER_STAB_HIT").is_ok_and(|v| v == "dependence") {
        opts.stability_hit = capstan_discover::stability::Hit::Dependence;
    }
    if let Some(v) = get("CAPSTAN_DISCOVER_SHARE_ALWAYS") {
        opts.share_always = v != 0.0;
    }
    if let Some(v) = get("CAPSTAN_DISCOVER_STABILITY") {
        opts.min_stability = v;
    }
    if let Some(v) = get("CAPSTAN_DISCOVER_BUMP_CENTRES") {
        opts.bump_centres = v as usize;
    }
    opts.engine.threads = 1;
    opts
}

/// Search every set with `opts` on `threads`.
pub fn search(
    cases: &[DiscoverCase],
    data: &[Dataset],
    opts: &Options,
    threads: usize,
) -> Vec<Outcome> {
    let out = std::sync::Mutex::new(vec![None; cases.len()]);
    let next = std::sync::atomic::AtomicUsize::new(0);
    std::thread::scope(|s| {
        for _ in 0..threads.max(1) {
            s.spawn(|| loop {
                let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                if i >= cases.len() {
                    break;
                }
                let d = discover(&data[i], opts, &mut |_, _| {});
                let mut o = score(&cases[i], &d);
                o.runs_short = cases[i].case.runs_short(&data[i]);
                if o.runs_short.0 > 0 {
                    o.describe += &format!(
                        " | {} of {} runs cut short by the firmware ({} rows)",
                        o.runs_short.0,
                        o.runs_short.1,
                        data[i].pairs.len()
                    );
                }
                out.lock().unwrap()[i] = Some(o);
            });
        }
    });
    out.into_inner().unwrap().into_iter().flatten().collect()
}

/// Simulate and search `per_kind` sets of every kind on `threads`, with the environment's
/// options.
pub fn run(seed: u64, per_kind: usize, threads: usize) -> Vec<Outcome> {
    let (cases, data) = sets(seed, per_kind, threads);
    let opts = options_from_env();
    let mut out = search(&cases, &data, &opts, threads);
    control::attach(seed, &cases, &mut out, &opts, threads);
    out
}

/// (hits, sets) of `hit` among the outcomes `pick` selects.
pub fn rate(
    out: &[Outcome],
    pick: impl Fn(&Outcome) -> bool,
    hit: impl Fn(&Outcome) -> bool,
) -> (usize, usize) {
    let sel: Vec<&Outcome> = out.iter().filter(|o| pick(o)).collect();
    (sel.iter().filter(|o| hit(o)).count(), sel.len())
}

/// The summary figures the targets read: false terms on null and inexpressible sets
/// together, the right dependence on the distinguishable kinds, mixed sets answered right.
pub fn headline(out: &[Outcome]) -> String {
    let f = rate(
        out,
        |o| matches!(o.group, Group::Null | Group::Inexpressible),
        |o| o.false_term(),
    );
    let d = rate(out, |o| o.distinguishable(), |o| o.right);
    let m = rate(out, |o| o.group == Group::Mixed, |o| o.mixed_ok());
    let c = rate(out, |o| o.control_named(), |o| o.mixed_ok());
    let pct = |(a, b): (usize, usize)| 100.0 * a as f64 / b.max(1) as f64;
    format!(
        "false terms (clean, catalogue-only, inexpressible) {}/{} ({:.1} %); right dependence, distinguishable kinds {}/{} ({:.1} %); mixed sets, effect named and term found {}/{} ({:.1} %), of those whose control names the effect {}/{} ({:.1} %)",
        f.0,
        f.1,
        pct(f),
        d.0,
        d.1,
        pct(d),
        m.0,
        m.1,
        pct(m),
        c.0,
        c.1,
        pct(c)
    )
}

/// Counts per kind: (sets, proposed, right, right or rival, confident, unexplained kept).
pub fn table(out: &[Outcome]) -> String {
    let mut s = String::from(
        "| kind | group | sets | oracle detects | term proposed | right dependence | right or named rival | confident (lack of fit resolved) | unexplained kept |\n|---|---|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for k in KINDS.iter() {
        let o: Vec<&Outcome> = out.iter().filter(|o| o.kind == k.name).collect();
        if o.is_empty() {
            continue;
        }
        let n = |f: &dyn Fn(&Outcome) -> bool| o.iter().filter(|x| f(x)).count();
        let name = match (k.group, k.twin) {
            (Group::Mixed, _) => format!(
                "mixed (effect named {}; and term found {})",
                n(&|x| x.effect_named),
                n(&|x| x.mixed_ok())
            ),
            (_, Some(_)) => format!("{} (twin)", k.name),
            _ => k.name.to_string(),
        };
        s += &format!(
            "| {} | {:?} | {} | {} | {} | {} | {} | {} | {} |\n",
            name,
            k.group,
            o.len(),
            if matches!(k.group, Group::Expressible | Group::Mixed) {
                n(&|x| x.oracle_detects).to_string()
            } else {
                "—".into()
            },
            n(&|x| !x.proposed.is_empty()),
            n(&|x| x.right),
            n(&|x| x.right_or_rival),
            n(&|x| x.confident),
            n(&|x| x.unexplained_after)
        );
    }
    let expr = |twin: Option<bool>| {
        let o: Vec<&Outcome> = out
            .iter()
            .filter(|o| o.group == Group::Expressible && twin.is_none_or(|t| o.twin == t))
            .collect();
        let n = |f: &dyn Fn(&Outcome) -> bool| o.iter().filter(|x| f(x)).count();
        format!(
            "oracle detects {}/{}, right dependence {}/{}",
            n(&|x| x.oracle_detects),
            o.len(),
            n(&|x| x.right),
            o.len()
        )
    };
    let cut: Vec<&Outcome> = out.iter().filter(|o| o.runs_short.0 > 0).collect();
    if !cut.is_empty() {
        let kinds: BTreeSet<&str> = cut.iter().map(|o| o.kind).collect();
        s += &format!(
            "\n{} sets ({}) lost {} of their {} runs to the firmware's safety stops (planted physics it reads as a fault, e.g. a T1 tare that makes the first level look slack: cord_break); they are scored as the smaller sets they are.\n",
            cut.len(),
            kinds.into_iter().collect::<Vec<_>>().join(", "),
            cut.iter().map(|o| o.runs_short.0).sum::<usize>(),
            cut.iter().map(|o| o.runs_short.1).sum::<usize>()
        );
    }
    s += &control::summary(out);
    s += &format!(
        "\nexpressible, all: {}\nexpressible, distinguishable at this design: {}\nexpressible, near-twins (indistinguishable at this design): {}\n{}\n{}\n",
        expr(None),
        expr(Some(false)),
        expr(Some(true)),
        headline(out),
        timing(out)
    );
    s
}

/// The search's time per 1,000 rows over the sets (this build's; `elapsed_s` of each answer,
/// the engine's catalogue selection included, one thread a set).
fn timing(out: &[Outcome]) -> String {
    let mut per: Vec<f64> = out
        .iter()
        .filter(|o| o.rows > 0)
        .map(|o| 1000.0 * o.elapsed_s / o.rows as f64)
        .collect();
    per.sort_by(f64::total_cmp);
    match per.len() {
        0 => String::new(),
        n => {
            let worst = out
                .iter()
                .filter(|o| o.rows > 0)
                .max_by(|a, b| {
                    (a.elapsed_s / a.rows as f64).total_cmp(&(b.elapsed_s / b.rows as f64))
                })
                .map_or(String::new(), |o| {
                    format!(" ({}, {} rows, {:.2} s)", o.label, o.rows, o.elapsed_s)
                });
            format!(
                "discover per 1,000 rows: median {:.2} s, worst {:.2} s over {n} sets{worst}",
                per[n / 2],
                per[n - 1]
            )
        }
    }
}
