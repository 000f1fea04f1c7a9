//! The verdicts in words, for `capstan diagnose` and `capstan analyze` alike: every sentence
//! that states a verdict is made here from the verdict itself (the effects found, each
//! mechanism's verdict and numbers, the adequacy decision, the rivals), never typed in beside
//! it. What each effect is comes from its catalogue entry.

use super::{Found, Numbers, Verdict};
use crate::evidence::adequacy::{underpowered, LackOfFit};
use crate::evidence::{Adequacy, Design, Rival};
use capstan_data::structure::StructureSummary;
use capstan_data::Basis;
use capstan_physics::EffectKind;

pub use crate::text::{list, sig, NOT_IDENTIFIED};

/// `v` with `decimals` decimals, or "not identified" if it could not be computed.
pub fn fixed(v: f64, decimals: usize) -> String {
    if v.is_finite() {
        format!("{v:.decimals$}")
    } else {
        NOT_IDENTIFIED.to_string()
    }
}

/// A catalogue parameter with its SE, the value to the SE's precision (two significant
/// digits of the SE): "n = 0.9017 ± 0.0086".
pub fn parameter(name: &str, v: f64, se: f64) -> String {
    if !v.is_finite() {
        return format!("{name} {NOT_IDENTIFIED}");
    }
    if !(se.is_finite() && se > 0.0) {
        return format!("{name} = {}", sig(v));
    }
    let decimals = (1.0 - se.log10().floor()).max(0.0) as usize;
    if decimals > 6 {
        return format!("{name} = {v:.3e} ± {se:.1e}");
    }
    format!("{name} = {v:.decimals$} ± {se:.decimals$}")
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

/// The verdict: what the data hold, whether anything is left unexplained, and which found
/// effects the data cannot tell from a rival.
pub fn verdict(effects: &[Found], adequacy: &Adequacy, rivals: &[Rival]) -> String {
    let base = verdict_of_set(effects, adequacy);
    if effects.is_empty() || rivals.is_empty() {
        return base;
    }
    format!("{base} {}", rival_sentences(rivals))
}

/// "These data cannot rule out thermal_drift (mu_change_per_100s = -0.2500) in place of
/// contact_heating: the set with it fits nearly as well (ΔBIC +2.1); in runs whose …"
pub fn rival_sentences(rivals: &[Rival]) -> String {
    rivals
        .iter()
        .map(|r| {
            let p = r
                .parameters
                .iter()
                .next()
                .map_or(String::new(), |(k, v)| format!(" ({k} = {})", sig(*v)));
            let fit = if r.delta_bic >= 0.0 {
                format!("fits nearly as well (ΔBIC +{:.1})", r.delta_bic)
            } else {
                format!(
                    "fits better (ΔBIC {:.1}) but was not kept by the stepwise selection",
                    r.delta_bic
                )
            };
            let why = r
                .reason
                .as_ref()
                .map_or(String::new(), |w| format!("; {w}"));
            format!(
                "These data cannot rule out {}{p} in place of {}: the set with it {fit}{why}.",
                r.effect, r.instead_of
            )
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// Too few replicate runs to tell whether anything systematic is left: no test of the lack of
/// fit, or one (beyond the cords' own parameters, where there is one, or the plain one) too
/// weak to rule out structure that matters. Every command that says "nothing is left" asks
/// this first.
pub fn inconclusive(adequacy: &Adequacy) -> bool {
    let lof = adequacy
        .lack_of_fit_beyond_cords
        .as_ref()
        .or(adequacy.lack_of_fit.as_ref());
    let weak = |l: &LackOfFit| underpowered(l, adequacy.rule);
    !adequacy.tested || lof.is_none_or(weak) || adequacy.lack_of_fit.as_ref().is_some_and(weak)
}

/// The verdict on the found set and the adequacy decision alone.
fn verdict_of_set(effects: &[Found], adequacy: &Adequacy) -> String {
    let names: Vec<String> = effects.iter().map(effect_phrase).collect();
    // Euler-Eytelwein "explains" the data only where a pure-error test could have shown
    // otherwise: with replicate runs enough for it to see structure the rule calls large.
    let inconclusive = inconclusive(adequacy);
    match (effects.is_empty(), adequacy.unexplained) {
        (true, false) if inconclusive => format!(
            "Not identified: no catalogue effect is supported, but these data are too few to tell whether Euler-Eytelwein explains them. {}",
            adequacy.sentence
        ),
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

/// The sentence a verdict on a structure not read from columns ends with (None when cords and
/// runs both come from columns).
pub fn structure_caveat(s: &StructureSummary) -> Option<String> {
    let mut parts = Vec::new();
    if s.cords.from == Basis::Assumed {
        parts.push(
            "the rows at one wrap are taken as one cord (no capstan_diameter_mm or cord column)"
                .to_string(),
        );
    }
    match s.runs.from {
        Basis::Inferred => parts.push(format!(
            "the runs are inferred from {} restarting (no run column)",
            s.runs.columns.first().map_or("step", String::as_str)
        )),
        Basis::Assumed => {
            parts.push("each cord is taken as one run (no run, step or time_s column)".to_string())
        }
        Basis::Columns => {}
    }
    (!parts.is_empty()).then(|| {
        format!(
            "This is a verdict on a structure not read from columns: {}.",
            list(&parts)
        )
    })
}

/// `s` with its first letter in upper case.
pub fn capitalised(s: &str) -> String {
    let mut c = s.chars();
    match c.next() {
        Some(f) => f.to_uppercase().collect::<String>() + c.as_str(),
        None => String::new(),
    }
}

/// What each mechanism of the catalogue is, physically (its entry's title).
pub fn title(kind: EffectKind) -> &'static str {
    kind.entry().title
}

/// A ΔBIC with its sign and one decimal ("not identified" if it could not be computed).
fn signed(v: f64) -> String {
    if v.is_finite() {
        format!("{v:+.1}")
    } else {
        NOT_IDENTIFIED.to_string()
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
            capitalised(name)
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
    let mut v = value_text(kind, n.value, n.se);
    if let Some((lo, hi)) = n.edge_interval {
        v += &format!(
            " (at the edge of its range; 95 % interval {} to {})",
            sig(lo),
            sig(hi)
        );
    }
    match verdict {
        Verdict::RuledIn => format!(
            "{} is in the data: {v}; dropping it costs ΔBIC {} {} (evidence computed with runs as clusters).",
            capitalised(name),
            signed(-n.delta_bic_given_causes),
            if causes.is_empty() { "against every run's own mu" } else { "given the other named causes" }
        ),
        Verdict::ExplainedAway => format!(
            "{} alone would improve the fit ({} = {}, ΔBIC {}), but not {given} (ΔBIC {}): it stood in for them.",
            capitalised(name),
            kind.parameter().unwrap_or("value"),
            sig(n.value_alone),
            signed(n.delta_bic_alone),
            signed(n.delta_bic_given_causes)
        ),
        Verdict::RuledOut => format!(
            "{} is ruled out: {v} {given}, and its 95 % interval lies inside ±{} of no effect, a size that would not matter (ΔBIC {}).",
            capitalised(name),
            sig(n.relevance_width),
            signed(n.delta_bic_given_causes)
        ),
        Verdict::NotEstablished => format!(
            "{} is not established: {v} {given} (ΔBIC {}), but its 95 % interval still reaches a size that matters (±{} from no effect).",
            capitalised(name),
            signed(n.delta_bic_given_causes),
            sig(n.relevance_width)
        ),
        Verdict::NotTestable => format!("{} cannot be tested on these data: {reason}.", capitalised(name)),
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

#[cfg(test)]
mod tests {
    use super::*;

    fn rival(delta_bic: f64, reason: Option<&str>) -> Rival {
        Rival {
            instead_of: "contact_heating",
            effect: "thermal_drift",
            parameters: [("mu_change_per_100s", -0.25)].into_iter().collect(),
            delta_bic,
            reason: reason.map(String::from),
            instead_of_kind: EffectKind::ContactHeating,
            kind: EffectKind::ThermalDrift,
        }
    }

    #[test]
    fn rival_sentences_come_from_the_rival() {
        let s = rival_sentences(&[rival(
            2.06,
            Some("runs that step up and back down separate them"),
        )]);
        assert_eq!(
            s,
            "These data cannot rule out thermal_drift (mu_change_per_100s = -0.2500) in place of \
             contact_heating: the set with it fits nearly as well (ΔBIC +2.1); runs that step up \
             and back down separate them."
        );
        let s = rival_sentences(&[rival(-1.5, None)]);
        assert!(s.contains("fits better (ΔBIC -1.5) but was not kept by the stepwise selection."));
    }
}
