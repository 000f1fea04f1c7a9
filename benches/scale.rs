//! How `diagnose` and `analyze` scale with the number of rows: a thesis-noise campaign
//! simulated end to end (10 cords × 84 runs ≈ 10,000 rows), repeated with new run numbers to
//! 10,000, 100,000 and 1,000,000 rows (the same 10 cords, ever more runs), each diagnosed and
//! analysed once. Prints the wall time, rows per second and the process's peak resident memory
//! after each step. Target: 1,000,000 rows in ≤ 60 s and ≤ 1 GB for each command.
//!
//! `cargo bench --bench scale` (release); `-- --max-rows N` stops at N rows (default
//! 1,000,000); `-- --diagnose-only` skips the analysis.

use capstan_data::{Dataset, Pair};
use capstan_validation::cases::{self, Class};
use std::time::Instant;

/// The data set repeated `k` times, each copy's runs numbered after the last copy's.
fn repeated(base: &Dataset, k: usize) -> Dataset {
    let max_run = base.pairs.iter().filter_map(|p| p.run).fold(0.0, f64::max);
    let pairs: Vec<Pair> = (0..k)
        .flat_map(|c| {
            base.pairs.iter().map(move |p| Pair {
                run: p.run.map(|r| r + c as f64 * max_run),
                ..p.clone()
            })
        })
        .collect();
    Dataset::from_pairs(&format!("{} ×{k}", base.source), pairs).expect("new run numbers")
}

/// Peak resident memory of this process so far, MB (Linux; NaN elsewhere).
fn peak_rss_mb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        })
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let max_rows = args
        .iter()
        .position(|a| a == "--max-rows")
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse::<usize>().ok())
        .unwrap_or(1_000_000);
    let diagnose_only = args.iter().any(|a| a == "--diagnose-only");
    let mut case = cases::draw_case(1, Class::Clean, 0);
    case.config.runs = 84;
    case.config.threads = 0;
    let t = Instant::now();
    let (base, _) = case.generate().expect("the campaign simulates");
    println!(
        "simulated {} rows ({} runs) in {:.1} s",
        base.pairs.len(),
        case.config.run_count(),
        t.elapsed().as_secs_f64()
    );
    println!(
        "{:>9} {:>9} {:>10} {:>12} {:>14}",
        "rows", "command", "wall s", "rows/s", "peak RSS MB"
    );
    for k in [1, 10, 100] {
        let d = repeated(&base, k);
        if d.pairs.len() > max_rows {
            break;
        }
        let t = Instant::now();
        let diag = capstan_engine::diagnose::diagnose(&d);
        let s = t.elapsed().as_secs_f64();
        let n = d.pairs.len();
        println!(
            "{n:>9} {:>9} {s:>10.2} {:>12.0} {:>14.0}   ({})",
            "diagnose",
            n as f64 / s,
            peak_rss_mb(),
            diag.effect
        );
        if diagnose_only {
            continue;
        }
        let t = Instant::now();
        let a = capstan_engine::analysis::run(&d, capstan_engine::analysis::Options::default());
        let s = t.elapsed().as_secs_f64();
        println!(
            "{n:>9} {:>9} {s:>10.2} {:>12.0} {:>14.0}   ({})",
            "analyze",
            n as f64 / s,
            peak_rss_mb(),
            if a.is_ok() { "ok" } else { "failed" }
        );
    }
}
