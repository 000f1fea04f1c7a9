//! What the rig can do, as `capstan predict` checks a design against it: the firmware's
//! over-force limit, the force sensors' range and the drive's voltage, taken from the
//! firmware's own defaults (its safety limits and calibration), never typed twice.

use capstan_engine::analysis::prediction::Span;

/// The rig's limits for a prediction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigLimits {
    /// Above this force on either channel the firmware stops the run (`over_force`), N.
    pub over_force_n: f64,
    /// The largest force the sensors read before the rail check, N (the lower of the two
    /// channels under the default calibration).
    pub sensor_top_n: f64,
    /// The highest drive voltage: the PWM's full control voltage times the amplifier's gain, V.
    pub drive_max_v: f64,
}

/// An `f32` constant of the firmware as the decimal it was written as (3.3 V, not
/// 3.2999999523 V): its shortest round-trip text, read as an `f64`.
fn decimal(x: f32) -> f64 {
    x.to_string().parse().unwrap_or(f64::from(x))
}

impl RigLimits {
    /// The limits of the rig as the firmware ships (default safety limits and calibration).
    pub fn firmware_defaults() -> RigLimits {
        let safety = capstan_rig::safety::SafetyLimits::default();
        let cal = capstan_rig::Calibration::default();
        let top = |ch: &capstan_rig::ChannelCal| {
            (f64::from(safety.rail_high_counts) - decimal(ch.zero_counts)) * decimal(ch.n_per_count)
        };
        RigLimits {
            over_force_n: decimal(safety.over_force_n),
            sensor_top_n: top(&cal.t1).min(top(&cal.t2)),
            drive_max_v: decimal(cal.amp.full_scale_v) * decimal(cal.amp.amp_gain),
        }
    }

    /// `--drive-v` outside the drive's range is refused: the rig cannot run it.
    pub fn check_drive(&self, drive_v: f64) -> anyhow::Result<()> {
        self.check_drive_for(
            drive_v,
            "the model cannot speak for a drive the rig cannot run",
        )
    }

    /// `--drive-v` outside the drive's range (0 V to its full voltage; a negative, infinite
    /// or NaN voltage too) is refused, with what it would have done (`consequence`, after
    /// the range and where it comes from): what `predict`, `condition` and `log` say.
    pub fn check_drive_for(&self, drive_v: f64, consequence: &str) -> anyhow::Result<()> {
        if !(0.0..=self.drive_max_v + 1e-9).contains(&drive_v) {
            anyhow::bail!(
                "--drive-v {}: the rig's drive gives 0 to {} V (the firmware's full control \
                 voltage times the amplifier's gain); {consequence}",
                capstan_data::ranges::shown(drive_v),
                capstan_data::ranges::shown(self.drive_max_v)
            );
        }
        Ok(())
    }
}

/// A checked `--drive-v` as a file records it: −0 V is 0 V (a cell "-0" reads as a sign
/// error; the firmware commands the same 0 V).
pub fn recorded_drive(v: Option<f64>) -> Option<f64> {
    v.map(|v| if v == 0.0 { 0.0 } else { v })
}

/// A flag on one prediction, as JSON names it.
pub const OVER_FORCE: &str = "over_force_limit";
/// Beyond the sensors' range.
pub const SENSOR_RANGE: &str = "sensor_range";
/// T1 outside the fitted T1.
pub const T1_OUTSIDE: &str = "t1_outside_fitted";
/// The intervals are not identified.
pub const NOT_IDENTIFIED: &str = "not_identified";

/// The flags of one prediction whose largest tension is `top_n` and whose T1 is `t1_n`.
pub fn flags(lim: &RigLimits, fitted_t1: Span, t1_n: f64, top_n: f64) -> Vec<&'static str> {
    let mut f = Vec::new();
    if top_n > lim.over_force_n {
        f.push(OVER_FORCE);
    }
    if top_n > lim.sensor_top_n {
        f.push(SENSOR_RANGE);
    }
    if !fitted_t1.contains(t1_n) {
        f.push(T1_OUTSIDE);
    }
    f
}

/// One warning per rig limit the predictions pass (`largest`: the largest tension among the
/// predictions and what it is, "T2" or "T1").
pub fn rig_warnings(lim: &RigLimits, largest: (f64, &str)) -> Vec<String> {
    let (v, what) = largest;
    let mut w = Vec::new();
    if v > lim.over_force_n {
        w.push(format!(
            "{what} up to {v:.1} N is beyond the firmware's over-force limit of {} N: the rig \
             stops such a run (fault over_force)",
            lim.over_force_n
        ));
    }
    if v > lim.sensor_top_n {
        w.push(format!(
            "{what} up to {v:.1} N is beyond the force sensors' range ({:.1} N under the default \
             calibration): the rig cannot measure it",
            lim.sensor_top_n
        ));
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The thesis rig: 45 N over-force, (3900 − 400) counts × 0.015 N = 52.5 N of sensor,
    /// 3.3 V × 4 = 13.2 V of drive.
    #[test]
    fn the_firmware_defaults_are_the_thesis_rig() {
        assert_eq!(recorded_drive(Some(-0.0)).unwrap().to_string(), "0");
        assert_eq!(recorded_drive(Some(13.2)), Some(13.2));
        let l = RigLimits::firmware_defaults();
        assert_eq!(l.over_force_n, 45.0);
        assert!((l.sensor_top_n - 52.5).abs() < 1e-9, "{}", l.sensor_top_n);
        assert!((l.drive_max_v - 13.2).abs() < 1e-9, "{}", l.drive_max_v);
        assert!(l.check_drive(13.2).is_ok() && l.check_drive(13.3).is_err());
        // Below 0 V, and a voltage that is not a number, are outside the drive's range too.
        assert!(l.check_drive(0.0).is_ok() && l.check_drive(-0.01).is_err());
        for v in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let e = l.check_drive_for(v, "so").unwrap_err().to_string();
            assert!(e.contains("the rig's drive gives 0 to 13.2 V"), "{e}");
        }
        let span = Span {
            min: 0.1,
            max: 22.0,
        };
        assert_eq!(flags(&l, span, 5.0, 30.0), Vec::<&str>::new());
        assert_eq!(flags(&l, span, 5.0, 50.0), vec![OVER_FORCE]);
        assert_eq!(
            flags(&l, span, 30.0, 103.6),
            vec![OVER_FORCE, SENSOR_RANGE, T1_OUTSIDE]
        );
        assert_eq!(rig_warnings(&l, (103.6, "T2")).len(), 2);
    }
}
