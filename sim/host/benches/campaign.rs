//! Times the default campaign (the thesis's 2 diameters × 5 wraps × 6 runs of 131.5 s, both
//! channels sampled at 1 kHz through the firmware's own code) and prints the real-time factor.
//!
//! `cargo bench -p capstan-sim` (release). `--threads N` to pin the worker count; `--repeat N`
//! to take the best of N.

use capstan_sim::campaign::{run_campaign, CampaignConfig};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let opt = |name: &str| {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1))
            .and_then(|v| v.parse::<usize>().ok())
    };
    let threads = opt("--threads").unwrap_or(0);
    let repeat = opt("--repeat").unwrap_or(3).max(1);
    let cfg = CampaignConfig {
        threads,
        ..CampaignConfig::default()
    };
    let mut best: Option<(f64, f64, usize, usize)> = None;
    for _ in 0..repeat {
        let r = run_campaign(&cfg).expect("the default campaign runs");
        let ticks: u64 = r.runs.iter().map(|x| (x.simulated_s * 1000.0) as u64).sum();
        println!(
            "campaign: {} runs, {} pairs, {:.0} s simulated in {:.3} s wall on {} threads: \
             {:.0}x real time, {:.0} ns per 1 ms tick per thread",
            r.runs.len(),
            r.rows.len(),
            r.simulated_s,
            r.wall_s,
            r.threads,
            r.realtime_factor(),
            r.wall_s * r.threads as f64 / ticks as f64 * 1e9
        );
        if best.is_none_or(|b| r.wall_s < b.1) {
            best = Some((r.simulated_s, r.wall_s, r.threads, r.rows.len()));
        }
    }
    let (sim, wall, threads, pairs) = best.unwrap();
    println!(
        "best: {pairs} pairs, {sim:.0} s simulated in {wall:.3} s on {threads} threads = {:.0}x real time",
        sim / wall
    );
}
