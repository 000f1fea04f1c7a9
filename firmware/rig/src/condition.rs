//! Conditioning: per step, the mean, standard deviation and count of each channel over the
//! step's window. Sums are kept in integer ADC counts, so the result does not depend on the
//! order or the float unit of the chip, and is converted to newtons once, at the end.

use crate::calib::{Calibration, ChannelCal};

/// Mean, standard deviation and count of one channel over a window.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub struct ChannelStats {
    /// Mean force, N.
    pub mean_n: f32,
    /// Sample standard deviation, N (0 with fewer than two samples).
    pub std_n: f32,
    /// Samples averaged.
    pub count: u32,
}

/// Accumulates both channels' counts over one step's window [start, end).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Window {
    start_us: u64,
    end_us: u64,
    sum: [u64; 2],
    sum_sq: [u64; 2],
    count: u32,
}

impl Window {
    /// An empty window over [start, end), µs on the run's clock.
    pub const fn new(start_us: u64, end_us: u64) -> Self {
        Window {
            start_us,
            end_us,
            sum: [0; 2],
            sum_sq: [0; 2],
            count: 0,
        }
    }

    /// Offer a sample taken at `t_us`; it counts only inside the window.
    #[inline]
    pub fn push(&mut self, t_us: u64, counts: [u16; 2]) {
        if t_us < self.start_us || t_us >= self.end_us {
            return;
        }
        for (i, &c) in counts.iter().enumerate() {
            let c = c as u64;
            self.sum[i] += c;
            self.sum_sq[i] += c * c;
        }
        self.count += 1;
    }

    /// Samples accepted so far.
    pub fn count(&self) -> u32 {
        self.count
    }

    /// The window's statistics for both channels, in newtons.
    pub fn stats(&self, cal: &Calibration) -> [ChannelStats; 2] {
        [self.channel(0, &cal.t1), self.channel(1, &cal.t2)]
    }

    fn channel(&self, i: usize, cal: &ChannelCal) -> ChannelStats {
        let n = self.count as u64;
        if n == 0 {
            return ChannelStats {
                mean_n: f32::NAN,
                std_n: f32::NAN,
                count: 0,
            };
        }
        let mean_counts = self.sum[i] as f64 / n as f64;
        let std_counts = if n > 1 {
            // n·Σc² − (Σc)² is exact in integers (no cancellation).
            let s = self.sum[i] as u128;
            let num = (n as u128 * self.sum_sq[i] as u128).saturating_sub(s * s);
            libm::sqrt(num as f64 / (n as f64 * (n - 1) as f64))
        } else {
            0.0
        };
        ChannelStats {
            mean_n: cal.newtons(mean_counts as f32),
            std_n: (std_counts as f32) * cal.n_per_count,
            count: self.count,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::Protocol;

    #[test]
    fn window_bounds_are_half_open() {
        let mut w = Window::new(2_000, 5_000);
        for t in [1_999, 2_000, 4_999, 5_000] {
            w.push(t, [1, 1]);
        }
        assert_eq!(w.count(), 2);
    }

    /// A synthetic signal with a known mean per step, plus a transient right after each change
    /// and a different level in the last second: only the window's level may show.
    #[test]
    fn synthetic_signal_gives_the_known_means_per_window() {
        let p = Protocol::default();
        let cal = Calibration::default();
        for k in 1..=p.levels() {
            let (a, b) = p.window_ms(k);
            let mut w = Window::new(a as u64 * 1000, b as u64 * 1000);
            let level_t1 = 1.5 * k as f32;
            let level_t2 = 4.0 * k as f32;
            let start = p.step_start_ms(k) as u64 * 1000;
            let next = p.step_start_ms(k + 1) as u64 * 1000;
            let mut t = start;
            let mut i = 0u32;
            while t < next {
                let since = t - start;
                // 1 s overshoot transient, a wrong level in the final second, ±3 counts of
                // symmetric triangle dither otherwise.
                let off = if since < 1_000_000 || t >= next - 1_000_000 {
                    5.0
                } else {
                    0.0
                };
                let dither = [-3.0, -1.5, 0.0, 1.5, 3.0, 1.5, 0.0, -1.5][(i % 8) as usize];
                let c1 = cal.t1.counts(level_t1 + off) + dither;
                let c2 = cal.t2.counts(level_t2 - off) - dither;
                w.push(t, [c1.round() as u16, c2.round() as u16]);
                t += 1_000;
                i += 1;
            }
            let [s1, s2] = w.stats(&cal);
            assert_eq!(s1.count, 7_000);
            assert_eq!(s2.count, 7_000);
            // Means to within one count of quantisation (0.015 N).
            assert!((s1.mean_n - level_t1).abs() < 0.015, "step {k}: {s1:?}");
            assert!((s2.mean_n - level_t2).abs() < 0.015, "step {k}: {s2:?}");
            // Dither of ±3 counts has an RMS of ~1.9 counts.
            assert!(s1.std_n > 1.5 * 0.015 && s1.std_n < 2.3 * 0.015, "{s1:?}");
        }
    }

    #[test]
    fn empty_window_is_nan_not_a_panic() {
        let w = Window::new(0, 10);
        let [s1, _] = w.stats(&Calibration::default());
        assert_eq!(s1.count, 0);
        assert!(s1.mean_n.is_nan());
    }
}
