//! Times `capstan_engine::diagnose::diagnose` on generated data sets of about 1,000 and 10,000 rows
//! (one clean set, one of every catalogue effect, the thesis's pair and one outside the
//! catalogue, all with the thesis rig's noise) and on the thesis data (720 rows).
//! Targets: under 0.2 s for 1,000 rows and under 1 s for 10,000 rows.
//!
//! `cargo bench --bench diagnose` (release). `--repeat N` takes the best of N (default 3);
//! `--quick` skips the 10,000-row sets; `--only NAME` times only the sets of that name.

use capstan_data::{thesis_dataset, Dataset};
use capstan_engine::diagnose::diagnose;
use capstan_validation::cases::{self, Case, Class};
use std::time::Instant;

/// The name of a case: its effects (or the physics outside the catalogue), `none` if clean.
fn name(case: &Case) -> String {
    let name = case
        .effects
        .iter()
        .map(|e| e.kind.name().to_string())
        .chain(case.outside.map(|o| o.0.to_string()))
        .collect::<Vec<_>>()
        .join("+");
    if name.is_empty() {
        "none".into()
    } else {
        name
    }
}

/// `case` with as many runs as make about `rows` rows (12 pairs a run).
fn scaled(mut case: Case, rows: usize) -> Dataset {
    let c = &mut case.config;
    let cords = c.wraps_deg.len() * c.diameters_mm.len() * c.drive_vs.len();
    c.runs = ((rows as f64 / (12.0 * cords as f64)).round() as u32).clamp(2, 400);
    c.threads = 0;
    case.generate().expect("the case simulates").0
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let repeat = args
        .iter()
        .position(|a| a == "--repeat")
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse::<usize>().ok())
        .unwrap_or(3)
        .max(1);
    let quick = args.iter().any(|a| a == "--quick");
    // `--only NAME`: just the sets of that name (e.g. to profile one with `perf record`).
    let only = args
        .iter()
        .position(|a| a == "--only")
        .and_then(|i| args.get(i + 1))
        .cloned();
    let mut picks = vec![cases::draw_case(1, Class::Clean, 0)];
    picks.extend((0..10).map(|i| cases::draw_case(1, Class::Single, i)));
    picks.push(cases::draw_case(1, Class::Pair, 0));
    picks.push(cases::draw_case(1, Class::Outside, 0));
    let mut sets = vec![("thesis".to_string(), thesis_dataset(), 1_000)];
    for &rows in if quick {
        &[1_000][..]
    } else {
        &[1_000, 10_000][..]
    } {
        for c in &picks {
            let name = name(c);
            if only.as_ref().is_none_or(|o| *o == name) {
                sets.push((name, scaled(c.clone(), rows), rows));
            }
        }
    }
    if let Some(only) = &only {
        sets.retain(|(name, _, _)| name == only);
    }
    println!(
        "{:<32} {:>6} {:>10} {:>12}  diagnosis",
        "data set", "rows", "best ms", "ms/1000 rows"
    );
    let mut worst = [0.0f64; 2];
    for (name, d, size) in &sets {
        let mut best = f64::INFINITY;
        let mut call = String::new();
        for _ in 0..repeat {
            let t = Instant::now();
            let dg = diagnose(d);
            best = best.min(t.elapsed().as_secs_f64());
            let found: Vec<&str> = dg.effects.iter().map(|e| e.effect).collect();
            call = if dg.unexplained {
                format!("unexplained ({})", dg.residual_pattern.unwrap_or("cells"))
            } else if found.is_empty() {
                "none".into()
            } else {
                found.join("+")
            };
        }
        let k = usize::from(*size >= 10_000);
        worst[k] = worst[k].max(best);
        println!(
            "{name:<32} {:>6} {:>10.1} {:>12.1}  {call}",
            d.pairs.len(),
            best * 1e3,
            best * 1e3 / d.pairs.len() as f64 * 1000.0
        );
    }
    let verdict = |t: f64, target: f64| if t <= target { "met" } else { "NOT met" };
    println!(
        "slowest ~1,000-row set: {:.0} ms (target 200 ms) — {}",
        worst[0] * 1e3,
        verdict(worst[0], 0.2)
    );
    if !quick {
        println!(
            "slowest ~10,000-row set: {:.0} ms (target 1000 ms) — {}",
            worst[1] * 1e3,
            verdict(worst[1], 1.0)
        );
    }
}
