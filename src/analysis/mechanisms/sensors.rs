//! The sensor side: a loss (or zero error) on the T1 path, a T2 zero offset, a T2 gain.

use super::{Ctx, Mechanism};
use crate::analysis::metrics::rmse_ln_amp;
use crate::fit::Param;
use serde_json::json;

/// A constant loss e1 on the servo side; the per-cord intercepts are checked against offsets.
pub fn t1_path_loss(c: &Ctx<'_>) -> Mechanism {
    let (ext, isl, lines) = (c.ext, c.s.isl, &c.s.cord_lines);
    let e1 = super::value(ext, Param::T1Offset);
    let dne = c.delta_aic("no_t1_loss");
    let rmse_without = c.variant("no_t1_loss").map_or(f64::NAN, |v| v.rmse_t2_n);
    let q_min = lines
        .iter()
        .map(|l| l.quadratic_t)
        .fold(f64::INFINITY, f64::min);
    let q_max = lines
        .iter()
        .map(|l| l.quadratic_t)
        .fold(f64::NEG_INFINITY, f64::max);
    Mechanism {
        name: "t1_path_loss".into(),
        verdict: if dne >= 10.0 { "ruled_in" } else if dne <= 2.0 { "ruled_out" } else { "not_established" }.into(),
        rule: "ruled_in if dropping e1 from the extended model costs ΔAIC ≥ +10".into(),
        summary: format!("e1 = {e1:.3} N (jackknife SE {:.3}); dropping it costs ΔAIC {dne:+.1} (RMSE {:.3} → {:.3} N). Intercepts of T2(T1) are not offsets: c = {:.2} + {:.2}·s (t = {:.1}) would need e1 = {:.2} N and e2 = {:.2} N, and every cord is concave (quadratic t from {q_min:.1} to {q_max:.1}).",
            c.jk("t1_offset_n"), ext.rmse(), rmse_without, isl.0, isl.1, isl.2, -isl.1, isl.0),
        evidence: json!({"e1_n": e1, "e1_jackknife_se": c.jk("t1_offset_n"), "delta_aic_without": dne, "intercept_vs_slope": c.s.isl_json.clone()}),
    }
}

/// A T2 zero offset on top of the extended model: does it help T2 without spoiling ln(T2/T1)?
pub fn t2_offset(c: &Ctx<'_>) -> Mechanism {
    let e2 = c.mixed_value("plus_t2_offset", Param::T2Offset);
    let dpe2 = c.delta_aic("plus_t2_offset");
    let ln_ratio = c
        .variant("plus_t2_offset")
        .map_or(f64::NAN, |v| v.rmse_ln_amp)
        / rmse_ln_amp(c.obs, &c.ext.t2_n);
    Mechanism {
        name: "t2_offset".into(),
        verdict: if dpe2 > -2.0 { "ruled_out" } else if ln_ratio > 1.5 { "not_supported" } else { "ruled_in" }.into(),
        rule: "ruled_out if e2 does not improve the extended model (ΔAIC > −2); not_supported if it helps T2 only by making ln(T2/T1) fit over 1.5× worse".into(),
        summary: format!("e2 = {e2:.3} N, ΔAIC {dpe2:+.1}, RMSE of ln amp ×{ln_ratio:.2}."),
        evidence: json!({"e2_n": e2, "delta_aic": dpe2, "rmse_ln_amp_ratio": ln_ratio}),
    }
}

/// A T2 gain: fitted on top of the extended model, and read from ln(slope) against β.
pub fn sensor_gain(c: &Ctx<'_>) -> Mechanism {
    let g = c.mixed_value("plus_gain", Param::T2Gain);
    let dpg = c.delta_aic("plus_gain");
    let (gi, gp) =
        c.s.gain_reg
            .as_ref()
            .map_or((f64::NAN, f64::NAN), |r| (r.coef[0].exp(), r.p[0]));
    Mechanism {
        name: "sensor_gain".into(),
        verdict: if dpg > -2.0 { "ruled_out" } else if dpg <= -10.0 { "ruled_in" } else { "not_established" }.into(),
        rule: "ruled_out if a T2 gain does not improve the extended model (ΔAIC > −2)".into(),
        summary: format!("g = {g:.3} with the extended terms (ΔAIC {dpg:+.1}); ln(slope) against β extrapolates to g = {gi:.3} at β = 0 (p = {gp:.2})."),
        evidence: json!({"gain": g, "delta_aic": dpg, "gain_from_ln_slope_intercept": gi, "p": gp}),
    }
}
