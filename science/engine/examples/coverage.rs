//! `capstan predict`'s 95 % prediction interval on new cords: each cord of the thesis data (or
//! of the pairs CSV given) left out, the rest analysed, the cord's measured T2 predicted at its
//! measured T1. Prints the share of rows inside the interval over all rows, per T2 band and per
//! cord, with the interval's mean width:
//! `cargo run --release -p capstan-engine --example coverage [-- PAIRS.csv]`.
use capstan_engine::analysis::{coverage::coverage, Options};

fn main() {
    let ds = match std::env::args().nth(1) {
        Some(p) => capstan_data::load_pairs(std::path::Path::new(&p)).expect("a pairs CSV"),
        None => capstan_data::thesis_dataset(),
    };
    let t = std::time::Instant::now();
    let c = coverage(&ds, Options::default());
    println!(
        "{}: each cord predicted by the analysis of the others ({:.1} s)",
        ds.source,
        t.elapsed().as_secs_f64()
    );
    for l in c.lines() {
        println!("  {l}");
    }
}
