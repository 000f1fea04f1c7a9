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

/// Three decimals, or a dash for a missing value.
pub fn f3(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.3}")
    } else {
        "–".into()
    }
}

/// `v` with `d` decimals, or a dash where it is not identified on these data.
pub fn fx(v: f64, d: usize) -> String {
    if v.is_finite() {
        format!("{v:.d$}")
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
    use super::fp;

    #[test]
    fn p_values_read_sanely() {
        assert_eq!(fp(1.71e-160), "< 0.0001");
        assert_eq!(fp(0.0007), "0.0007");
        assert_eq!(fp(0.0321), "0.032");
        assert_eq!(fp(f64::NAN), "–");
    }
}
