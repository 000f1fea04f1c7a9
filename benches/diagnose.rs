//! Times `capstan::diagnose::diagnose` on data sets of about 1,000 rows: one generated case of
//! every catalogue effect (and none) scaled to ~1,000 rows, and the thesis data (720 rows).
//! Target: under 0.2 s per data set.
//!
//! `cargo bench --bench diagnose` (release). `--repeat N` takes the best of N (default 5).

use capstan::data::thesis_dataset;
use capstan::diagnose::{cases, diagnose};
use capstan_friction::EffectKind;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let repeat = args
        .iter()
        .position(|a| a == "--repeat")
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse::<usize>().ok())
        .unwrap_or(5)
        .max(1);
    let mut sets = vec![("thesis".to_string(), thesis_dataset())];
    for kind in EffectKind::ALL {
        let mut case = cases::draw_case(1, kind, 0);
        // About 1,000 rows: 12 pairs per run.
        let c = &mut case.config;
        let cords = c.wraps_deg.len() * c.diameters_mm.len() * c.drive_vs.len();
        c.runs = ((1000.0 / (12.0 * cords as f64)).round() as u32).clamp(2, 40);
        c.threads = 0;
        let (d, _) = case.generate().expect("the case simulates");
        sets.push((kind.name().to_string(), d));
    }
    let mut worst: f64 = 0.0;
    println!(
        "{:<20} {:>6} {:>10} {:>12}  diagnosis",
        "data set", "rows", "best ms", "ms/1000 rows"
    );
    for (name, d) in &sets {
        let mut best = f64::INFINITY;
        let mut call = String::new();
        for _ in 0..repeat {
            let t = Instant::now();
            let dg = diagnose(d);
            best = best.min(t.elapsed().as_secs_f64());
            call = dg.effect.to_string();
        }
        worst = worst.max(best);
        println!(
            "{name:<20} {:>6} {:>10.1} {:>12.1}  {call}",
            d.pairs.len(),
            best * 1e3,
            best * 1e3 / d.pairs.len() as f64 * 1000.0
        );
    }
    println!(
        "slowest data set: {:.1} ms (target: under 200 ms per ~1,000 rows) — {}",
        worst * 1e3,
        if worst < 0.2 { "met" } else { "NOT met" }
    );
}
