//! The physical ranges: one table for every numeric column of a pairs CSV and every numeric
//! option of the commands that write data (`log`, `simulate`, `rig`) or read it. A value
//! outside its range is refused with the range, by the reader (with its file, line and column)
//! and on the command line alike, so that what one command writes the others read, and no
//! conversion to an integer (times in µs, delays in ms, counts) can wrap around.

use std::fmt::Write as _;

/// The allowed values of one quantity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Range {
    /// What it is, in words.
    pub quantity: &'static str,
    /// Unit (empty: a count or an index).
    pub unit: &'static str,
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
    /// The value must be above `min` (not equal to it).
    pub above_min: bool,
    /// Why the bound is where it is.
    pub why: &'static str,
}

impl Range {
    /// `v` if it is finite and inside the range; otherwise why not (e.g. "must be greater than
    /// 0 and at most 3600 deg (ten turns)").
    pub fn check(&self, v: f64) -> Result<f64, RangeError> {
        if v.is_nan() {
            return Err(RangeError::NotANumber);
        }
        let low = if self.above_min {
            v <= self.min
        } else {
            v < self.min
        };
        if !v.is_finite() || low || v > self.max {
            return Err(RangeError::Outside(*self));
        }
        Ok(v)
    }

    /// The range in words: "within ±10000 N (...)", "greater than 0 and at most 3600 deg (...)",
    /// "from 0 to 1000000 s (...)".
    pub fn describe(&self) -> String {
        let u = if self.unit.is_empty() {
            String::new()
        } else {
            format!(" {}", self.unit)
        };
        let mut s = if self.min == -self.max && !self.above_min {
            format!("within ±{}{u}", num(self.max))
        } else if self.above_min {
            format!(
                "greater than {} and at most {}{u}",
                num(self.min),
                num(self.max)
            )
        } else {
            format!("from {} to {}{u}", num(self.min), num(self.max))
        };
        if !self.why.is_empty() {
            let _ = write!(s, " ({})", self.why);
        }
        s
    }

    /// A command-line value: `flag value: must be ...` when out of range.
    pub fn option(&self, flag: &str, v: f64) -> Result<f64, OptionError> {
        self.check(v).map_err(|reason| OptionError {
            flag: flag.to_string(),
            value: v,
            reason,
        })
    }
}

/// Why a value is not inside its [`Range`].
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum RangeError {
    /// The value is NaN.
    #[error("not a number")]
    NotANumber,
    /// The value is infinite or outside the range (which the message states).
    #[error("must be {}", .0.describe())]
    Outside(Range),
}

/// A command-line value outside its range: `flag value: must be ...`.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{flag} {}: {reason}", shown(*.value))]
pub struct OptionError {
    /// The option as typed (`--wrap-deg`).
    pub flag: String,
    /// The value given, in the option's unit.
    pub value: f64,
    /// Why it is refused.
    pub reason: RangeError,
}

/// A value a user gave, as a message repeats it: whole numbers below 1e16 in full, others as
/// Rust prints them, except that very large or very small magnitudes read in scientific
/// notation with six significant digits at most (1e308 is not three hundred digits, nor
/// 9.999999999999999e299).
pub fn shown(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e16 {
        // A whole number as typed (4294967295, 1000000000), never in exponent form.
        format!("{v:.0}")
    } else if v.is_finite() && v != 0.0 && !(1e-4..1e7).contains(&v.abs()) {
        let s = format!("{v:.5e}");
        let (mantissa, exp) = s.split_once('e').unwrap_or((&s, "0"));
        let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
        format!("{mantissa}e{exp}")
    } else {
        format!("{v}")
    }
}

#[cfg(test)]
mod shown_tests {
    use super::shown;

    #[test]
    fn huge_and_tiny_values_read_short() {
        assert_eq!(shown(1e308), "1e308");
        assert_eq!(shown(9.999999999999999e299), "1e300");
        assert_eq!(shown(-2.5e-7), "-2.5e-7");
        assert_eq!(shown(12.25), "12.25");
        assert_eq!(shown(4294967295.0), "4294967295");
        assert_eq!(shown(-0.0), "-0");
        assert_eq!(shown(f64::INFINITY), "inf");
    }
}

/// A bound as written: integers plainly, large or small ones in scientific notation.
fn num(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e7 {
        format!("{v:.0}")
    } else {
        format!("{v:e}")
    }
}

/// A force reading, N: ten kilonewtons is far beyond any bench capstan rig (the thesis rig's
/// sensors end at about 55 N) and keeps every sum of squares finite. Zero and negative
/// readings are data: a sensor with a zero offset reads a slack cord below zero.
pub const TENSION_N: Range = Range {
    quantity: "tension",
    unit: "N",
    min: -1.0e4,
    max: 1.0e4,
    above_min: false,
    why: "beyond that no force sensor of a capstan rig reads",
};
/// Wrap angle, deg (ten turns).
pub const WRAP_DEG: Range = Range {
    quantity: "wrap angle",
    unit: "deg",
    min: 0.0,
    max: 3600.0,
    above_min: true,
    why: "ten turns",
};
/// Capstan diameter, mm.
pub const DIAMETER_MM: Range = Range {
    quantity: "capstan diameter",
    unit: "mm",
    min: 0.0,
    max: 1000.0,
    above_min: true,
    why: "a bench capstan",
};
/// Drive-motor voltage, V.
pub const DRIVE_V: Range = Range {
    quantity: "drive voltage",
    unit: "V",
    min: -1000.0,
    max: 1000.0,
    above_min: false,
    why: "a bench motor drive",
};
/// Run number.
pub const RUN: Range = Range {
    quantity: "run number",
    unit: "",
    min: -1.0e9,
    max: 1.0e9,
    above_min: false,
    why: "",
};
/// Step number.
pub const STEP: Range = Range {
    quantity: "step number",
    unit: "",
    min: -1.0e9,
    max: 1.0e9,
    above_min: false,
    why: "",
};
/// Time since the trigger, s (beyond Unix-epoch timestamps for centuries).
pub const TIME_S: Range = Range {
    quantity: "time",
    unit: "s",
    min: -1.0e10,
    max: 1.0e10,
    above_min: false,
    why: "",
};
/// Any other numeric column.
pub const EXTRA: Range = Range {
    quantity: "value",
    unit: "",
    min: -1.0e300,
    max: 1.0e300,
    above_min: false,
    why: "",
};
/// `capstan log --duration`, s (a year).
pub const LOG_DURATION_S: Range = Range {
    quantity: "logging time",
    unit: "s",
    min: 0.0,
    max: 3.2e7,
    above_min: true,
    why: "a year",
};
/// `capstan simulate --fault NAME@SECONDS`: when after the trigger, s (a run of the thesis
/// protocol lasts 131.5 s; a million seconds is beyond any protocol's run).
pub const FAULT_AT_S: Range = Range {
    quantity: "fault time",
    unit: "s",
    min: 0.0,
    max: 1.0e6,
    above_min: false,
    why: "after the trigger",
};
/// `capstan simulate --two-control --delays-ms`: wait before a channel's trigger, ms (an hour).
pub const DELAY_MS: Range = Range {
    quantity: "delay",
    unit: "ms",
    min: 0.0,
    max: 3.6e6,
    above_min: false,
    why: "an hour",
};
/// `capstan simulate --runs`: repeat runs per cord.
pub const RUNS_PER_CORD: Range = Range {
    quantity: "runs per cord",
    unit: "",
    min: 1.0,
    max: 1.0e6,
    above_min: false,
    why: "",
};
/// Protocol times of `simulate` (`--dwell-ms`, `--window-after-ms`, `--window-before-ms`),
/// ms (an hour per step).
pub const PROTOCOL_MS: Range = Range {
    quantity: "protocol time",
    unit: "ms",
    min: 0.0,
    max: 3.6e6,
    above_min: false,
    why: "an hour",
};
/// Worker threads.
pub const THREADS: Range = Range {
    quantity: "threads",
    unit: "",
    min: 1.0,
    max: 1024.0,
    above_min: false,
    why: "",
};

/// Every range, by the column or option it bounds (for the documentation and its test).
pub const TABLE: [(&str, Range); 14] = [
    ("t1_n, t2_n", TENSION_N),
    ("wrap_deg, --wrap-deg, --wraps", WRAP_DEG),
    (
        "capstan_diameter_mm, --diameter-mm, --diameters",
        DIAMETER_MM,
    ),
    ("drive_v, --drive-v", DRIVE_V),
    ("run", RUN),
    ("step", STEP),
    ("time_s", TIME_S),
    ("any other numeric column", EXTRA),
    ("log --duration", LOG_DURATION_S),
    ("simulate --fault NAME@SECONDS", FAULT_AT_S),
    ("simulate --delays-ms", DELAY_MS),
    ("simulate --runs", RUNS_PER_CORD),
    (
        "simulate --dwell-ms, --window-after-ms, --window-before-ms",
        PROTOCOL_MS,
    ),
    ("--threads", THREADS),
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_say_what_they_allow() {
        assert_eq!(
            WRAP_DEG.check(1e9).unwrap_err().to_string(),
            "must be greater than 0 and at most 3600 deg (ten turns)"
        );
        assert_eq!(
            WRAP_DEG.check(0.0).unwrap_err(),
            WRAP_DEG.check(-1.0).unwrap_err()
        );
        assert_eq!(WRAP_DEG.check(3600.0), Ok(3600.0));
        assert!(TENSION_N.check(-1e4).is_ok() && TENSION_N.check(1e154).is_err());
        assert_eq!(
            TENSION_N.check(f64::NAN).unwrap_err().to_string(),
            "not a number"
        );
        assert_eq!(
            TIME_S.check(f64::INFINITY).unwrap_err().to_string(),
            "must be within ±1e10 s"
        );
        assert_eq!(
            FAULT_AT_S.describe(),
            "from 0 to 1000000 s (after the trigger)"
        );
        // Every bound converts to the integers the commands use without wrapping: µs in u64,
        // ms in u32.
        assert!(FAULT_AT_S.max * 1e6 < u64::MAX as f64 / 2.0);
        assert!(DELAY_MS.max * 1e3 < u32::MAX as f64);
        assert!(PROTOCOL_MS.max * 1e3 < u32::MAX as f64);
        for (what, r) in TABLE {
            assert!(r.min < r.max && r.max.is_finite(), "{what}");
        }
    }
}
