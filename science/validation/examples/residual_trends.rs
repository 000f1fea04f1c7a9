//! How often the report's "the extended model's residuals still trend" fires on simulated nulls
//! at the thesis's design: `cargo run --release -p capstan-validation --example residual_trends
//! -- [CASES] [SEED]` (defaults 100 cases, the asserted seed). Each case is a ten-cord campaign
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
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get());
    let p = residual_trend_p(&CordCase::many(Truth::Null, seed, n), threads)
        .expect("every campaign simulates and analyses");
    println!("{n} null campaigns of 10 cords, seed {seed}");
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
}
