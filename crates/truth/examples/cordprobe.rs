use capstan_engine::evidence::{self};
use capstan_truth::cord_cases::{CordCase, Truth};
use std::time::Instant;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(4);
    let seed: u64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(7);
    if args.get(3).map(|s| s.as_str()) == Some("mu") {
        for ch in [0.0, 0.2, 0.5] {
            let mut c = CordCase::draw(
                if std::env::var("DIAM").is_ok() {
                    Truth::Diameter
                } else {
                    Truth::WrapTurn
                },
                seed,
            );
            c.change = ch;
            if std::env::var("KEEP").is_err() {
                c.scatter.mu_pct = 0.0;
                c.scatter.run_pct = 0.0;
                c.scatter.t2_zero_sd_n = 0.0;
                c.scatter.heating_rel = 0.0;
            }
            println!("change {ch}");
            cordmu(&c);
        }
        return;
    }
    let which: Vec<Truth> = match args.get(3).map(|s| s.as_str()) {
        Some("null") => vec![Truth::Null],
        Some("gain") => vec![Truth::GainNull],
        Some("diam") => vec![Truth::Diameter],
        Some("wrap") => vec![Truth::WrapTurn],
        _ => Truth::ALL.to_vec(),
    };
    for t in which {
        for mut c in CordCase::many(t, seed, n) {
            let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<f64>().ok());
            if let Some(v) = env("T2SD") {
                c.scatter.t2_zero_sd_n = v;
            }
            if let Some(v) = env("HEATREL") {
                c.scatter.heating_rel = v;
            }
            if let Some(v) = env("MUPCT") {
                c.scatter.mu_pct = v;
            }
            let t0 = Instant::now();
            let ds = c.generate().unwrap();
            let gen = t0.elapsed().as_secs_f64();
            let a = evidence::assess(&ds, &evidence::Options::default());
            let sel: Vec<&str> = a.selected.iter().map(|k| k.name()).collect();
            let re: Vec<String> = a
                .adequacy
                .cords
                .random_effects
                .iter()
                .map(|e| format!("{}:{:.3}", &e.parameter[..4.min(e.parameter.len())], e.p))
                .collect();
            let pats: Vec<String> = a
                .adequacy
                .directed
                .iter()
                .map(|d| format!("{}:{:.3}", d.structure, d.p))
                .collect();
            let lof = a.adequacy.lack_of_fit.as_ref().map_or("-".into(), |l| {
                format!("{:.3}/{:.2}", l.p, l.systematic_ratio)
            });
            let lofb = a
                .adequacy
                .lack_of_fit_beyond_cords
                .as_ref()
                .map_or("-".into(), |l| {
                    format!("{:.3}/{:.2}", l.p, l.systematic_ratio)
                });
            let bt: Vec<String> = a
                .evidence
                .iter()
                .filter(|e| e.level == evidence::Level::BetweenCord)
                .map(|e| {
                    format!(
                        "{}:{:.1}:p{:.4}:v{:.5}",
                        &e.effect[..6],
                        e.delta_bic,
                        e.p,
                        e.value
                    )
                })
                .collect();
            let worst: Vec<String> = a
                .adequacy
                .cords
                .patterns
                .iter()
                .filter(|p| p.p_family < 0.2)
                .map(|p| format!("{}/{}:{:.3}", p.covariate, p.summary, p.p_family))
                .collect();
            println!("   worst {:?}", worst);
            let cm0 = capstan_engine::evidence::between::cord_means(&a.design, &a.fit.mu);
            let cm1 =
                capstan_engine::evidence::between::cord_means(&a.design, &a.adequacy.cords.runs_mu);
            let sd = |v: &[f64]| {
                let m = v.iter().sum::<f64>() / v.len() as f64;
                (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt() / m
            };
            println!("   SDMU {:.4} {:.4}", sd(&cm0), sd(&cm1));
            println!(
                "   CM {}",
                cm0.iter()
                    .map(|x| format!("{x:.5}"))
                    .collect::<Vec<_>>()
                    .join(" ")
            );
            println!(
                "   CA {}",
                cm1.iter()
                    .map(|x| format!("{x:.5}"))
                    .collect::<Vec<_>>()
                    .join(" ")
            );
            println!("{:?} ch {:+.3} gen {:.2}s | sel {:?} unexp {} pat {:?} | lof {} -> {} | RE {:?} | dir {:?} | bt {:?} | left {:?}", t, c.change, gen, sel, a.adequacy.unexplained, a.adequacy.pattern, lof, lofb, re, pats, bt, a.adequacy.left_between_cords);
        }
    }
}
#[allow(dead_code)]
pub fn cordmu(c: &CordCase) {
    let ds = c.generate().unwrap();
    let a = evidence::assess(&ds, &evidence::Options::default());
    let cm = capstan_engine::evidence::between::cord_means(&a.design, &a.fit.mu);
    for (g, cd) in a.design.cords.iter().enumerate() {
        println!("  d {} w {} mu {:.4}", cd.diameter_mm, cd.wrap_deg, cm[g]);
    }
}
