//! `cargo bench -p capstan-discover --bench discover`: `capstan discover` (the engine's
//! catalogue selection included) on a 1,000-row and a 10,000-row data set made by the
//! firmware-in-the-loop simulator with the thesis rig's noise (targets: ≤ 2 s and ≤ 20 s on
//! this 2-core machine), and on the bundled thesis data. Median of a few runs.

use capstan_discover::{discover, Options};
use capstan_validation::discover_cases::{self, KINDS};

fn time(data: &capstan_data::Dataset, reps: usize) -> (f64, f64) {
    let mut t: Vec<f64> = (0..reps)
        .map(|_| {
            let t0 = std::time::Instant::now();
            let d = discover(data, &Options::default(), &mut |_, _| {});
            std::hint::black_box(&d);
            t0.elapsed().as_secs_f64()
        })
        .collect();
    t.sort_by(f64::total_cmp);
    (t[t.len() / 2], t[t.len() - 1])
}

fn main() {
    let thesis = capstan_data::thesis_dataset();
    let (m, w) = time(&thesis, 5);
    println!(
        "thesis ({} rows): median {m:.3} s, worst {w:.3} s",
        thesis.pairs.len()
    );
    let kind = KINDS
        .iter()
        .find(|k| k.name == "t2_lowforce")
        .expect("kind");
    for (runs, target) in [(15u32, 2.0), (143, 20.0)] {
        let mut c = discover_cases::draw(99, kind, 0, discover_cases::Variety::Thesis);
        c.case.config.runs = runs;
        c.case.config.threads = 2;
        let (data, _) = c.case.generate().expect("simulate");
        let reps = if runs > 10 { 3 } else { 5 };
        let (m, w) = time(&data, reps);
        println!(
            "{} rows: median {m:.3} s, worst {w:.3} s (target ≤ {target} s){}",
            data.pairs.len(),
            if w <= target { "" } else { "  OVER TARGET" }
        );
    }
}
