//! How often the report's "the extended model's residuals still trend" fires on simulated nulls
//! at the thesis's design: `cargo run --release -p capstan-validation --example residual_trends
//! -- [CASES] [SEED] [CORDS_PER_CELL] [DIAMETERS] [mu-only]` (defaults 100 cases, the asserted
//! seed, 1 cord per (diameter, wrap), both diameters; `DIAMETERS` = 1 keeps the first: 5 cords;
//! `mu-only`: only mu scatters from cord to cord, so the extended model, with its random mu per
//! cord, is the truth's own form and every claim is false). Each case
//! is a campaign (the thesis's: ten cords)
//! of the between-cord calibration's null (heating and a T2 zero as on the thesis data, each
//! scattered from cord to cord; no trend with run, time or anything else: `cord_cases`), run
//! through the whole analysis. Prints how often the smallest of the extended model's
//! cord-clustered slope p-values is below 0.05 as it is (unadjusted) and after Holm's
//! adjustment over its family (what the report quotes), with Wilson 95 % intervals.
use capstan_validation::cord_calibration::{residual_trend_p, wilson, ASSERT_SEED};
use capstan_validation::cord_cases::{CordCase, Truth};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(100);
    let seed: u64 = (args.get(2).and_then(|s| s.parse().ok())).unwrap_or(ASSERT_SEED);
    let reps: u32 = (args.get(3).and_then(|s| s.parse().ok())).unwrap_or(1);
    let diameters: usize = (args.get(4).and_then(|s| s.parse().ok())).unwrap_or(2);
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get());
    let mut cases = CordCase::many(Truth::Null, seed, n);
    for c in &mut cases {
        c.replicates = reps;
        c.diameters_mm.truncate(diameters.max(1));
        if args.get(5).map(String::as_str) == Some("mu-only") {
            c.scatter.t2_zero_sd_n = 0.0;
            c.scatter.heating_rel = 0.0;
        }
    }
    let cords = cases[0].diameters_mm.len() * cases[0].wraps_deg.len() * reps as usize;
    let p = residual_trend_p(&cases, threads).expect("every campaign simulates and analyses");
    println!("{n} null campaigns of {cords} cords, seed {seed}");
    let mut by_test = std::collections::BTreeMap::<&str, usize>::new();
    for x in p.iter().filter(|x| x.1 < 0.05) {
        *by_test.entry(x.2.as_str()).or_default() += 1;
    }
    for (what, k) in [
        (
            "smallest p < 0.05, unadjusted",
            p.iter().filter(|x| x.0 < 0.05).count(),
        ),
        (
            "a trend claimed (Holm-adjusted p < 0.05)",
            p.iter().filter(|x| x.1 < 0.05).count(),
        ),
    ] {
        let (lo, hi) = wilson(k, n);
        println!(
            "  {what}: {k}/{n} ({:.1} %, Wilson 95 % {:.1} to {:.1} %)",
            100.0 * k as f64 / n as f64,
            100.0 * lo,
            100.0 * hi
        );
    }
    for (test, k) in by_test {
        println!("    {k:3}  {test}");
    }
}
