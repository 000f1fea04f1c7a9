//! What builds up along a run or from run to run: contact heating (mu falls with the remembered
//! friction load), against a plain drift with time; and wear between runs.

use super::{Ctx, Mechanism};
use crate::fit::Param;
use serde_json::json;

/// Contact heating: mu·exp(−h·H), H the friction-load memory with time constant τ.
pub fn contact_heating(c: &Ctx<'_>) -> Mechanism {
    let ext = c.ext;
    let tau_a = super::value(ext, Param::HeatTauS);
    let h_tau = super::value(ext, Param::HeatPerNs) * tau_a;
    let (dnh, dtd) = (
        c.delta_aic("no_heating"),
        c.delta_aic("time_drift_instead_of_heating"),
    );
    let rmse_without = c.variant("no_heating").map_or(f64::NAN, |v| v.rmse_t2_n);
    let profile = &c.v.tau_profile;
    let best_tau = profile
        .iter()
        .min_by(|a, b| a.aic.total_cmp(&b.aic))
        .map_or(f64::NAN, |p| p.tau_s);
    let aic_at = |t: f64| {
        profile
            .iter()
            .find(|p| (p.tau_s - t).abs() < 1e-9)
            .map_or(f64::NAN, |p| p.aic)
    };
    let tau_gap = aic_at(7.0) - aic_at(0.25);
    Mechanism {
        name: "contact_heating".into(),
        verdict: if dnh >= 10.0 && dtd >= 10.0 { "ruled_in" } else if dnh < 2.0 { "ruled_out" } else { "not_established" }.into(),
        rule: "ruled_in if dropping the friction-load term costs ΔAIC ≥ +10 and a drift with time since the trigger instead of it is worse by ΔAIC ≥ +10".into(),
        summary: format!("mu = mu0·exp(−h·H), H the friction-load memory: dropping it costs ΔAIC {dnh:+.1} (RMSE {:.3} → {:.3} N); a drift with time instead fits worse by ΔAIC {dtd:+.1}. Steady state: mu falls by {:.1} % per 10 N of T2 − T1 (×{:.3} at 40 N). The memory is short: τ = {tau_a:.2} s (profile best at {best_tau} s; AIC at τ = 7 s is {tau_gap:+.1} worse than at 0.25 s).",
            ext.rmse(), rmse_without, 100.0 * (1.0 - (-h_tau * 10.0).exp()), (-h_tau * 40.0).exp()),
        evidence: json!({"delta_aic_without": dnh, "delta_aic_time_drift_instead": dtd, "heat_per_ns": super::value(ext, Param::HeatPerNs), "heat_tau_s": tau_a, "h_tau_per_n": h_tau, "tau_profile_best_s": best_tau, "aic_tau7_minus_tau025": tau_gap}),
    }
}

/// Wear: a change of mu per run, pooled and at cord level.
pub fn wear(c: &Ctx<'_>) -> Mechanism {
    let dpw = c.delta_aic("plus_wear");
    let wear = c.mixed_value("plus_wear", Param::MuChangePerRun);
    let (wm, wt, wp) = c.s.wear_t.unwrap_or((f64::NAN, f64::NAN, f64::NAN));
    let cords = c.s.run_slopes.len();
    Mechanism {
        name: "wear".into(),
        verdict: if wp < 0.05 && dpw <= -10.0 { "ruled_in" } else { "not_established" }.into(),
        rule: "ruled_in only if a run trend is significant at cord level (one-sample t of the per-cord run slopes, p < 0.05) and improves the pooled fit (ΔAIC ≤ −10)".into(),
        summary: format!("Pooled: mu changes {:+.2} % per run (ΔAIC {dpw:+.1}); at cord level the run slope of ln amp is {wm:+.4}/run (t = {wt:.2}, p = {wp:.2}, {cords} cords).", 100.0 * wear),
        evidence: json!({"mu_change_per_run": wear, "delta_aic": dpw, "cord_level_mean_slope": wm, "cord_level_t": wt, "cord_level_p": wp, "cords": cords}),
    }
}
