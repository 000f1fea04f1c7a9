//! An effect at a size ([`Effect`]), the catalogue's names, and `NAME=VALUE` parsing. What
//! each effect is lives in its entry ([`crate::catalogue`]).

use crate::{EffectKind, Model};
use core::fmt;
use core::str::FromStr;

impl EffectKind {
    /// The catalogue name.
    pub fn name(self) -> &'static str {
        self.entry().name
    }

    /// The catalogue parameter name (`None` for `none`).
    pub fn parameter(self) -> Option<&'static str> {
        self.entry().parameter
    }

    /// The parameter value at which the effect vanishes.
    pub fn neutral_value(self) -> f64 {
        self.entry().neutral
    }

    /// The data column the effect needs to be testable (beyond wrap, T1, T2), if any.
    pub fn required_column(self) -> Option<&'static str> {
        self.entry().column
    }

    /// Look an effect up by its catalogue name.
    pub fn from_name(name: &str) -> Option<EffectKind> {
        EffectKind::ALL.into_iter().find(|k| k.name() == name)
    }
}

impl fmt::Display for EffectKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// An effect at a given parameter value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Effect {
    /// Which effect.
    pub kind: EffectKind,
    /// Its parameter (ignored for `none`).
    pub value: f64,
}

impl Effect {
    /// No departure from Euler-Eytelwein.
    pub const NONE: Effect = Effect {
        kind: EffectKind::None,
        value: 0.0,
    };

    /// Switch the effect on in `model` (overwrites that one parameter).
    pub fn apply(&self, model: &mut Model) {
        (self.kind.entry().apply)(model, self.value);
    }

    /// The value of this effect's parameter in `model`.
    pub fn read(kind: EffectKind, model: &Model) -> f64 {
        (kind.entry().read)(model)
    }
}

/// Why `NAME=VALUE` is not an effect.
#[derive(Clone, Debug, PartialEq)]
pub enum ParseEffectError {
    /// The name is not in the catalogue.
    UnknownEffect,
    /// `none` takes no value; every other effect needs one.
    MissingValue,
    /// The value is not a finite number.
    BadValue,
    /// `none` was given a value.
    NoneTakesNoValue,
    /// The value is outside what a real rig can hold (the entry's `physical` range).
    OutOfRange {
        /// The effect.
        kind: EffectKind,
        /// Lowest value.
        lo: f64,
        /// Highest value.
        hi: f64,
    },
}

impl fmt::Display for ParseEffectError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ParseEffectError::UnknownEffect => {
                f.write_str("unknown effect (known: ")?;
                for (i, k) in EffectKind::ALL.iter().enumerate() {
                    if i > 0 {
                        f.write_str(", ")?;
                    }
                    f.write_str(k.name())?;
                }
                f.write_str(")")
            }
            ParseEffectError::MissingValue => f.write_str("expected NAME=VALUE"),
            ParseEffectError::BadValue => f.write_str("the value is not a finite number"),
            ParseEffectError::NoneTakesNoValue => {
                f.write_str("`none` takes no value (it is Euler-Eytelwein with no effect)")
            }
            ParseEffectError::OutOfRange { kind, lo, hi } => {
                let e = kind.entry();
                write!(
                    f,
                    "{} must be {lo} to {hi}{}{} (what a real rig can hold; neutral {})",
                    e.parameter.unwrap_or("the value"),
                    if e.unit.is_empty() { "" } else { " " },
                    e.unit,
                    e.neutral
                )
            }
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for ParseEffectError {}

impl FromStr for Effect {
    type Err = ParseEffectError;

    /// `NAME=VALUE`, e.g. `pressure_friction=0.85`, or `none`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let (name, value) = match s.split_once('=') {
            Some((n, v)) => (n.trim(), Some(v.trim())),
            None => (s.trim(), None),
        };
        let kind = EffectKind::from_name(name).ok_or(ParseEffectError::UnknownEffect)?;
        match (kind, value) {
            (EffectKind::None, None) => Ok(Effect::NONE),
            (EffectKind::None, Some(_)) => Err(ParseEffectError::NoneTakesNoValue),
            (_, None) => Err(ParseEffectError::MissingValue),
            (_, Some(v)) => {
                let value: f64 = v.parse().map_err(|_| ParseEffectError::BadValue)?;
                if !value.is_finite() {
                    return Err(ParseEffectError::BadValue);
                }
                let (lo, hi) = kind.entry().physical;
                if !(lo..=hi).contains(&value) {
                    return Err(ParseEffectError::OutOfRange { kind, lo, hi });
                }
                Ok(Effect { kind, value })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_neutral_values_do_nothing() {
        for kind in EffectKind::ALL {
            assert_eq!(EffectKind::from_name(kind.name()), Some(kind));
            let base = Model::euler_eytelwein(0.115);
            let neutral = base.with_effect(Effect {
                kind,
                value: kind.neutral_value(),
            });
            assert_eq!(neutral, base, "{kind}");
        }
    }

    /// Every range holds its neutral value and the sizes the generated cases plant, spread over
    /// the thesis-like designs they are planted on (so the cases a user can reproduce with
    /// `capstan simulate --effect` parse), and refuses what no rig holds.
    #[cfg(feature = "std")]
    #[test]
    fn physical_ranges_hold_the_planted_sizes_and_refuse_the_rest() {
        use crate::entry::Span;
        for kind in EffectKind::ALL {
            let e = kind.entry();
            let (lo, hi) = e.physical;
            assert!(lo <= e.neutral && e.neutral <= hi, "{kind}");
            if kind == EffectKind::None {
                continue;
            }
            let span = match e.cases.span {
                Span::One => 1.0,
                Span::Time100s => 1.315,
                Span::Runs => 5.0,
                Span::Diameters => 12.7,
                Span::Voltages => 5.0,
            };
            for change in [e.cases.care.0, e.cases.care.1] {
                for sign in [1.0, -1.0] {
                    if sign < 0.0 && !e.cases.signed {
                        continue;
                    }
                    let v = (e.cases.value)(sign * change, span);
                    let text = format!("{kind}={v}");
                    assert!(
                        text.parse::<Effect>().is_ok(),
                        "{text}: {:?}",
                        text.parse::<Effect>()
                    );
                }
            }
            let beyond = format!("{kind}={}", hi + (hi - lo).max(1.0));
            let err = beyond.parse::<Effect>().unwrap_err();
            assert!(
                matches!(err, ParseEffectError::OutOfRange { .. }),
                "{beyond}"
            );
            assert!(
                err.to_string().contains("what a real rig can hold"),
                "{err}"
            );
        }
        assert!("sensor_gain=0".parse::<Effect>().is_err());
        assert!("t2_offset=1e9".parse::<Effect>().is_err());
    }

    #[test]
    fn parses_name_value() {
        let e: Effect = "pressure_friction=0.85".parse().unwrap();
        assert_eq!(e.kind, EffectKind::PressureFriction);
        assert_eq!(e.value, 0.85);
        assert_eq!("none".parse::<Effect>(), Ok(Effect::NONE));
        assert_eq!(
            "wear".parse::<Effect>(),
            Err(ParseEffectError::MissingValue)
        );
        assert_eq!(
            "heat=1".parse::<Effect>(),
            Err(ParseEffectError::UnknownEffect)
        );
        assert_eq!("wear=x".parse::<Effect>(), Err(ParseEffectError::BadValue));
        assert_eq!(
            "wear=inf".parse::<Effect>(),
            Err(ParseEffectError::BadValue)
        );
    }

    #[test]
    fn apply_then_read_gives_the_value() {
        for kind in EffectKind::ALL.into_iter().skip(1) {
            let m = Model::euler_eytelwein(0.1).with_effect(Effect { kind, value: 0.37 });
            assert!((Effect::read(kind, &m) - 0.37).abs() < 1e-15, "{kind}");
        }
    }
}
