fn main() {
    let seeds: Vec<u64> = std::env::args()
        .skip(1)
        .map(|s| s.parse().unwrap())
        .collect();
    for c in capstan_truth::cases::draw_cases(20_260_522)
        .into_iter()
        .filter(|c| seeds.contains(&c.seed))
    {
        let (ds, _) = c.generate().unwrap();
        let d = capstan_engine::diagnose::diagnose(&ds);
        println!("{}\n  verdict: {}", c.describe(), d.verdict);
        let a = &d.adequacy;
        println!(
            "  lof {:?}\n  beyond {:?}\n  common {:?}",
            a.lack_of_fit.as_ref().map(|l| (l.p, l.systematic_ratio)),
            a.lack_of_fit_beyond_cords
                .as_ref()
                .map(|l| (l.p, l.systematic_ratio)),
            a.common
        );
        for t in &a.directed {
            println!(
                "  dir {} {} F={:.2} p={:.4} r2={:.3} units {}",
                t.structure, t.unit, t.f, t.p, t.partial_r2, t.units
            );
        }
        for p in &a.cords.patterns {
            if p.p_family < 0.2 {
                println!(
                    "  pat {} {} t={:.2} pfam={:.4}",
                    p.covariate, p.summary, p.t, p.p_family
                );
            }
        }
    }
}
