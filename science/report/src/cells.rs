//! The text of the report's cells and sentences: numbers with their decimals, or a dash where
//! a number is not identified on these data, and text escaped for HTML. Shared by the page
//! ([`super::html`]) and its tables ([`super::tables`]).

use capstan_engine::analysis::uncertainty::WithInterval;

/// Escape text for HTML (and SVG).
pub fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// `text` with the sign of every negative number set as a minus sign (U+2212), as a journal
/// sets it: a hyphen-minus directly before a digit (or before ".5"), where no letter, digit or
/// hyphen, underscore, slash or dot precedes it. "-0.82 N" and "(-1.07 to -0.58)" change;
/// "leave-one-cord-out", "2026-11-29", "5.0e-4" and a path such as "runs/-1.csv" do not. For prose and table cells, not for files read back as
/// numbers (CSV, JSON), which keep the ASCII sign.
pub fn minus_signs(text: &str) -> String {
    let c: Vec<char> = text.chars().collect();
    let sign = |i: usize| {
        let before = i.checked_sub(1).map(|j| c[j]);
        let digit_after = match (c.get(i + 1), c.get(i + 2)) {
            (Some(d), _) if d.is_ascii_digit() => true,
            (Some('.'), Some(d)) => d.is_ascii_digit(),
            _ => false,
        };
        digit_after && !before.is_some_and(|b| b.is_alphanumeric() || "-_/\\.".contains(b))
    };
    (0..c.len())
        .map(|i| if c[i] == '-' && sign(i) { '−' } else { c[i] })
        .collect()
}

/// Three decimals, or a dash for a missing value.
pub fn f3(v: f64) -> String {
    fx(v, 3)
}

/// `v` with `d` decimals, or a dash where it is not identified on these data. A value that
/// rounds to zero has no sign ("0.00", never "-0.00").
pub fn fx(v: f64, d: usize) -> String {
    if v.is_finite() {
        let t = format!("{v:.d$}");
        match t.strip_prefix('-') {
            Some(rest) if rest.bytes().all(|b| b == b'0' || b == b'.') => rest.to_string(),
            _ => t,
        }
    } else {
        "–".into()
    }
}

/// `v` with its sign and `d` decimals, or a dash.
pub fn fs(v: f64, d: usize) -> String {
    if v.is_finite() {
        format!("{v:+.d$}")
    } else {
        "–".into()
    }
}

/// `v` in scientific notation with `d` decimals, or a dash.
pub fn fe(v: f64, d: usize) -> String {
    if v.is_finite() {
        format!("{v:.d$e}")
    } else {
        "–".into()
    }
}

/// A value with its 95 % interval: "0.775 [0.70, 0.86]".
pub fn with_ci(w: &WithInterval) -> String {
    format!("{} [{}, {}]", f3(w.value), f3(w.ci95.lo), f3(w.ci95.hi))
}

/// Decimals that show `v` at its standard error's precision (the SE to two significant
/// digits: −0.8234 ± 0.107 → 2, "−0.82"), or two significant digits of the value without an SE
/// (its uncertainty not computed: 0.7965 → "0.80"; 0 → "0.0"). The one
/// rounding rule of Table 1, the headline and `parameters.tex`, so a value reads the same in
/// each.
pub fn se_decimals(v: f64, se: Option<f64>) -> usize {
    match se.filter(|s| s.is_finite() && *s > 0.0) {
        Some(s) => (1 - s.log10().floor() as i32).clamp(0, 8) as usize,
        None if v.is_finite() && v != 0.0 => {
            (1 - v.abs().log10().floor() as i32).clamp(0, 8) as usize
        }
        None => 1,
    }
}

/// A p-value as a reader quotes it: "< 0.0001" below that, otherwise two significant figures
/// at most four decimals ("0.032", "0.0007"), or a dash.
pub fn fp(p: f64) -> String {
    if !p.is_finite() {
        "–".into()
    } else if p < 1e-4 {
        "< 0.0001".into()
    } else if p < 0.01 {
        format!("{p:.4}")
    } else {
        format!("{p:.3}")
    }
}

#[cfg(test)]
mod tests {
    use super::{fp, minus_signs, se_decimals};

    #[test]
    fn only_signs_become_minus_signs() {
        assert_eq!(
            minus_signs("offset of -0.82 N (-1.07 to -0.58), rho -.5"),
            "offset of −0.82 N (−1.07 to −0.58), rho −.5"
        );
        for kept in [
            "leave-one-cord-out",
            "2026-11-29",
            "p ≤ 5.0e-4",
            "--seed",
            "x-1",
            "a_-1",
        ] {
            assert_eq!(minus_signs(kept), kept);
        }
        assert_eq!(minus_signs("-3"), "−3");
        assert_eq!(super::fx(-0.001, 2), "0.00");
        assert_eq!(super::fx(-0.01, 2), "-0.01");
        assert_eq!(minus_signs("−3 - 2"), "−3 - 2");
    }

    #[test]
    fn p_values_read_sanely() {
        assert_eq!(fp(1.71e-160), "< 0.0001");
        assert_eq!(se_decimals(-0.8234, Some(0.107)), 2);
        assert_eq!(se_decimals(0.00829, Some(0.00108)), 4);
        assert_eq!(se_decimals(0.00788, Some(0.00037)), 5);
        assert_eq!(se_decimals(0.7965, None), 2);
        assert_eq!(se_decimals(0.03871, None), 3);
        assert_eq!(se_decimals(12.5, None), 0);
        assert_eq!(fp(0.0007), "0.0007");
        assert_eq!(fp(0.0321), "0.032");
        assert_eq!(fp(f64::NAN), "–");
    }
}
