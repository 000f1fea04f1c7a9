//! `capstan diagnose` on the same data, quoted by the analysis: its single-effect call (with
//! and, for data without `time_s`, without the thesis protocol's step times) and how it relates
//! to the analysis's mechanisms. Every number is taken from the two runs, none typed in.

use super::mechanisms::Mechanisms;
use super::ExtendedDetail;
use crate::data::Dataset;
use crate::diagnose::{diagnose, diagnose_with, Diagnosis, Options};
use capstan_friction::EffectKind;
use serde::Serialize;
use serde_json::{json, Value};
use std::fmt::Write as _;

/// One call of the diagnosis and its answer.
#[derive(Clone, Debug, Serialize)]
pub struct Call {
    /// The Rust call.
    pub call: &'static str,
    /// The equivalent command line.
    pub command: &'static str,
    /// Its answer (the `capstan diagnose --json` object).
    pub result: Diagnosis,
}

/// The diagnosis quoted by the analysis.
#[derive(Clone, Debug, Serialize)]
pub struct DiagnoseQuote {
    /// `diagnose(&data)`: what `capstan diagnose` prints.
    pub default: Call,
    /// `diagnose_with(&data, protocol_times)`: only for data with `step` and without `time_s`.
    pub protocol_times: Option<Call>,
    /// One line for the headline.
    pub headline: String,
    /// How the single-effect call relates to the analysis's mechanisms.
    pub relation: String,
    /// The numbers the relation quotes.
    pub comparison: Value,
}

/// The answer in one phrase: "pressure_friction (n = 0.9017 ± 0.0086, ΔBIC −74.0)".
pub fn verdict(d: &Diagnosis) -> String {
    if d.unexplained {
        return format!("unexplained ({})", d.residual_pattern.unwrap_or("cells"));
    }
    if d.effects.is_empty() {
        return "none (no candidate supported)".into();
    }
    let v: Vec<String> = d.effects.iter().map(crate::diagnose::words::effect_phrase).collect();
    v.join(" + ")
}

fn test<'a>(m: &'a Mechanisms, name: &str) -> Option<&'a super::mechanisms::Mechanism> {
    m.tests.iter().find(|t| t.name == name)
}

fn ev(m: &Mechanisms, test_name: &str, key: &str) -> f64 {
    test(m, test_name)
        .and_then(|t| t.evidence.get(key))
        .and_then(Value::as_f64)
        .unwrap_or(f64::NAN)
}

fn ruled_in(m: &Mechanisms, name: &str) -> bool {
    test(m, name).is_some_and(|t| t.verdict == "ruled_in")
}

/// Both calls of the diagnosis on `ds`: `diagnose`, and `diagnose_with` the thesis protocol's
/// step times when the data have `step` but no `time_s`.
pub fn calls(ds: &Dataset) -> (Call, Option<Call>) {
    let default = Call {
        call: "capstan::diagnose::diagnose(&data)",
        command: "capstan diagnose DATA.csv",
        result: diagnose(ds),
    };
    let protocol_times = (ds.has_column("step") && !ds.has_column("time_s")).then(|| Call {
        call: "capstan::diagnose::diagnose_with(&data, &Options { protocol_times: true, ..Options::default() })",
        command: "capstan diagnose DATA.csv --protocol-times",
        result: diagnose_with(
            ds,
            &Options {
                protocol_times: true,
                ..Options::default()
            },
        ),
    });
    (default, protocol_times)
}

/// Quote the diagnosis `calls` next to the analysis's `mechanisms` and `extended` fit.
pub fn quote(
    (default, protocol_times): (Call, Option<Call>),
    mechanisms: &Mechanisms,
    extended: &ExtendedDetail,
) -> DiagnoseQuote {
    let mut headline = verdict(&default.result);
    if let Some(p) = &protocol_times {
        let _ = write!(
            headline,
            "; with the protocol's step times {}",
            verdict(&p.result)
        );
    }
    let (relation, comparison) = relate(
        &default.result,
        protocol_times.as_ref().map(|c| &c.result),
        mechanisms,
        extended,
    );
    DiagnoseQuote {
        default,
        protocol_times,
        headline,
        relation,
        comparison,
    }
}

/// The paragraph relating the single-effect call to the two-mechanism finding, and its numbers.
fn relate(
    d: &Diagnosis,
    timed: Option<&Diagnosis>,
    m: &Mechanisms,
    e: &ExtendedDetail,
) -> (String, Value) {
    let value = |k: &str| e.values.iter().find(|v| v.0 == k).map_or(f64::NAN, |v| v.1);
    let heating = ruled_in(m, "contact_heating");
    let e1 = value("t1_offset_n");
    let d_heat = ev(m, "contact_heating", "delta_aic_without");
    let d_drift = ev(m, "contact_heating", "delta_aic_time_drift_instead");
    let n_alone = ev(m, "pressure_dependent_friction", "n_alone");
    let n_ext = ev(m, "pressure_dependent_friction", "n_with_extended");
    let dn_ext = ev(m, "pressure_dependent_friction", "delta_aic_with_extended");
    // The extended model's mechanisms (other ruled-in tests are not modelled).
    let inside: Vec<&str> = m
        .causes
        .iter()
        .map(|c| c.name.as_str())
        .filter(|n| ["contact_heating_load_memory", "t1_path_loss"].contains(n))
        .collect();
    let mut s = format!(
        "capstan diagnose names the one catalogue effect that best explains the data; the analysis's extended model carries {} at once ({}).",
        if inside.len() == 2 { "two mechanisms" } else { "its mechanisms" },
        inside.join(" + ")
    );
    if let (Some(c), true) = (d.candidate(EffectKind::PressureFriction), heating) {
        let same = (c.value - n_alone).abs() <= 2.0 * c.parameter_se;
        let _ = write!(s, " Without times, the best single stand-in for amplification falling as the friction load builds is a tension exponent, n = {:.3} ± {:.3} ({} the analysis's one-mu power law: {n_alone:.3}); with the load memory in, the analysis's n is {n_ext:.3} (ΔAIC {dn_ext:+.1}).",
            c.value, c.parameter_se, if same { "the same as" } else { "against" });
    }
    let drift_call = [timed, Some(d)]
        .into_iter()
        .flatten()
        .find(|x| x.kind == EffectKind::ThermalDrift);
    if let (Some(t), true) = (drift_call, heating) {
        let c = t
            .candidate(EffectKind::ThermalDrift)
            .expect("the chosen effect is a candidate");
        let _ = write!(s, " With step times, time grows with the load along every run, so a drift of mu wins ({:+.1} % per 100 s); in the analysis a drift in place of the load memory is worse by ΔAIC {d_drift:+.1}, because cords reaching different loads share the same step times.",
            100.0 * c.value);
    }
    if let (Some(c), true) = (d.candidate(EffectKind::T1Offset), e1.is_finite()) {
        let same = c.value.signum() == e1.signum();
        let _ = write!(s, " Its single-effect T1 offset ({:+.3} N, {}) has {} the analysis's loss e1 = {e1:+.3} N{}.",
            c.value, if c.supported { "supported" } else { "not supported" },
            if same { "the same sign as" } else { "the opposite sign to" },
            if same { "" } else { ": alone it must mimic the decay with tension" });
    }
    let cand = |x: &Diagnosis, k: EffectKind| {
        x.candidate(k).map_or(Value::Null, |c| json!({"value": c.value, "se": c.parameter_se, "delta_bic": c.delta_bic, "supported": c.supported}))
    };
    let comparison = json!({
        "diagnose_pressure_friction": cand(d, EffectKind::PressureFriction),
        "diagnose_t1_offset": cand(d, EffectKind::T1Offset),
        "diagnose_thermal_drift_with_protocol_times": timed.map_or(Value::Null, |t| cand(t, EffectKind::ThermalDrift)),
        "analysis_n_power_law_alone": n_alone,
        "analysis_n_with_extended": n_ext,
        "analysis_delta_aic_n_with_extended": dn_ext,
        "analysis_delta_aic_without_load_memory": d_heat,
        "analysis_delta_aic_drift_instead_of_load_memory": d_drift,
        "analysis_e1_n": e1,
    });
    (s, comparison)
}
