use host_sim::plant::rng::{derive_seed, Rng};
fn main() {
    let ds = [12.7f64, 25.4];
    let ws = [270.0f64, 360.0, 450.0, 630.0, 720.0];
    let mut within = 0.0;
    let mut across = 0.0;
    let (mut nw, mut na) = (0.0, 0.0);
    let mut big = 0;
    let n = 20000;
    for s in 0..n {
        let seed = derive_seed(11, &[0, s as u64]);
        let mut z = vec![];
        for &d in &ds {
            for &w in &ws {
                let cs = derive_seed(seed, &[d.to_bits(), 10f64.to_bits(), w.to_bits()]);
                z.push(Rng::new(cs).normal());
            }
        }
        for i in 0..10 {
            for j in 0..10 {
                if i < j {
                    let p = z[i] * z[j];
                    if (i < 5) == (j < 5) {
                        within += p;
                        nw += 1.0
                    } else {
                        across += p;
                        na += 1.0
                    }
                }
            }
        }
        let a: f64 = z[..5].iter().sum::<f64>() / 5.0;
        let b: f64 = z[5..].iter().sum::<f64>() / 5.0;
        let m = (a + b) / 2.0;
        let ss: f64 = z
            .iter()
            .enumerate()
            .map(|(i, x)| (x - if i < 5 { a } else { b }).powi(2))
            .sum::<f64>();
        let t = (a - b) / ((ss / 8.0) * (0.4)).sqrt();
        let _ = m;
        if t.abs() > 2.896 {
            big += 1;
        }
    }
    println!(
        "within {:.4} across {:.4} rate@0.02 {:.4}",
        within / nw,
        across / na,
        big as f64 / n as f64
    );
}
