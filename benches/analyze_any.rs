//! `capstan analyze` on data sets drawn the way the property test draws them
//! (`tests/diagnose_any_input.rs`: wild tensions, many wraps, optional columns present or not),
//! from 5 to 1,000 rows, and on simulated rig data with many cords (up to 40, where every fit
//! converges and the leave-one-cord-out refits all run): every accepted set analysed end to
//! end as the command does it (the analysis, the closed loop, the report), timed. Target:
//! every accepted set of ≤ 1,000 rows answered in ≤ 2 s on 2 cores.
//!
//! `cargo bench --bench analyze_any` (release); `-- --sets N` draws N sets (default 150),
//! `-- --max-rows N` caps their size (default 1,000), `-- --seed S`, `-- --keep K` writes set
//! K's CSV to `set-K.csv` (to run `capstan analyze` on it alone).

use capstan_data::{check_capstan_data, read_pairs, Dataset};
use capstan_sim::plant::rng::Rng;
use capstan_validation::cases::{draw_case, Class};
use std::time::Instant;

fn arg(args: &[String], name: &str, default: u64) -> u64 {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn pick(rng: &mut Rng, v: &[f64]) -> f64 {
    v[(rng.uniform() * v.len() as f64) as usize % v.len()]
}

fn tension(rng: &mut Rng) -> f64 {
    match (rng.uniform() * 9.0) as u32 {
        0..=5 => -2.0 + 62.0 * rng.uniform(),
        6 => 0.0,
        7 => -1e4 + 2e4 * rng.uniform(),
        _ => pick(rng, &[1e-300, -1e-300, 1e-9, 9_999.999, -9_999.999]),
    }
}

/// One random data set as CSV text, `rows` rows.
fn draw(rng: &mut Rng, rows: usize) -> String {
    let names = ["capstan_diameter_mm", "drive_v", "run", "step", "time_s"];
    let cols: Vec<bool> = (0..5).map(|_| rng.uniform() < 0.5).collect();
    let mut s = String::from("wrap_deg,t1_n,t2_n");
    for (n, on) in names.iter().zip(&cols) {
        if *on {
            s += &format!(",{n}");
        }
    }
    s.push('\n');
    for _ in 0..rows {
        let wrap = if rng.uniform() < 0.8 {
            pick(rng, &[270.0, 360.0, 450.0, 630.0, 720.0])
        } else {
            0.001 + 3600.0 * rng.uniform()
        };
        let t1 = tension(rng);
        let t2 = if rng.uniform() < 0.6 {
            (t1 * (1.0 + 7.0 * rng.uniform())).clamp(-9_999.0, 9_999.0)
        } else {
            tension(rng)
        };
        s += &format!("{wrap},{t1},{t2}");
        let time = if rng.uniform() < 0.75 {
            100.0 * rng.uniform()
        } else {
            -1e9 + 2e9 * rng.uniform()
        };
        let opt = [
            pick(rng, &[12.7, 19.05, 25.4, 0.5, 999.0]),
            pick(rng, &[6.0, 10.0, 12.0, -3.0, 0.0]),
            pick(rng, &[1.0, 2.0, 3.0, 1e6]),
            (14.0 * rng.uniform()).floor(),
            time,
        ];
        for (v, on) in opt.iter().zip(&cols) {
            if *on {
                s += &format!(",{v}");
            }
        }
        s.push('\n');
    }
    s
}

/// Simulated rig data (thesis noise, a planted effect or none) on `wraps` × 2 diameters,
/// `runs` runs per cord: many cords, fits that converge.
fn simulated(seed: u64, k: u64, wraps: usize, runs: u32) -> Dataset {
    let mut case = draw_case(
        seed,
        [Class::Clean, Class::Single, Class::Pair][k as usize % 3],
        k,
    );
    let c = &mut case.config;
    c.wraps_deg = (0..wraps).map(|i| 270.0 + 45.0 * i as f64).collect();
    c.diameters_mm = vec![12.7, 25.4];
    c.drive_vs = vec![10.0];
    c.runs = runs;
    c.threads = 0;
    // Every column kept: the case dropped one its own (smaller) design did not need.
    case.drop_columns.clear();
    case.generate().expect("the case simulates").0
}

/// Analyse `d` end to end as `capstan analyze` does; the wall time and a description.
fn analyse(d: &Dataset, dir: &std::path::Path, what: &str) -> Option<(f64, usize, String)> {
    let t0 = Instant::now();
    let opts = capstan_engine::analysis::Options {
        threads: 2,
        ..Default::default()
    };
    let a = capstan_engine::analysis::run(d, opts).ok()?;
    let cl = capstan_validation::closed_loop::run(&a, 2).ok();
    let html = capstan_report::report_html(
        &a,
        cl.as_ref().map(|c| c.curves.as_slice()),
        "",
        &capstan_report::Context::library(),
    )
    .expect("the report renders")
    .0;
    let mut csv = Vec::new();
    capstan_report::write_predictions_csv(&mut csv, d, &a).unwrap();
    let _ = std::fs::create_dir_all(dir);
    std::fs::write(dir.join("report.html"), html).unwrap();
    let s = t0.elapsed().as_secs_f64();
    let notes = if a.fit_notes.is_empty() {
        String::new()
    } else {
        format!("; {}", a.fit_notes.join("; "))
    };
    let what = format!(
        "{what}: {} rows, {} cords, {} runs; evidence {:.2} s, fits {:.2} s, loco {:.2} s{notes}",
        d.pairs.len(),
        a.obs.groups.len(),
        a.obs.runs.len(),
        a.elapsed.evidence_s,
        a.elapsed.fits_s,
        a.elapsed.loco_s,
    );
    Some((s, d.pairs.len(), what))
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let sets = arg(&args, "--sets", 150);
    let max_rows = arg(&args, "--max-rows", 1_000).max(5);
    let seed = arg(&args, "--seed", 23);
    let mut rng = Rng::new(seed);
    let dir = std::env::temp_dir().join(format!("capstan-bench-any-{}", std::process::id()));
    let mut times: Vec<(f64, usize, String)> = Vec::new();
    let (mut refused, mut too_few) = (0, 0);
    // Simulated rig data: 8 to 40 cords, 240 to 960 rows.
    for (k, (wraps, runs)) in [(4, 3), (6, 2), (8, 3), (10, 2), (12, 2), (20, 1)]
        .into_iter()
        .enumerate()
    {
        if 24 * wraps * runs as usize > max_rows as usize {
            continue;
        }
        let d = simulated(seed, k as u64, wraps, runs);
        if let Some(t) = analyse(&d, &dir, &format!("simulated {k}")) {
            times.push(t);
        }
    }
    for k in 0..sets {
        // Half the sets small (as the issue drew them), half up to `max_rows`.
        let rows = if k % 2 == 0 {
            5 + (rng.uniform() * 56.0) as usize
        } else {
            5 + (rng.uniform() * (max_rows - 4) as f64) as usize
        }
        .min(max_rows as usize);
        let text = draw(&mut rng, rows);
        let Ok(d) = read_pairs(text.as_bytes(), &format!("set-{k}.csv")) else {
            refused += 1;
            continue;
        };
        if check_capstan_data(&d).is_err() {
            refused += 1;
            continue;
        }
        match analyse(&d, &dir, &format!("set {k}")) {
            Some(t) => {
                // `--keep K`: set K's CSV to the current directory (to profile it alone).
                if arg(&args, "--keep", u64::MAX) == k {
                    std::fs::write(format!("set-{k}.csv"), &text).unwrap();
                }
                times.push(t)
            }
            None => too_few += 1,
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    times.sort_by(|a, b| b.0.total_cmp(&a.0));
    let n = times.len();
    println!(
        "{n} sets analysed ({refused} refused by the reader, {too_few} too few rows), seed {seed}"
    );
    if n == 0 {
        return;
    }
    let median = times[n / 2].0;
    println!(
        "wall time: slowest {:.2} s, median {median:.3} s; over 2 s: {}",
        times[0].0,
        times.iter().filter(|t| t.0 > 2.0).count()
    );
    for (s, _, what) in times.iter().take(5) {
        println!("  {s:.2} s  {what}");
    }
}
