//! The gates as tests: every gate's statistic per set (`capstan_discover::profile`) and its
//! false-positive rate and power over the planted sets.
#![allow(dead_code)]

use capstan_data::Dataset;
use capstan_discover::library;
use capstan_discover::profile::{profile, GateRow};
use capstan_discover::Options;
use capstan_validation::discover_cases::DiscoverCase;

/// One set's profile.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SetProfile {
    pub kind: &'static str,
    pub group: String,
    pub twin: bool,
    pub planted: Option<&'static str>,
    pub right: Vec<Vec<&'static str>>,
    pub label: String,
    pub updown: bool,
    pub timed: bool,
    pub diameters: usize,
    pub runs: u32,
    pub size: f64,
    pub bar: f64,
    pub n: usize,
    pub gates: Vec<GateRow>,
}

impl SetProfile {
    /// A distinguishable expressible set (or a mixed one, whose outside kind is).
    fn planted_fair(&self) -> bool {
        (self.group == "Expressible" && !self.twin) || self.group == "Mixed"
    }

    /// Does the library term `name` have the right dependence here?
    fn right_term(&self, name: &str) -> bool {
        let Some(t) = library::term(name) else {
            return false;
        };
        let mut deps: Vec<&str> = t.depends_on.iter().map(|v| v.name()).collect();
        deps.sort_unstable();
        self.right.iter().any(|r| {
            let mut r = r.clone();
            r.sort_unstable();
            r == deps
        })
    }

    /// The terms the search could pick (physical sign, separable), best screen first.
    fn eligible(&self, opts: &Options) -> impl Iterator<Item = &GateRow> {
        let max_r2 = opts.max_r2_model;
        self.gates
            .iter()
            .filter(move |g| g.sign_ok && g.r2_model <= max_r2)
    }
}

/// Every set's profile, on `threads`.
pub fn profile_all(
    cases: &[DiscoverCase],
    data: &[Dataset],
    opts: &Options,
    threads: usize,
) -> Vec<SetProfile> {
    let out = std::sync::Mutex::new(vec![None; cases.len()]);
    let next = std::sync::atomic::AtomicUsize::new(0);
    std::thread::scope(|s| {
        for _ in 0..threads.max(1) {
            s.spawn(|| loop {
                let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                if i >= cases.len() {
                    break;
                }
                let c = &cases[i];
                let (bar, n, gates) = profile(&data[i], opts);
                let p = SetProfile {
                    kind: c.kind.name,
                    group: format!("{:?}", c.kind.group),
                    twin: c.kind.twin.is_some(),
                    planted: c.planted.map(|k| k.name),
                    right: c.right().iter().map(|r| r.to_vec()).collect(),
                    label: c.label(),
                    updown: c.layout.updown,
                    timed: c.layout.timed,
                    diameters: c.layout.diameters,
                    runs: c.layout.runs,
                    size: c.size,
                    bar,
                    n,
                    gates,
                };
                out.lock().unwrap()[i] = Some(p);
            });
        }
    });
    out.into_inner().unwrap().into_iter().flatten().collect()
}

/// Whether a term passes a gate.
type Passes<'o> = Box<dyn Fn(&SetProfile, &GateRow) -> bool + 'o>;

/// One gate: its name, its stated rule, whether it applies to a term (the replicate gate to
/// within-run terms with replicate cells, the lack of fit's share where the catalogue left one
/// and the term is within runs), and whether a term passes it.
struct Gate<'o> {
    name: &'static str,
    rule: String,
    applies: fn(&GateRow) -> bool,
    passes: Passes<'o>,
}

fn gates(opts: &Options) -> Vec<Gate<'_>> {
    vec![
        Gate {
            name: "screen",
            rule: format!(
                "ΔBIC < the search's first bar (extended BIC, γ = {})",
                opts.gamma
            ),
            applies: |_| true,
            passes: Box::new(|s, g| g.delta_bic < s.bar),
        },
        Gate {
            name: "replicate runs",
            rule: format!(
                "one-sided t of the runs' shared scores, p < {}",
                opts.replicate_alpha
            ),
            applies: |g| g.replicate.is_some(),
            passes: Box::new(|_, g| {
                g.replicate
                    .as_ref()
                    .is_none_or(|r| r.p < opts.replicate_alpha)
            }),
        },
        Gate {
            name: "stability",
            rule: format!(
                "picked and past the bar in ≥ {:.0} % of {} cord resamples",
                100.0 * opts.min_stability,
                opts.resamples
            ),
            applies: |_| true,
            passes: Box::new(|_, g| g.stability >= opts.min_stability),
        },
        Gate {
            name: "held-out cords",
            rule: "pooled LOCO RMSE ratio < 1".into(),
            applies: |_| true,
            passes: Box::new(|_, g| g.heldout.as_ref().is_some_and(|h| h.value < 1.0)),
        },
        Gate {
            name: "lack of fit",
            rule: format!(
                "removes ≥ {:.0} % of the systematic variance the catalogue left{}",
                100.0 * opts.min_share_resolved,
                if opts.share_always {
                    ""
                } else {
                    " (judged only when the lack of fit stays significant with it)"
                }
            ),
            applies: |g| g.lof_share.is_some(),
            passes: Box::new(|_, g| match (g.lof_share, g.lof_open_after) {
                (_, Some(false)) if !opts.share_always => true,
                (Some(s), _) => s >= opts.min_share_resolved,
                (None, _) => true,
            }),
        },
    ]
}

fn pct(a: usize, b: usize) -> String {
    match b {
        0 => "—".into(),
        _ => format!("{a}/{b} ({:.0} %)", 100.0 * a as f64 / b as f64),
    }
}

/// Each gate as a test: on the clean and catalogue-only sets (nothing to find) and on the
/// inexpressible ones (structure no library term expresses), how often the term the screen ranks
/// first passes it (its false-positive rate, alone and given the screen passed); on the
/// distinguishable and mixed sets, how often the best term of the right dependence does (its
/// power, alone and given the screen).
pub fn tables(p: &[SetProfile], opts: &Options) -> String {
    let mut s = String::from(
        "Each gate counts the sets where it applies to the term (the replicate gate to within-run terms with replicate cells, the share to within-run terms where the catalogue left a lack of fit).\n\n| gate | rule | null sets: best term passes | … given the screen | inexpressible: best term passes | … given the screen | planted: best right term passes | … given the screen |\n|---|---|---:|---:|---:|---:|---:|---:|\n",
    );
    let gs = gates(opts);
    let screen = &gs[0];
    // (passes, sets, passes given the screen, sets past the screen) for the sets `pick`
    // selects, on the term `term` picks in each.
    let count = |g: &Gate, pick: &dyn Fn(&SetProfile) -> bool, right: bool| {
        let mut c = [0usize; 4];
        for set in p.iter().filter(|x| pick(x)) {
            let mut terms = set.eligible(opts);
            let t = match right {
                true => terms.find(|x| set.right_term(x.name)),
                false => terms.next(),
            };
            if let Some(t) = t.filter(|t| (g.applies)(t)) {
                c[1] += 1;
                c[0] += usize::from((g.passes)(set, t));
                if (screen.passes)(set, t) {
                    c[3] += 1;
                    c[2] += usize::from((g.passes)(set, t));
                }
            }
        }
        c
    };
    for g in &gs {
        let n = count(g, &|x| x.group == "Null", false);
        let i = count(g, &|x| x.group == "Inexpressible", false);
        let w = count(g, &|x| x.planted_fair(), true);
        s += &format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} |\n",
            g.name,
            g.rule,
            pct(n[0], n[1]),
            pct(n[2], n[3]),
            pct(i[0], i[1]),
            pct(i[2], i[3]),
            pct(w[0], w[1]),
            pct(w[2], w[3])
        );
    }
    s += &size_of_replicate_test(p, opts);
    s += &size_of_screen_test(p);
    s
}

/// The replicate gate's size as a test of one term: over every within-run term of the clean
/// and catalogue-only sets, the share with p below α (and below 0.05).
fn size_of_replicate_test(p: &[SetProfile], opts: &Options) -> String {
    let (mut n, mut a, mut five) = (0, 0, 0);
    for set in p.iter().filter(|s| s.group == "Null") {
        for g in set.gates.iter().filter_map(|g| g.replicate.as_ref()) {
            n += 1;
            a += usize::from(g.p < opts.replicate_alpha);
            five += usize::from(g.p < 0.05);
        }
    }
    format!(
        "\nThe replicate gate as a test of one term (every within-run term of the clean and catalogue-only sets; one-sided in the direction of the screen's estimate, which the data choose, so about a two-sided test at twice the level): p < {}: {}; p < 0.05: {}.\n",
        opts.replicate_alpha,
        pct(a, n),
        pct(five, n)
    )
}

/// The screen's statistic as a test of one term at its nominal 1 % (χ²₁ > 6.63): over every
/// within-run term of the clean and catalogue-only sets.
fn size_of_screen_test(p: &[SetProfile]) -> String {
    let (mut n, mut a) = (0, 0);
    for set in p.iter().filter(|s| s.group == "Null") {
        for g in set.gates.iter().filter(|g| g.replicate.is_some()) {
            n += 1;
            a += usize::from(-g.delta_bic + (set.n as f64).ln() > 6.63);
        }
    }
    format!(
        "The screen's statistic as a test of one term at its nominal 1 % (χ²₁ > 6.63; the same terms): {} — the run-to-run wander the replicate gate is there for.\n",
        pct(a, n)
    )
}
