//! The diagnosis in words: every sentence that states a verdict is made here from the verdict
//! itself (the effects found and the adequacy decision), never typed in beside it.

use super::Found;
use crate::evidence::Adequacy;

/// A catalogue parameter with its SE, the value to the SE's precision (two significant
/// digits of the SE): "n = 0.9017 ± 0.0086".
pub fn parameter(name: &str, v: f64, se: f64) -> String {
    if !(se.is_finite() && se > 0.0) {
        return format!("{name} = {}", sig(v));
    }
    let decimals = (1.0 - se.log10().floor()).max(0.0) as usize;
    if decimals > 6 {
        return format!("{name} = {v:.3e} ± {se:.1e}");
    }
    format!("{name} = {v:.decimals$} ± {se:.decimals$}")
}

/// Four significant digits (scientific for very small or large magnitudes).
pub fn sig(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let e = v.abs().log10().floor();
    if (-3.0..5.0).contains(&e) {
        format!("{:.*}", (3.0 - e).max(0.0) as usize, v)
    } else {
        format!("{v:.3e}")
    }
}

/// "pressure_friction (n = 0.902 ± 0.009, ΔBIC −74.0)".
pub fn effect_phrase(f: &Found) -> String {
    let p = f
        .parameters
        .iter()
        .next()
        .map_or(String::new(), |(k, v)| parameter(k, *v, f.parameter_se));
    format!("{} ({p}, ΔBIC {:.1})", f.effect, f.delta_bic_given_others)
}

/// A list in words: "a", "a and b", "a, b and c".
pub fn list(items: &[String]) -> String {
    match items.len() {
        0 => String::new(),
        1 => items[0].clone(),
        n => format!("{} and {}", items[..n - 1].join(", "), items[n - 1]),
    }
}

/// The verdict: what the data hold, and whether anything is left unexplained.
pub fn verdict(effects: &[Found], adequacy: &Adequacy) -> String {
    let names: Vec<String> = effects.iter().map(effect_phrase).collect();
    match (effects.is_empty(), adequacy.unexplained) {
        (true, false) => format!(
            "No catalogue effect is supported: Euler-Eytelwein, with every run's own mu, explains the data within their noise. {}",
            adequacy.sentence
        ),
        (false, false) => format!(
            "The data hold {}. {}",
            list(&names),
            adequacy.sentence
        ),
        (true, true) => format!(
            "Unexplained: {} No catalogue effect is supported on its own.",
            capitalised(&adequacy.sentence)
        ),
        (false, true) => format!(
            "Unexplained: {} The catalogue effects that improve the fit — {} — do not account for it, so they are not a diagnosis.",
            capitalised(&adequacy.sentence),
            list(&names)
        ),
    }
}

fn capitalised(s: &str) -> String {
    let mut c = s.chars();
    match c.next() {
        Some(f) => f.to_uppercase().collect::<String>() + c.as_str(),
        None => String::new(),
    }
}
