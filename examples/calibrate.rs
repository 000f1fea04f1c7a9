//! Calibrate and evaluate `capstan diagnose` on generated cases (`capstan_validation::cases`).
//!
//! ```text
//! cargo run --release --example calibrate -- [SEED] [--every K] [--grid] [--verbose]
//!                                            [--dump-seed CASE_SEED]
//!                                            [--dump-outside ROWS | --dump-single ROWS I]
//! ```
//! * without `--grid`: the figures of the default decision rule on the cases of SEED (every
//!   K-th case), with every miss;
//! * `--grid`: the same figures for a grid of thresholds (within-run ΔBIC, between ΔBIC, the
//!   adequacy test's α and size), on the same simulated data sets: how the thresholds in
//!   `science/engine/src/evidence/mod.rs` and `science/engine/src/evidence/adequacy.rs` were
//!   chosen (on seed 99; the test asserts on another seed);
//! * `--dump-seed S`: write the case with seed S to /tmp/case.csv.
use capstan_engine::diagnose::{diagnose_with, Options};
use capstan_engine::evidence::AdequacyRule;
use capstan_validation::{cases, score};

fn arg<T: std::str::FromStr>(args: &[String], name: &str) -> Option<T> {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let seed: u64 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(99);
    let every: usize = arg(&args, "--every").unwrap_or(1);
    let verbose = args.iter().any(|a| a == "--verbose");
    let cs: Vec<cases::Case> = cases::draw_cases(seed)
        .into_iter()
        .enumerate()
        .filter(|(i, _)| i % every == 0)
        .map(|x| x.1)
        .collect();
    let dump = ["--dump-outside", "--dump-single"]
        .iter()
        .find_map(|f| args.iter().position(|a| a == f));
    if let Some(i) = dump {
        // A benchmark case scaled to about ROWS rows: `--dump-outside ROWS` (case 0 of the
        // outside class) or `--dump-single ROWS INDEX` (single-effect case INDEX).
        let rows: f64 = args
            .get(i + 1)
            .and_then(|v| v.parse().ok())
            .unwrap_or(1000.0);
        let mut c = if args[i] == "--dump-single" {
            let index = args.get(i + 2).and_then(|v| v.parse().ok()).unwrap_or(0);
            cases::draw_case(seed, cases::Class::Single, index)
        } else {
            cases::draw_case(seed, cases::Class::Outside, 0)
        };
        let cords =
            c.config.wraps_deg.len() * c.config.diameters_mm.len() * c.config.drive_vs.len();
        c.config.runs = ((rows / (12.0 * cords as f64)).round() as u32).clamp(2, 400);
        let (d, _) = c.generate().expect("the case simulates");
        let mut f = std::fs::File::create("/tmp/case.csv").expect("/tmp is writable");
        capstan_data::write_pairs_to(&mut f, &d.pairs).expect("written");
        eprintln!("wrote /tmp/case.csv: {}", c.describe());
        return;
    }
    if let Some(s) = arg::<u64>(&args, "--dump-seed") {
        let c = cs
            .iter()
            .find(|c| c.seed == s)
            .expect("a case with that seed");
        let (d, _) = c.generate().expect("the case simulates");
        let mut f = std::fs::File::create("/tmp/case.csv").expect("/tmp is writable");
        capstan_data::write_pairs_to(&mut f, &d.pairs).expect("written");
        eprintln!("wrote /tmp/case.csv: {}", c.describe());
        return;
    }
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let t0 = std::time::Instant::now();
    let data = score::generate(&cs, threads).expect("every case simulates");
    eprintln!(
        "{} cases simulated in {:.1} s",
        cs.len(),
        t0.elapsed().as_secs_f64()
    );
    if args.iter().any(|a| a == "--grid") {
        println!("within between alpha ratio | single pairs outside clean | small");
        for within in [6.0, 7.0, 8.0] {
            for between in [4.0, 5.0, 6.0] {
                for (alpha, ratio) in [(1e-3, 0.35), (1e-3, 0.5)] {
                    let opts = Options {
                        within_threshold: within,
                        between_threshold: between,
                        adequacy: AdequacyRule {
                            alpha,
                            min_ratio: ratio,
                            ..AdequacyRule::default()
                        },
                        threads: 1,
                        ..Options::default()
                    };
                    let out = score::evaluate(&cs, &data, threads, |d| diagnose_with(d, &opts));
                    let m = score::Metrics::of(&out);
                    let f = |x: (usize, usize)| 100.0 * x.0 as f64 / x.1.max(1) as f64;
                    println!(
                        "{within:>6} {between:>7} {alpha:>5} {ratio:>5} | {:>5.1} {:>5.1} {:>5.1} {:>5.1} | {:>5.1}{}",
                        f(m.single),
                        f(m.pairs),
                        f(m.outside),
                        f(m.clean_alarms),
                        f(m.small),
                        if m.failures().is_empty() { "  passes" } else { "" }
                    );
                }
            }
        }
        return;
    }
    // `--rival-gap G`: report rivals up to G (the figures below for every gap up to it).
    let rival_gap = arg(&args, "--rival-gap").unwrap_or(capstan_engine::evidence::RIVAL_GAP);
    let opts = Options {
        rival_gap,
        ..Options::default()
    };
    let out = score::evaluate(&cs, &data, threads, |d| diagnose_with(d, &opts));
    let m = score::Metrics::of(&out);
    print!("{}", m.table());
    print_rivals(&out, rival_gap);
    for class in [cases::Class::Single, cases::Class::SmallSingle] {
        let pe: Vec<String> = score::per_effect(&out, class)
            .iter()
            .filter(|x| x.2 > 0)
            .map(|(k, a, b)| format!("{}:{a}/{b}", k.name()))
            .collect();
        println!("{}: {}", class.name(), pe.join(" "));
    }
    for o in &out {
        if !o.correct() || verbose {
            let found: Vec<String> = o
                .found
                .iter()
                .map(|e| format!("{}={:.4}", e.kind, e.value))
                .collect();
            let rivals: Vec<String> = o
                .rivals
                .iter()
                .map(|(f, r, b)| format!("{r} for {f} (+{b:.1})"))
                .collect();
            println!(
                "{} {} -> {:?} unexplained={} {:?} rivals {:?} | {}",
                if o.correct() { "ok  " } else { "MISS" },
                o.describe,
                found,
                o.unexplained,
                o.pattern,
                rivals,
                o.candidates
            );
        }
    }
    let rows: usize = out.iter().map(|o| o.rows).sum();
    let secs: f64 = out.iter().map(|o| o.elapsed_s).sum();
    println!(
        "diagnose: {:.1} ms per 1000 rows on average",
        1e3 * secs / rows as f64 * 1000.0
    );
}

/// The rival figures of [`score::Metrics`] for each gap up to `max_gap` (the outcomes hold the
/// rivals up to it): how many right single/pair calls carry a rival, and how many calls of one
/// effect in place of another report the planted one as its rival.
fn print_rivals(out: &[score::Outcome], max_gap: f64) {
    println!("rival gap | right calls with a rival | one in place of another: truth a rival");
    let mut gap = 2.0;
    while gap <= max_gap + 1e-9 {
        let within: Vec<score::Outcome> = out
            .iter()
            .cloned()
            .map(|mut o| {
                o.rivals.retain(|r| r.2 < gap);
                o
            })
            .collect();
        let m = score::Metrics::of(&within);
        let (d, c) = (m.rival_doubts, m.rival_catches);
        println!("{gap:>9.0} | {:>4}/{:<4} | {:>4}/{:<4}", d.0, d.1, c.0, c.1);
        gap += 2.0;
    }
}
