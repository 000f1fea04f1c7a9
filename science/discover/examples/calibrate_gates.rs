//! `cargo run --release -p capstan-discover --example calibrate_gates -- SEED PER_KIND [THREADS] [OUT.jsonl]`:
//! every gate of `capstan discover` as a test (docs/README-discover.md, "The gates as tests"):
//! on the planted sets of SEED (the varied designs; `CAPSTAN_DISCOVER_CACHE=DIR` keeps them),
//! each gate's statistic for every testable term at the first step ([`capstan_discover::profile`]),
//! written one set a line to OUT.jsonl if given, and the gates' false-positive rates and power
//! printed.
#[path = "../tests/support/validation.rs"]
mod validation;

#[path = "support/gates.rs"]
mod gates;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let seed: u64 = a.get(1).and_then(|s| s.parse().ok()).unwrap_or(26);
    let per_kind: usize = a.get(2).and_then(|s| s.parse().ok()).unwrap_or(12);
    let threads: usize = a.get(3).and_then(|s| s.parse().ok()).unwrap_or(2);
    let t0 = std::time::Instant::now();
    let (cases, data) = validation::sets(seed, per_kind, threads);
    let opts = validation::options_from_env();
    let profiles = gates::profile_all(&cases, &data, &opts, threads);
    if let Some(path) = a.get(4) {
        let mut s = String::new();
        for p in &profiles {
            s += &serde_json::to_string(p).expect("json");
            s.push('\n');
        }
        std::fs::write(path, s).expect("write");
    }
    println!(
        "seed {seed}, {per_kind} per kind, {} sets, {:.0} s",
        cases.len(),
        t0.elapsed().as_secs_f64()
    );
    println!("{}", gates::tables(&profiles, &opts));
}
