//! What differs between cords: the capstan diameter, and the wrap dependence of mu.

use super::{Ctx, Mechanism};
use crate::fit::stats::mean;
use crate::fit::{Observations, Param};
use serde_json::json;

/// Diameter dependence: the per-cord mu of the two capstans, and a diameter term in the
/// extended model (None with one diameter).
pub fn diameter_dependence(c: &Ctx<'_>) -> Option<Mechanism> {
    let (t, _, p) = c.s.mu_test?;
    let dpd = c.delta_aic("plus_diameter");
    let (small, large) = (mean(&c.s.mu_small), mean(&c.s.mu_large));
    Some(Mechanism {
        name: "diameter_dependence".into(),
        verdict: if p > 0.05 && dpd > -2.0 { "no_effect" } else { "not_established" }.into(),
        rule: "no_effect if the per-cord mu do not differ between capstans (Welch p > 0.05) and a diameter term does not improve the extended model (ΔAIC > −2)".into(),
        summary: format!("Per-cord Euler-Eytelwein mu: small capstan {small:.4}, large {large:.4} (Welch t = {t:.2}, p = {p:.2}); diameter term in the extended model ΔAIC {dpd:+.1}."),
        evidence: json!({"mu_small_mean": small, "mu_large_mean": large, "welch_t": t, "welch_p": p, "delta_aic": dpd}),
    })
}

fn wrap_span(obs: &Observations) -> f64 {
    let w = obs.rows.iter().map(|r| r.op.wrap_rad);
    w.clone().fold(f64::NEG_INFINITY, f64::max) - w.fold(f64::INFINITY, f64::min)
}

/// The wrap slope of ln mu, kept as an empirical population term.
pub fn wrap_dependence_of_mu(c: &Ctx<'_>) -> Mechanism {
    let dnw = c.delta_aic("no_wrap_slope");
    let slope = super::value(c.ext, Param::MuLogSlopePerRad);
    let jk = c.jk("mu_log_slope_per_rad");
    Mechanism {
        name: "wrap_dependence_of_mu".into(),
        verdict: "kept_empirical".into(),
        rule: "kept as an empirical population term (it lets a new cord borrow the wrap trend; its in-sample gain is small because the cord effects absorb it)".into(),
        summary: format!("ln mu rises {slope:.4}/rad (jackknife SE {jk:.4}), {:+.1} % from the smallest to the largest wrap; dropping it: ΔAIC {dnw:+.1}.",
            100.0 * ((slope * wrap_span(c.obs)).exp() - 1.0)),
        evidence: json!({"mu_log_slope_per_rad": slope, "jackknife_se": jk, "delta_aic_without": dnw}),
    }
}
