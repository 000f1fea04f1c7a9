//! Numbers and lists as the sentences print them, shared by the evidence and the verdict
//! layers (below both, so neither imports the other for its wording).

/// What a number that could not be computed is shown as.
pub const NOT_IDENTIFIED: &str = "not identified";

/// Four significant digits (scientific for very small or large magnitudes).
pub fn sig(v: f64) -> String {
    if !v.is_finite() {
        return NOT_IDENTIFIED.to_string();
    }
    if v == 0.0 {
        return "0".to_string();
    }
    let e = v.abs().log10().floor();
    if (-3.0..5.0).contains(&e) {
        format!("{:.*}", (3.0 - e).max(0.0) as usize, v)
    } else {
        format!("{v:.3e}")
    }
}

/// A list in words: "a", "a and b", "a, b and c".
pub fn list(items: &[String]) -> String {
    match items.len() {
        0 => String::new(),
        1 => items[0].clone(),
        n => format!("{} and {}", items[..n - 1].join(", "), items[n - 1]),
    }
}
