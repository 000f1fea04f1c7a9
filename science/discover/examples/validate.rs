//! `cargo run --release -p capstan-discover --example validate -- SEED PER_KIND [THREADS]`:
//! the planted-truth table of `capstan discover` on one master seed (the calibration seed is
//! 26, the test seed tests/planted.rs uses is 20_261_127).
#[path = "../tests/support/validation.rs"]
mod validation;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let seed: u64 = a.get(1).and_then(|s| s.parse().ok()).unwrap_or(26);
    let per_kind: usize = a.get(2).and_then(|s| s.parse().ok()).unwrap_or(4);
    let threads: usize = a.get(3).and_then(|s| s.parse().ok()).unwrap_or(2);
    let t0 = std::time::Instant::now();
    let out = validation::run(seed, per_kind, threads);
    for o in &out {
        eprintln!("{}", o.describe);
    }
    println!(
        "seed {seed}, {per_kind} per kind, {:.0} s",
        t0.elapsed().as_secs_f64()
    );
    println!("{}", validation::table(&out));
}
