use capstan_truth::cord_cases::{CordCase, Truth};
fn main() {
    let k: u32 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(2);
    for seed in 1..4u64 {
        let mut set = CordCase::draw(Truth::Null, seed).set();
        set.replicates = k;
        let t = std::time::Instant::now();
        let ds = set.generate().unwrap();
        let a =
            capstan_engine::analysis::run(&ds, capstan_engine::analysis::Options { threads: 2 })
                .unwrap();
        let g = &a.gain;
        println!("seed {seed} cords {} rows {} ({:.1} s): ratio {:.3} p {:.4} verdict {:?} failed {} causes {:?} base {:?} ext {:?}", g.cords, ds.pairs.len(), t.elapsed().as_secs_f64(), g.value, g.p, g.verdict, g.failed.len(), a.mechanisms.causes.iter().map(|c| c.name).collect::<Vec<_>>(), a.models[0].loco_rmse_t2_n, a.models.iter().find(|m| m.name=="extended").and_then(|m| m.loco_rmse_t2_n));
        for f in g.folds.iter().take(3) {
            println!("   fold {:?} {:?} {:?}", f.cords, f.causes, f.failed);
        }
    }
}
