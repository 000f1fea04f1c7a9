//! Deterministic random numbers, `no_std`: xoshiro256++ seeded through SplitMix64, and normal
//! deviates by the ziggurat method (Marsaglia & Tsang 2000, 256 layers; exact Gaussian, one
//! 64-bit draw and a comparison in ~99 % of cases).
//!
//! Everything is integer and IEEE arithmetic plus `libm`'s software `exp`/`log`/`sqrt`, so a
//! seed gives the same bits on the host and on a Cortex-M (soft float) alike.

/// SplitMix64: turns any 64-bit value into a well-mixed one. Used to derive seeds.
pub fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A seed derived from a parent seed and a list of values (e.g. a cord's diameter, wrap and
/// voltage as bits): the same inputs always give the same seed, whatever else is simulated.
pub fn derive_seed(parent: u64, parts: &[u64]) -> u64 {
    let mut s = splitmix64(parent ^ 0x6361_7073_7461_6e00);
    for &p in parts {
        s = splitmix64(s ^ splitmix64(p));
    }
    s
}

/// Ziggurat layers.
const LAYERS: usize = 256;
/// Right edge of the base layer's rectangle (start of the tail), for 256 layers.
const ZIG_R: f64 = 3.654_152_885_361_009;
/// Area of every layer (rectangle + wedge; the base: rectangle + tail), for 256 layers.
const ZIG_V: f64 = 4.928_673_233_99e-3;

/// The ziggurat's layer edges: x[0] = V/f(R) (the base layer's equivalent width), x[1] = R,
/// ..., x[256] = 0, with f(x) = exp(−x²/2).
#[derive(Clone, Debug, PartialEq)]
struct Ziggurat {
    x: [f64; LAYERS + 1],
    /// x[i+1]/x[i]: below it a draw is inside layer i's rectangle.
    ratio: [f64; LAYERS],
}

impl Ziggurat {
    fn new() -> Self {
        let mut x = [0.0; LAYERS + 1];
        let mut f = libm::exp(-0.5 * ZIG_R * ZIG_R);
        x[0] = ZIG_V / f;
        x[1] = ZIG_R;
        for i in 2..LAYERS {
            x[i] = libm::sqrt(-2.0 * libm::log(ZIG_V / x[i - 1] + f));
            f = libm::exp(-0.5 * x[i] * x[i]);
        }
        x[LAYERS] = 0.0;
        let mut ratio = [0.0; LAYERS];
        for i in 0..LAYERS {
            ratio[i] = x[i + 1] / x[i];
        }
        Ziggurat { x, ratio }
    }
}

/// xoshiro256++ (Blackman & Vigna): fast, 256 bits of state, passes BigCrush.
#[derive(Clone, Debug, PartialEq)]
pub struct Rng {
    s: [u64; 4],
    zig: Option<Ziggurat>,
}

impl Rng {
    /// A generator whose state is filled from `seed` by SplitMix64 (never all zero).
    pub fn new(seed: u64) -> Self {
        let mut x = seed;
        let mut s = [0u64; 4];
        for w in s.iter_mut() {
            x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
            *w = splitmix64(x.wrapping_sub(0x9E37_79B9_7F4A_7C15));
        }
        if s == [0; 4] {
            s[0] = 1;
        }
        Rng { s, zig: None }
    }

    /// A generator with an explicit state (for reference vectors).
    pub const fn from_state(s: [u64; 4]) -> Self {
        Rng { s, zig: None }
    }

    /// The next 64 random bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        let s = &mut self.s;
        let result = s[0].wrapping_add(s[3]).rotate_left(23).wrapping_add(s[0]);
        let t = s[1] << 17;
        s[2] ^= s[0];
        s[3] ^= s[1];
        s[1] ^= s[2];
        s[0] ^= s[3];
        s[2] ^= t;
        s[3] = s[3].rotate_left(45);
        result
    }

    /// Uniform in [0, 1) with 53 random bits.
    #[inline]
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// A standard normal deviate (mean 0, sd 1).
    #[inline]
    pub fn normal(&mut self) -> f64 {
        if self.zig.is_none() {
            self.zig = Some(Ziggurat::new());
        }
        loop {
            let bits = self.next_u64();
            let i = (bits & 0xff) as usize;
            // 53 signed bits, independent of the layer bits: u in (−1, 1).
            let u = ((bits >> 11) as i64 - (1i64 << 52)) as f64 * (1.0 / (1u64 << 52) as f64);
            let zig = self.zig.as_ref().unwrap();
            if u.abs() < zig.ratio[i] {
                return u * zig.x[i];
            }
            if i == 0 {
                return self.tail(u < 0.0);
            }
            // The wedge between layer i's rectangle and the curve.
            let x = u * zig.x[i];
            let (xi, xj) = (zig.x[i], zig.x[i + 1]);
            let f0 = libm::exp(-0.5 * (xi * xi - x * x));
            let f1 = libm::exp(-0.5 * (xj * xj - x * x));
            if f1 + self.uniform() * (f0 - f1) < 1.0 {
                return x;
            }
        }
    }

    /// A draw from the normal's tail beyond R (Marsaglia 1964).
    fn tail(&mut self, negative: bool) -> f64 {
        loop {
            let a = -libm::log(1.0 - self.uniform()) / ZIG_R;
            let b = -libm::log(1.0 - self.uniform());
            if b + b > a * a {
                let x = ZIG_R + a;
                return if negative { -x } else { x };
            }
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;

    #[test]
    fn xoshiro256pp_reference_output() {
        // State {1, 2, 3, 4}: the first output is rotl(1 + 4, 23) + 1.
        let mut r = Rng::from_state([1, 2, 3, 4]);
        assert_eq!(r.next_u64(), 41_943_041);
    }

    #[test]
    fn normals_have_unit_variance_and_are_reproducible() {
        let mut a = Rng::new(7);
        let mut b = Rng::new(7);
        let n = 200_000;
        let (mut sum, mut sq, mut beyond3) = (0.0, 0.0, 0);
        for _ in 0..n {
            let x = a.normal();
            assert_eq!(x.to_bits(), b.normal().to_bits());
            sum += x;
            sq += x * x;
            if x.abs() > 3.0 {
                beyond3 += 1;
            }
        }
        let mean = sum / n as f64;
        let var = sq / n as f64 - mean * mean;
        assert!(mean.abs() < 0.01, "{mean}");
        assert!((var - 1.0).abs() < 0.01, "{var}");
        // P(|x| > 3) = 0.27 %: 540 expected.
        assert!((400..700).contains(&beyond3), "{beyond3}");
        assert_ne!(Rng::new(8).next_u64(), Rng::new(7).next_u64());
    }

    #[test]
    fn the_ziggurat_closes_and_matches_the_normal_distribution() {
        let z = Ziggurat::new();
        // The recursion must land on the top of the curve: one more layer would reach x = 0.
        let top = ZIG_V / z.x[LAYERS - 1] + libm::exp(-0.5 * z.x[LAYERS - 1] * z.x[LAYERS - 1]);
        assert!((top - 1.0).abs() < 1e-9, "{top}");
        // Kolmogorov-Smirnov against the normal CDF on 100 000 draws.
        let mut r = Rng::new(11);
        let mut v: std::vec::Vec<f64> = (0..100_000).map(|_| r.normal()).collect();
        v.sort_by(|a, b| a.partial_cmp(b).unwrap());
        let n = v.len() as f64;
        let cdf = |x: f64| 0.5 * libm::erfc(-x / core::f64::consts::SQRT_2);
        let d = v
            .iter()
            .enumerate()
            .map(|(k, &x)| {
                let c = cdf(x);
                (c - k as f64 / n).abs().max((c - (k + 1) as f64 / n).abs())
            })
            .fold(0.0, f64::max);
        // 1 % critical value: 1.63/sqrt(n).
        assert!(d < 1.63 / n.sqrt(), "KS distance {d}");
        // Tails beyond R = 3.65 do occur (P = 2.6e-4 per draw).
        assert!(
            v[0] < -3.65 && v[v.len() - 1] > 3.65,
            "{} {}",
            v[0],
            v[v.len() - 1]
        );
    }

    #[test]
    fn derived_seeds_depend_on_every_part() {
        let a = derive_seed(1, &[12, 270]);
        assert_eq!(a, derive_seed(1, &[12, 270]));
        assert_ne!(a, derive_seed(1, &[270, 12]));
        assert_ne!(a, derive_seed(2, &[12, 270]));
    }
}
