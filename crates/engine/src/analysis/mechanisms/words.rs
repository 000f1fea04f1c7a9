//! The mechanisms in words. Every sentence that states a verdict is made here, from the verdict
//! and its numbers: the report and `metrics.json` print these, never a sentence typed in beside
//! them.

use super::verdict::{Numbers, Verdict};
use crate::diagnose::words::{list, parameter, sig};
use crate::evidence::Design;
use capstan_friction::EffectKind;

/// What each mechanism of the catalogue is, physically (its entry's title).
pub fn title(kind: EffectKind) -> &'static str {
    kind.entry().title
}

/// A ΔBIC with its sign and one decimal ("not identified" if it could not be computed).
fn signed(v: f64) -> String {
    if v.is_finite() {
        format!("{v:+.1}")
    } else {
        crate::diagnose::words::NOT_IDENTIFIED.to_string()
    }
}

fn value_text(kind: EffectKind, v: f64, se: f64) -> String {
    parameter(kind.parameter().unwrap_or("value"), v, se)
}

/// The sentence of one mechanism's verdict, with its numbers; `causes` are the named causes.
pub fn sentence(
    kind: EffectKind,
    verdict: Verdict,
    n: Option<&Numbers>,
    causes: &[&str],
    reason: &str,
) -> String {
    let name = title(kind);
    let Some(n) = n else {
        return format!(
            "{} cannot be tested on these data: {reason}.",
            capital(name)
        );
    };
    let given = if causes.is_empty() {
        "on its own".to_string()
    } else {
        format!(
            "given {}",
            list(&causes.iter().map(|c| c.to_string()).collect::<Vec<_>>())
        )
    };
    let v = value_text(kind, n.value, n.se);
    match verdict {
        Verdict::RuledIn => format!(
            "{} is in the data: {v}; dropping it costs ΔBIC {} {} (evidence computed with runs as clusters).",
            capital(name),
            signed(-n.delta_bic_given_causes),
            if causes.is_empty() { "against every run's own mu" } else { "given the other named causes" }
        ),
        Verdict::ExplainedAway => format!(
            "{} alone would improve the fit ({} = {}, ΔBIC {}), but not {given} (ΔBIC {}): it stood in for them.",
            capital(name),
            kind.parameter().unwrap_or("value"),
            sig(n.value_alone),
            signed(n.delta_bic_alone),
            signed(n.delta_bic_given_causes)
        ),
        Verdict::RuledOut => format!(
            "{} is ruled out: {v} {given}, and its 95 % interval lies inside ±{} of no effect, a size that would not matter (ΔBIC {}).",
            capital(name),
            sig(n.relevance_width),
            signed(n.delta_bic_given_causes)
        ),
        Verdict::NotEstablished => format!(
            "{} is not established: {v} {given} (ΔBIC {}), but its 95 % interval still reaches a size that matters (±{} from no effect).",
            capital(name),
            signed(n.delta_bic_given_causes),
            sig(n.relevance_width)
        ),
        Verdict::NotTestable => format!("{} cannot be tested on these data: {reason}.", capital(name)),
    }
}

/// What the design of these data can and cannot separate, from the data themselves.
pub fn protocol_limits(d: &Design, named: &[EffectKind]) -> Vec<String> {
    let mut out = Vec::new();
    let both = d.has_both_directions();
    if both {
        out.push("Steps rise and fall in these data, so a memory of the friction load shows as a difference between rising and falling tension, and load is decorrelated from time.".to_string());
    } else {
        out.push("Steps only rise in these data: tension, friction load and time since the trigger grow together inside every run, so a drift with time, contact heating and a power law in tension are told apart only by cords reaching different tensions at the same step. An up-down (or randomised) step order separates them.".to_string());
    }
    if !d.columns.time_s {
        out.push("There is no time_s column: a drift with time cannot be tested (capstan diagnose --protocol-times takes the times from step with the thesis protocol).".to_string());
    }
    out.extend(
        named
            .iter()
            .filter_map(|k| k.entry().named_note)
            .map(String::from),
    );
    if d.wraps().len() < 3 {
        out.push("Fewer than three wraps: an offset on T1 and one on T2 (and a gain) are told apart only across wraps.".to_string());
    }
    if d.cords.len() < 10 {
        out.push(format!("{} cords: effects on mu that vary between cords (gain, diameter, speed) are judged against the cord-to-cord scatter with only that many independent observations.", d.cords.len()));
    }
    out
}

fn capital(s: &str) -> String {
    let mut c = s.chars();
    match c.next() {
        Some(f) => f.to_uppercase().collect::<String>() + c.as_str(),
        None => String::new(),
    }
}
