//! Deterministic random numbers, `no_std`: xoshiro256++ seeded through SplitMix64, and normal
//! deviates by Marsaglia's polar method (exact Gaussian, two per logarithm).
//!
//! Everything is integer arithmetic plus `libm`'s software `log`/`sqrt`, so a seed gives the same
//! bits on the host and on a Cortex-M (soft float) alike.

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

/// xoshiro256++ (Blackman & Vigna): fast, 256 bits of state, passes BigCrush.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Rng {
    s: [u64; 4],
    spare: Option<u64>,
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
        Rng { s, spare: None }
    }

    /// A generator with an explicit state (for reference vectors).
    pub const fn from_state(s: [u64; 4]) -> Self {
        Rng { s, spare: None }
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

    /// Uniform in (-1, 1).
    #[inline]
    fn symmetric(&mut self) -> f64 {
        // 53 bits signed: (-2^52 .. 2^52) / 2^52, zero included, ±1 excluded.
        ((self.next_u64() >> 11) as i64 - (1i64 << 52)) as f64 * (1.0 / (1u64 << 52) as f64)
    }

    /// A standard normal deviate (mean 0, sd 1).
    #[inline]
    pub fn normal(&mut self) -> f64 {
        if let Some(bits) = self.spare.take() {
            return f64::from_bits(bits);
        }
        loop {
            let u = self.symmetric();
            let v = self.symmetric();
            let s = u * u + v * v;
            if s < 1.0 && s > 0.0 {
                let f = libm::sqrt(-2.0 * libm::log(s) / s);
                self.spare = Some((v * f).to_bits());
                return u * f;
            }
        }
    }
}

#[cfg(test)]
mod tests {
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
    fn derived_seeds_depend_on_every_part() {
        let a = derive_seed(1, &[12, 270]);
        assert_eq!(a, derive_seed(1, &[12, 270]));
        assert_ne!(a, derive_seed(1, &[270, 12]));
        assert_ne!(a, derive_seed(2, &[12, 270]));
    }
}
