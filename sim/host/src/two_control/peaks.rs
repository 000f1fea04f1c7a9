//! The drive's peaks, sampled every 1 ms: the inrush of a spin-up (the motor at standstill
//! draws V/R until its back-emf builds, through the amplifier control's RC filter), and the
//! peaks while the capstan runs, apart. A series sampled every 10 ms catches the inrush
//! wherever its grid falls: the figures the docs once gave (2.03 A / 20 W, then 1.25 A /
//! 11.1 W) were that, for other filters (`docs/README-sim.md`).

use capstan_plant::DriveState;

/// How long after the drive comes on its current counts as the spin-up's inrush, s: ten of the
/// motor's mechanical time constants (~31 ms at 10 V).
pub const INRUSH_S: f64 = 0.3;

/// The drive's peaks over a run.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DrivePeaks {
    /// Highest current, A (a spin-up's inrush).
    pub peak_current_a: f64,
    /// Highest electrical power into the motor, W.
    pub peak_power_w: f64,
    /// Highest current outside the first [`INRUSH_S`] after the drive came on, A.
    pub running_current_a: f64,
    /// Highest power outside those, W.
    pub running_power_w: f64,
    /// Mean power while the drive is on, W.
    pub mean_power_w: f64,
    /// Samples taken, and of them with the drive on.
    pub samples: u64,
    on_samples: u64,
    sum_power_w: f64,
    /// When the drive last came on, s (None: off).
    on_since_s: Option<f64>,
}

impl DrivePeaks {
    /// One sample of the drive at `t_s`.
    pub fn add(&mut self, t_s: f64, d: &DriveState) {
        self.samples += 1;
        self.peak_current_a = self.peak_current_a.max(d.current_a);
        self.peak_power_w = self.peak_power_w.max(d.power_w);
        if d.drive_v <= 0.0 {
            self.on_since_s = None;
            return;
        }
        let since = *self.on_since_s.get_or_insert(t_s);
        self.on_samples += 1;
        self.sum_power_w += d.power_w;
        self.mean_power_w = self.sum_power_w / self.on_samples as f64;
        if t_s - since > INRUSH_S {
            self.running_current_a = self.running_current_a.max(d.current_a);
            self.running_power_w = self.running_power_w.max(d.power_w);
        }
    }
}
