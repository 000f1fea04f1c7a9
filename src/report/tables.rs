//! The report's HTML tables: the gain table, residual patterns, mechanism verdicts, nested
//! variants, the extended fit, and the thesis's per-angle R².

use super::html::esc;
use crate::analysis::{Analysis, ModelMetrics};
use std::fmt::Write as _;

/// Three decimals, or a dash for a missing value.
pub fn f3(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.3}")
    } else {
        "–".into()
    }
}

fn model_row(m: &ModelMetrics) -> String {
    let count = if m.n_params_strict != m.n_params {
        format!("{} (strict {:.1})", m.n_params, m.n_params_strict)
    } else {
        format!("{}", m.n_params)
    };
    let r2: Vec<String> = m
        .per_cord_r2_amp
        .iter()
        .map(|c| format!("{:.2}", c.r2))
        .collect();
    format!(
        "<tr><td>{}</td><td>{count}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{:.1}</td><td>{:.1}</td><td>{}</td></tr>",
        esc(&m.name),
        f3(m.rmse_t2_n),
        f3(m.rmse_ln_amp),
        m.loco_rmse_t2_n.map_or("not refittable".into(), f3),
        f3(m.per_cord_r2_amp_median),
        m.aic,
        m.bic,
        r2.join(" "),
    )
}

/// The gain table, one row per model.
pub fn gain(a: &Analysis) -> String {
    let mut h = String::from("<table><tr><th>model</th><th>fitted values</th><th>RMSE T2 (N)</th><th>RMSE ln(T2/T1)</th><th>LOCO RMSE T2 (N)</th><th>median per-cord R² amp</th><th>AIC</th><th>BIC</th><th>per-cord R² of amplification</th></tr>");
    for m in &a.models {
        h.push_str(&model_row(m));
    }
    h.push_str("</table>");
    h
}

/// Residual trends against every column.
pub fn residual_patterns(a: &Analysis) -> String {
    let mut h = String::from("<table><tr><th>model</th><th>residual</th><th>column</th><th>ρ</th><th>slope/SD</th><th>t (cluster)</th><th>p (cluster)</th><th>η²</th><th>F</th><th>p (F)</th></tr>");
    for p in &a.residual_patterns {
        let _ = write!(h, "<tr><td>{}</td><td>{}</td><td>{}</td><td>{:.3}</td><td>{:.4}</td><td>{:.2}</td><td>{:.3}</td><td>{:.3}</td><td>{:.1}</td><td>{:.2e}</td></tr>", p.model, p.residual, esc(&p.column), p.spearman_rho, p.slope_per_sd, p.slope_t_cluster, p.slope_p_cluster, p.eta2, p.f, p.f_p);
    }
    h.push_str("</table>");
    h
}

/// The mechanism verdicts.
pub fn mechanisms(a: &Analysis) -> String {
    let mut h = String::from(
        "<table><tr><th>mechanism</th><th>verdict</th><th>evidence</th><th>rule</th></tr>",
    );
    for t in &a.mechanisms.tests {
        let _ = write!(
            h,
            "<tr><td>{}</td><td class=\"verdict-{}\">{}</td><td>{}</td><td>{}</td></tr>",
            esc(&t.name),
            t.verdict,
            t.verdict,
            esc(&t.summary),
            esc(&t.rule)
        );
    }
    h.push_str("</table>");
    h
}

/// Every nested variant with ΔAIC/ΔBIC.
pub fn variants(a: &Analysis) -> String {
    let mut h = String::from("<table><tr><th>variant</th><th>reference</th><th>values</th><th>RMSE T2</th><th>RMSE ln amp</th><th>ΔAIC</th><th>ΔBIC</th><th>fitted</th></tr>");
    for v in &a.mechanisms.variants {
        let vals: Vec<String> = v
            .values
            .iter()
            .map(|(k, x)| format!("{k} = {x:.4}"))
            .collect();
        let _ = write!(h, "<tr><td>{}</td><td>{}</td><td>{}</td><td>{:.3}</td><td>{:.3}</td><td>{:+.1}</td><td>{:+.1}</td><td>{}</td></tr>", esc(&v.description), esc(&v.reference), v.n_params, v.rmse_t2_n, v.rmse_ln_amp, v.delta_aic, v.delta_bic, esc(&vals.join(", ")));
    }
    h.push_str("</table>");
    h
}

/// The extended fit's values with their standard errors, then the cord offsets.
pub fn extended(a: &Analysis) -> String {
    let e = &a.extended;
    let mut h = String::from("<table><tr><th>value</th><th>estimate</th><th>Gauss-Newton SE</th><th>jackknife SE (LOCO)</th></tr>");
    let jk = |k: &str| {
        e.jackknife_se
            .iter()
            .find(|x| x.0 == k)
            .map_or(f64::NAN, |x| x.1)
    };
    for ((k, v), (_, se)) in e.values.iter().zip(&e.standard_errors) {
        let se = if se.abs() < 1e3 {
            format!("{se:.5}")
        } else {
            "unidentified alone".into()
        };
        let j = jk(k);
        let j = if j.is_finite() {
            format!("{j:.5}")
        } else {
            "–".into()
        };
        let _ = write!(
            h,
            "<tr><td>{k}</td><td>{v:.5}</td><td>{se}</td><td>{j}</td></tr>"
        );
    }
    let _ = write!(
        h,
        "<tr><td>h·τ (1/N)</td><td>{:.5}</td><td></td><td>{:.5}</td></tr></table>",
        e.heat_per_n_steady,
        jk("heat_per_ns*heat_tau_s")
    );
    let _ = write!(h, "<p>σ<sub>u</sub> = {:.4} (ln mu), λ = {:.1}, edf of the cord effects {:.2}; population-only RMSE (u = 0) {:.3} N. h and τ trade off when τ is short; their product (steady-state ln-mu loss per newton of friction load) is what the data fix: mu × {:.3} at T2 − T1 = 40 N.</p>",
        e.sigma_u, e.lambda, e.edf_random, e.rmse_population_t2_n, e.mu_factor_at_40n_load);
    h.push_str("<table><tr><th>cord</th><th>u (ln mu)</th></tr>");
    for (c, u) in &e.cord_log_mu {
        let _ = write!(h, "<tr><td>{}</td><td>{u:+.4}</td></tr>", esc(c));
    }
    h.push_str("</table>");
    h
}

/// The thesis's per-angle R² of amplification.
pub fn thesis_r2(a: &Analysis) -> String {
    let mut h = String::from("<table><tr><th>angle (deg)</th><th>R²</th><th>rows</th></tr>");
    for r in &a.thesis_per_angle_r2 {
        let _ = write!(
            h,
            "<tr><td>{}</td><td>{:.3}</td><td>{}</td></tr>",
            r.wrap_deg, r.r2, r.rows
        );
    }
    h.push_str("</table>");
    h
}
