//! Scoring `capstan discover` on planted sets (shared by tests/planted.rs and
//! examples/validate.rs; each uses part of it).
#![allow(dead_code)]

use capstan_discover::{discover, Discovery, Options};
use capstan_truth::discover_cases::{self, DiscoverCase, Group, KINDS};
use std::collections::BTreeSet;

/// One set's outcome.
#[derive(Clone, Debug)]
pub struct Outcome {
    pub kind: &'static str,
    pub group: Group,
    /// A near-twin of what the model already has at this design (`Kind::twin`).
    pub twin: bool,
    pub size: f64,
    pub proposed: Vec<&'static str>,
    /// A proposed term has the right dependence.
    pub right: bool,
    /// ... or a rival of a proposed term has it.
    pub right_or_rival: bool,
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
    /// ... and whether such a term passes the search's first bar, on the screen and on the
    /// replicate cells' means (the gate): the planted physics is detectable at all.
    pub oracle_detects: bool,
    pub elapsed_s: f64,
    /// Runs of the design the firmware cut short or never logged (a planted T1 tare can make
    /// it read a slack cord at the first level and stop the run with `cord_break`, as it
    /// should), and the design's runs.
    pub runs_short: (usize, usize),
    pub describe: String,
}

fn deps(d: &[capstan_discover::library::Var]) -> BTreeSet<&'static str> {
    d.iter().map(|v| v.name()).collect()
}

pub fn score(c: &DiscoverCase, d: &Discovery) -> Outcome {
    let ok = |set: BTreeSet<&'static str>| {
        c.kind
            .right
            .iter()
            .any(|r| r.iter().copied().collect::<BTreeSet<_>>() == set)
    };
    let right = d.terms.iter().any(|t| ok(deps(t.depends_on)));
    let right_or_rival = right
        || d.terms
            .iter()
            .any(|t| t.rivals.iter().any(|r| ok(deps(r.depends_on))));
    // Where the terms of the right dependence stood in the first screen (a diagnostic).
    let right_terms: Vec<String> = d
        .search
        .screen
        .iter()
        .enumerate()
        .filter(|(_, r)| {
            capstan_discover::library::LIBRARY
                .iter()
                .find(|t| t.name == r.name)
                .is_some_and(|t| ok(deps(t.depends_on)))
        })
        .map(|(i, r)| {
            format!(
                "#{} {} {:.1} rep {:.1} r2 {:.2}",
                i + 1,
                r.name,
                r.delta_bic,
                r.replicate.as_ref().map_or(f64::NAN, |x| x.delta_bic),
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
        size: c.size,
        proposed: d.terms.iter().map(|t| t.name).collect(),
        right,
        right_or_rival,
        // A term with nothing shown left (or nothing testable left) counts as confident.
        confident: !d.terms.is_empty() && d.unexplained_after != Some(true),
        partial: d.terms.last().is_some_and(|t| t.partial),
        unexplained_after: d.unexplained_after == Some(true),
        oracle_dbic,
        oracle_detects,
        elapsed_s: d.elapsed_s,
        runs_short: (0, 0),
        describe: format!(
            "{} {:+.3}: oracle {:?} {} cat {:?} lof {:?} | {:?} unexplained_after={:?} right {:?} displaced {:?} declined={:?}",
            c.kind.name,
            c.size,
            oracle_dbic.map(|x| (x * 10.0).round() / 10.0),
            if oracle_detects { "detects" } else { "misses" },
            d.catalogue_effects,
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
/// whether one passes the search's first bar on the screen and on the replicate cells' means.
fn oracle(
    c: &DiscoverCase,
    d: &Discovery,
    ok: &dyn Fn(BTreeSet<&'static str>) -> bool,
) -> (Option<f64>, bool) {
    if c.kind.group != Group::Expressible {
        return (None, false);
    }
    let bar = d.search.first_bar;
    let right: Vec<_> = d
        .search
        .screen
        .iter()
        .filter(|r| r.sign_ok && r.r2_model <= Options::default().max_r2_model)
        .filter(|r| {
            capstan_discover::library::LIBRARY
                .iter()
                .find(|t| t.name == r.name)
                .is_some_and(|t| ok(deps(t.depends_on)))
        })
        .collect();
    let best = right
        .iter()
        .map(|r| r.delta_bic)
        .fold(None, |m: Option<f64>, x| Some(m.map_or(x, |m| m.min(x))));
    let detects = right
        .iter()
        .any(|r| r.delta_bic < bar && r.replicate.as_ref().is_none_or(|x| x.delta_bic < bar));
    (best, detects)
}

/// The size scale of the planted physics (`CAPSTAN_DISCOVER_SCALE`, default 1): a power curve
/// of the oracle on the calibration seed multiplies every planted size by it.
fn size_scale() -> f64 {
    std::env::var("CAPSTAN_DISCOVER_SCALE")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1.0)
}

/// Every set's runs in up-down order (`CAPSTAN_DISCOVER_DESIGN=updown`).
fn updown() -> bool {
    std::env::var("CAPSTAN_DISCOVER_DESIGN").is_ok_and(|v| v == "updown")
}

/// The sets, simulated; with `CAPSTAN_DISCOVER_CACHE=DIR` kept in DIR as pairs CSVs
/// (read back exactly) so that a calibration can be re-run without re-simulating.
fn generate_cached(
    seed: u64,
    per_kind: usize,
    plain: &[capstan_truth::cases::Case],
    threads: usize,
) -> Vec<capstan_data::Dataset> {
    let dir = std::env::var("CAPSTAN_DISCOVER_CACHE").ok();
    let scale = size_scale();
    let mut tag = if scale == 1.0 {
        String::new()
    } else {
        format!("-x{scale}")
    };
    if updown() {
        tag += "-updown";
    }
    let path = |i: usize| {
        dir.as_ref()
            .map(|d| std::path::Path::new(d).join(format!("s{seed}-k{per_kind}{tag}-{i}.csv")))
    };
    let cached: Option<Vec<capstan_data::Dataset>> = (0..plain.len())
        .map(|i| path(i).and_then(|p| capstan_data::load_pairs(&p).ok()))
        .collect();
    if let Some(d) = cached {
        return d;
    }
    let data = capstan_truth::score::generate(plain, threads).unwrap_or_else(|e| panic!("{e}"));
    if let Some(d) = &dir {
        let _ = std::fs::create_dir_all(d);
        for (i, ds) in data.iter().enumerate() {
            if let Some(p) = path(i) {
                let _ = capstan_data::write_pairs(&p, &ds.pairs);
            }
        }
    }
    data
}

/// Simulate and search `per_kind` sets of every kind (kinds by index `every`-th) on `threads`.
pub fn run(seed: u64, per_kind: usize, threads: usize) -> Vec<Outcome> {
    let mut cases = if updown() {
        discover_cases::draw_all_updown(seed, per_kind)
    } else {
        discover_cases::draw_all(seed, per_kind)
    };
    let scale = size_scale();
    if scale != 1.0 {
        for c in cases.iter_mut().filter(|c| c.kind.group != Group::Null) {
            c.size *= scale;
            c.case.config.unmodelled.set(c.kind.name, c.size);
            c.case.outside = Some((c.kind.name, c.size));
        }
    }
    if let Ok(only) = std::env::var("CAPSTAN_DISCOVER_KINDS") {
        let only: Vec<&str> = only.split(',').collect();
        cases.retain(|c| only.contains(&c.kind.name));
    }
    let plain: Vec<capstan_truth::cases::Case> = cases.iter().map(|c| c.case.clone()).collect();
    let data = generate_cached(seed, per_kind, &plain, threads);
    let mut opts = Options::default();
    if let Ok(v) = std::env::var("CAPSTAN_DISCOVER_MAX_R2") {
        opts.max_r2_model = v.parse().expect("CAPSTAN_DISCOVER_MAX_R2");
    }
    if let Ok(v) = std::env::var("CAPSTAN_DISCOVER_TRIES") {
        opts.max_tries = v.parse().expect("CAPSTAN_DISCOVER_TRIES");
    }
    if let Ok(v) = std::env::var("CAPSTAN_DISCOVER_PARTIAL") {
        opts.min_share_resolved = v.parse().expect("CAPSTAN_DISCOVER_PARTIAL");
    }
    opts.engine.threads = 1;
    let out = std::sync::Mutex::new(vec![None; cases.len()]);
    let next = std::sync::atomic::AtomicUsize::new(0);
    std::thread::scope(|s| {
        for _ in 0..threads.max(1) {
            s.spawn(|| loop {
                let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                if i >= cases.len() {
                    break;
                }
                let d = discover(&data[i], &opts, &mut |_, _| {});
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
        s += &format!(
            "| {} | {:?} | {} | {} | {} | {} | {} | {} | {} |\n",
            k.name,
            k.group,
            o.len(),
            if k.group == Group::Expressible {
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
    s += &format!(
        "\nexpressible, all: {}\nexpressible, distinguishable at this design: {}\nexpressible, near-twins (indistinguishable at this design): {}\n",
        expr(None),
        expr(Some(false)),
        expr(Some(true))
    );
    s
}
