//! The between-cord calibration's figures: `cargo run --release -p capstan-truth --example
//! cord_calibration -- [CASES_PER_TRUTH] [SEED]` (defaults: 100 per truth, the asserted seed).
//! Prints each figure with its target, and what was said per truth.
use capstan_truth::cord_calibration::{cases, run, CordFigures, ASSERT_SEED};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(100);
    let seed: u64 = args
        .get(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(ASSERT_SEED);
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get());
    let t = Instant::now();
    let outcomes = run(&cases(seed, n), threads).expect("every case simulates");
    let f = CordFigures::of(&outcomes);
    println!(
        "{} cases per truth, seed {seed}, {:.0} s",
        n,
        t.elapsed().as_secs_f64()
    );
    for l in f.lines() {
        println!("  {l}");
    }
    if let Some(path) = std::env::var_os("CAPSTAN_CORDS_JSON") {
        std::fs::write(path, serde_json::to_string(&outcomes).expect("JSON")).expect("written");
    }
    for (truth, said) in &f.answers {
        println!("{truth}:");
        for (what, k) in said {
            println!("    {k:4}  {what}");
        }
    }
}
