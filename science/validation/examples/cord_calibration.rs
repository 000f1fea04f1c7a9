//! The between-cord calibration's figures: `cargo run --release -p capstan-validation --example
//! cord_calibration -- [CASES_PER_TRUTH] [SEED] [CORDS_PER_CELL]` (defaults: 100 per truth,
//! the asserted seed, 1 new cord per (diameter, wrap): the thesis's 10 cords). Prints each
//! figure with its target, what was said per truth, and the oracle's bound on the power
//! figures (`capstan_validation::cord_bounds`: what any test of the cords' mu could reach on the
//! same design).
use capstan_engine::evidence::between::CORD_ALPHA;
use capstan_validation::cord_bounds::oracle;
use capstan_validation::cord_calibration::{cases, run, CordFigures, ASSERT_SEED};
use capstan_validation::cord_cases::Truth;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(100);
    let seed: u64 = args
        .get(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(ASSERT_SEED);
    let reps: u32 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(1);
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get());
    let t = Instant::now();
    let outcomes = run(&cases(seed, n, reps), threads).expect("every case simulates");
    let f = CordFigures::of(&outcomes);
    println!(
        "{} cases per truth, seed {seed}, {} cords per (diameter, wrap), {:.0} s",
        n,
        reps,
        t.elapsed().as_secs_f64()
    );
    for l in f.lines() {
        println!("  {l}");
    }
    for truth in [Truth::Diameter, Truth::WrapTurn] {
        for alpha in [CORD_ALPHA, 0.05] {
            println!("  {}", oracle(truth, reps, alpha, 4000, seed).line());
        }
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
