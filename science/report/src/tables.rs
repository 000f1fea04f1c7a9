//! The report's HTML tables: the gain table with its intervals, the held-out cords, the
//! ln-amplification residuals by step, residual patterns, mechanism verdicts, the extended fit,
//! and the thesis's per-angle R².

use super::cells::{esc, f3, fe, fp, fs, fx, with_ci};
use capstan_engine::analysis::residuals::StepResidual;
use capstan_engine::analysis::{Analysis, ModelMetrics};
use capstan_engine::verdict::Verdict;
use std::fmt::Write as _;

fn model_row(m: &ModelMetrics) -> String {
    let count = if m.n_params_detail.edf_random > 0.0 {
        format!(
            "{} ({} fixed + {} edf of the cord effects)",
            fx(m.n_params, 1),
            m.n_params_detail.fixed,
            fx(m.n_params_detail.edf_random, 1)
        )
    } else {
        format!("{}", m.n_params)
    };
    let r2: Vec<String> = m.per_cord_r2_amp.iter().map(|c| fx(c.r2, 2)).collect();
    format!(
        "<tr><td>{}</td><td>{count}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
        esc(&m.name),
        with_ci(&m.rmse_t2_uncertainty),
        match m.ln_amp_undefined_rows {
            0 => f3(m.rmse_ln_amp),
            k => format!("{} ({k} rows predicted T2 ≤ 0 left out)", f3(m.rmse_ln_amp)),
        },
        m.loco_rmse_t2_uncertainty
            .as_ref()
            .map_or("not refittable".into(), with_ci),
        f3(m.per_cord_r2_amp_median),
        fx(m.aic, 1),
        fx(m.bic, 1),
        r2.join(" "),
    )
}

/// The gain table, one row per model.
pub fn gain(a: &Analysis) -> String {
    let mut h = String::from("<table><tr><th>model</th><th>parameters (effective dof)</th><th>RMSE T2 (N) [95 % CI, cords resampled]</th><th>RMSE ln(T2/T1)</th><th>LOCO RMSE T2 (N) [95 % CI]</th><th>median per-cord R² amp</th><th>AIC (rows as if independent)</th><th>BIC (ditto)</th><th>per-cord R² of amplification</th></tr>");
    for m in &a.models {
        h.push_str(&model_row(m));
    }
    h.push_str("</table>");
    h
}

/// Residual trends against every column.
pub fn residual_patterns(a: &Analysis) -> String {
    let mut h = String::from("<table><tr><th>model</th><th>residual</th><th>column</th><th>ρ</th><th>slope/SD</th><th>t (cluster)</th><th>p (cluster)</th><th>p (Holm)</th><th>η²</th><th>F</th><th>p (F)</th></tr>");
    for p in &a.residual_patterns {
        let _ = write!(h, "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>", p.model, p.residual, esc(&p.column), fx(p.spearman_rho, 3), fx(p.slope_per_sd, 4), fx(p.slope_t_cluster, 2), esc(&fp(p.slope_p_cluster)), esc(&fp(p.slope_p_holm)), fx(p.eta2, 3), fx(p.f, 1), esc(&fp(p.f_p)));
    }
    h.push_str("</table>");
    h
}

/// The mechanism verdicts, each with its generated sentence.
pub fn mechanisms(a: &Analysis) -> String {
    let mut h = String::from("<table><tr><th>mechanism</th><th>verdict</th><th>evidence</th></tr>");
    for t in &a.mechanisms.tests {
        let _ = write!(
            h,
            "<tr data-mechanism=\"{}\"><td>{}</td><td class=\"verdict-{}\">{}</td><td class=\"summary\">{}</td></tr>",
            t.name,
            esc(t.name),
            t.verdict.name(),
            t.verdict.name(),
            esc(&t.summary),
        );
    }
    h.push_str("</table><p>The rules, one for every mechanism:</p><ul>");
    for v in [
        Verdict::RuledIn,
        Verdict::ExplainedAway,
        Verdict::RuledOut,
        Verdict::NotEstablished,
        Verdict::NotTestable,
    ] {
        let _ = write!(h, "<li>{}</li>", esc(v.rule()));
    }
    h.push_str("</ul>");
    h
}

/// Every cord's held-out RMSE.
pub fn held_out(a: &Analysis) -> String {
    let mut h = String::from("<table><tr><th>held-out cord</th><th>rows</th>");
    let names: Vec<String> = a
        .held_out
        .first()
        .map(|c| c.rmse_t2_n.iter().map(|x| x.0.clone()).collect())
        .unwrap_or_default();
    for n in &names {
        let _ = write!(h, "<th>{} LOCO RMSE T2 (N)</th>", esc(n));
    }
    h.push_str("<th>extended better</th></tr>");
    for c in &a.held_out {
        let _ = write!(h, "<tr><td>{}</td><td>{}</td>", esc(&c.cord), c.rows);
        for (_, v) in &c.rmse_t2_n {
            let _ = write!(h, "<td>{}</td>", f3(*v));
        }
        let _ = write!(
            h,
            "<td>{}</td></tr>",
            if c.extended_better { "yes" } else { "no" }
        );
    }
    h.push_str("</table>");
    h
}

/// ln-amplification residuals by step.
pub fn ln_amp_by_step(steps: &[StepResidual]) -> String {
    let mut h = String::from("<table><tr><th>step</th><th>rows</th><th>mean T1 (N)</th><th>mean ln-amp residual, Euler-Eytelwein</th><th>extended</th><th>RMS, Euler-Eytelwein</th><th>RMS, extended</th><th>predicted T2 ≤ 0 (Euler-Eytelwein / extended; left out of the ln residuals)</th><th>lowest T2, extended / measured (N)</th></tr>");
    for s in steps {
        let worse = s.extended_rms > s.baseline_rms || s.extended_nonpositive > 0;
        let _ = write!(
            h,
            "<tr{}><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{} / {}</td><td>{} / {}</td></tr>",
            if worse { " class=\"worse\"" } else { "" },
            s.step,
            s.rows,
            f3(s.mean_t1_n),
            fs(s.baseline_mean, 3),
            fs(s.extended_mean, 3),
            fx(s.baseline_rms, 3),
            fx(s.extended_rms, 3),
            s.baseline_nonpositive,
            s.extended_nonpositive,
            fs(s.extended_lowest_n, 2),
            fx(s.measured_lowest_n, 2)
        );
    }
    h.push_str("</table>");
    h
}

/// The extended fit's values with their cluster-robust standard errors, then the cord
/// offsets.
pub fn extended(a: &Analysis) -> String {
    let e = &a.extended;
    let se = |v: f64| fx(v, 5);
    let mut h = String::from("<table><tr><th>value</th><th>estimate</th><th>unit</th><th>cord-jackknife SE (cords as clusters)</th><th>evidence engine SE (runs as clusters)</th><th>note</th></tr>");
    for v in &e.values {
        // As Table 1 gives it: what the data identify (heating's k = h·τ, in 1/N).
        let (name, scale) = crate::parameters::identified(&v.name);
        let (unit, _) = crate::parameters::describe(name);
        let note = v.note.clone() + &crate::parameters::heating_note(name, v.value * scale);
        let _ = write!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            esc(name),
            fx(v.value * scale, 5),
            esc(unit),
            se(v.jackknife_se * scale),
            se(v.run_clustered_se * scale),
            esc(note.trim_start_matches("; "))
        );
    }
    h.push_str("</table>");
    let _ = write!(h, "<p>σ<sub>u</sub> = {} (ln mu), λ = {}; the cord effects count {} effective degrees of freedom, so the model uses {} fixed + {} = {}; population-only RMSE (u = 0) {} N.</p>",
        fx(e.sigma_u, 4), fx(e.lambda, 1), fx(e.edf_random, 2), e.n_fixed, fx(e.edf_random, 2), fx(e.effective_dof, 2), fx(e.rmse_population_t2_n, 3));
    h.push_str("<table><tr><th>cord</th><th>u (ln mu)</th></tr>");
    for (c, u) in &e.cord_log_mu {
        let _ = write!(h, "<tr><td>{}</td><td>{}</td></tr>", esc(c), fs(*u, 4));
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
            "<tr><td>{}</td><td>{}</td><td>{}</td></tr>",
            r.wrap_deg,
            fx(r.r2, 3),
            r.rows
        );
    }
    h.push_str("</table>");
    h
}

/// Table 1: every fitted quantity once ([`crate::parameters`]).
pub fn parameters(a: &Analysis) -> String {
    let mut h = String::from("<table class=\"parameters\"><tr><th>quantity</th><th>estimate of</th><th>value</th><th>SE</th><th>unit</th><th>95 % interval</th><th>how the interval is computed / why two estimates differ</th></tr>");
    for r in crate::parameters::rows(a) {
        let d = crate::cells::se_decimals(r.value, r.se);
        // At the SE's decimals with an SE (0.00788 ± 0.00037), else small values in scientific.
        let show = |x: f64| match r.se {
            Some(_) => fx(x, d),
            None => fs_plain(x, d),
        };
        let ci = match (r.ci95_lo, r.ci95_hi) {
            (Some(lo), Some(hi)) => format!("{} to {}", show(lo), show(hi)),
            _ => "–".into(),
        };
        let _ = write!(
            h,
            "<tr data-key=\"{}\"><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{ci}</td><td>{}</td></tr>",
            esc(&r.key),
            esc(&r.quantity),
            esc(&r.source),
            show(r.value),
            r.se.map_or("–".into(), |se| fx(se, d)),
            esc(r.unit),
            esc(&r.note)
        );
    }
    h.push_str("</table>");
    h
}

/// A value with `d` significant-looking decimals (small values in scientific notation).
fn fs_plain(v: f64, d: usize) -> String {
    if v != 0.0 && v.abs() < 1e-3 {
        fe(v, 2)
    } else {
        fx(v, d)
    }
}
