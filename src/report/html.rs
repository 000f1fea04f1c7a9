//! `report.html`: the sections of the report around the tables and figures (self-contained:
//! inline SVG and CSS, no scripts or external resources).

use super::figures::{self, Figure};
use super::plot::{hex, Dash, Entry, Key, DASH, DOT_PERIOD};
use super::tables;
use crate::analysis::closed_loop::SimCurve;
use crate::analysis::Analysis;
use std::fmt::Write as _;

const STYLE: &str = "body{font-family:Helvetica,Arial,sans-serif;max-width:1320px;margin:1em auto;padding:0 1em;color:#222;line-height:1.4}table{border-collapse:collapse;margin:.5em 0}td,th{border:1px solid #ccc;padding:3px 7px;font-size:13px;text-align:left;vertical-align:top}th{background:#f3f3f3}figure{margin:1.2em 0}figure svg.chart{max-width:100%;height:auto}.legend{display:flex;flex-wrap:wrap;gap:6px 22px;margin:0 12px 4px;font-size:12.5px}.legend svg{vertical-align:middle;margin-right:6px}figcaption{font-size:14px;color:#333;margin-top:.3em}.verdict-ruled_in{color:#080;font-weight:bold}.verdict-ruled_out{color:#a00}.note{background:#f8f8f0;padding:.5em 1em;border-left:3px solid #cc9}pre{background:#f6f6f6;padding:.5em;overflow-x:auto}";

/// Escape text for HTML (and SVG).
pub fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// A figure's legend: one row of samples (drawn as the chart draws them) and labels.
fn legend_html(entries: &[Entry]) -> String {
    let mut h = String::from("<div class=\"legend\">");
    for e in entries {
        let key = match e.key {
            Key::Marker(m) => {
                let (c, r) = (hex(m.color), f64::from(m.radius).max(4.5));
                let paint = if m.hollow {
                    format!("fill=\"none\" stroke=\"{c}\" stroke-width=\"1.3\"")
                } else {
                    format!("fill=\"{c}\"")
                };
                format!("<circle cx=\"14\" cy=\"8\" r=\"{r}\" {paint}/>")
            }
            Key::Line(l) => {
                let dash = match l.dash {
                    Dash::Solid => String::new(),
                    Dash::Dashed => format!(" stroke-dasharray=\"{} {}\"", DASH.0, DASH.1),
                    Dash::Dotted => format!(
                        " stroke-dasharray=\"0.1 {}\" stroke-linecap=\"round\"",
                        DOT_PERIOD - 0.1
                    ),
                };
                format!(
                    "<line x1=\"2\" y1=\"8\" x2=\"26\" y2=\"8\" stroke=\"{}\" stroke-width=\"{}\"{dash}/>",
                    hex(l.color),
                    l.width
                )
            }
        };
        let _ = write!(
            h,
            "<span><svg width=\"28\" height=\"16\" aria-hidden=\"true\">{key}</svg>{}</span>",
            esc(&e.label)
        );
    }
    h.push_str("</div>");
    h
}

/// A figure: its legend, its chart (`data-series`: the number of data layers that
/// `scripts/check-report` expects drawn) and its caption.
fn figure_html(h: &mut String, figs: &[Figure], id: &str) {
    if let Some(f) = figs.iter().find(|f| f.id == id) {
        let _ = write!(
            h,
            "<figure class=\"plot\" data-figure=\"{}\" data-series=\"{}\">{}{}<figcaption>{}</figcaption></figure>",
            f.id,
            f.chart.marks,
            legend_html(&f.legend),
            f.chart.svg,
            esc(&f.caption)
        );
    }
}

fn headline(h: &mut String, a: &Analysis) {
    let get = |n: &str| a.models.iter().find(|m| m.name == n);
    let (Some(b), Some(e)) = (get("baseline"), get("extended")) else {
        return;
    };
    let _ = write!(h, "<h2>Headline</h2><ul><li>Euler-Eytelwein with one fitted mu = {:.4}: RMSE of T2 {:.3} N, leave-one-cord-out {:.3} N.</li>", a.baseline_fit.model(None).law.mu, b.rmse_t2_n, b.loco_rmse_t2_n.unwrap_or(f64::NAN));
    if let Some(t) = get("thesis") {
        let _ = write!(h, "<li>The thesis's Table 3 double exponential ({} hand-set numbers): RMSE {:.3} N; it cannot predict a new cord.</li>", t.n_params, t.rmse_t2_n);
    }
    let _ = write!(h, "<li>The extended model ({} fitted values: {} fixed + {} variance component; strictly {:.1} with the cord effects' effective dof): RMSE {:.3} N in-sample, {:.3} N leave-one-cord-out.</li>", e.n_params, e.n_params_detail.fixed, e.n_params_detail.variance_components, e.n_params_strict, e.rmse_t2_n, e.loco_rmse_t2_n.unwrap_or(f64::NAN));
    let causes: Vec<String> = a
        .mechanisms
        .causes
        .iter()
        .map(|c| format!("<b>{}</b>: {}", esc(&c.name), esc(&c.description)))
        .collect();
    let _ = write!(h, "<li>Named causes: {}.</li>", causes.join("; "));
    if let Some(d) = &a.diagnosis {
        let _ = write!(
            h,
            "<li><code>capstan diagnose</code> on the same data: {}.</li>",
            esc(&d.headline)
        );
    }
    h.push_str("</ul>");
}

fn gain_section(h: &mut String, a: &Analysis, figs: &[Figure]) {
    h.push_str("<h2>The gain</h2>");
    h.push_str(&tables::gain(a));
    figure_html(h, figs, "gain");
    for m in &a.models {
        let _ = write!(
            h,
            "<p><b>{}</b>: {} (count: {}).</p>",
            esc(&m.name),
            esc(&m.description),
            esc(m.n_params_detail.rule)
        );
    }
    if let Some(e) = a.models.iter().find(|m| m.name == "extended") {
        let s = &a.extended.strict12;
        let _ = write!(h, "<p class=\"note\">Parameter count. The ≤ 12 budget is read with the standard mixed-model convention: fixed effects ({}) plus variance components ({}), {} in all; the ten per-cord offsets are predictions governed by one fitted variance, not free values. Counted strictly by their effective degrees of freedom ({:.2}), the model uses {:.2} values; shrinking the cord effects until fixed + edf = 12 gives an in-sample RMSE of {:.3} N (λ = {:.0}), {} 0.80 N. AIC/BIC in the table use the mixed count; with the strict count AIC = {:.1}, BIC = {:.1}.</p>",
            e.n_params_detail.fixed, e.n_params_detail.variance_components, e.n_params, e.n_params_detail.edf_random, e.n_params_strict, s.rmse_t2_n, s.lambda,
            if s.rmse_t2_n <= 0.80 { "within" } else { "just above" }, e.aic_strict, e.bic_strict);
    }
}

/// The self-contained HTML report.
pub fn report_html(
    a: &Analysis,
    closed_loop: Option<&[SimCurve]>,
    closed_loop_note: &str,
) -> anyhow::Result<String> {
    let figs = figures::all(a, closed_loop)?;
    let mut h = String::new();
    let _ = write!(h, "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>Capstan analysis</title><style>{STYLE}</style></head><body>");
    let _ = write!(h, "<h1>Capstan friction: what Euler-Eytelwein gets wrong on this rig</h1><p>Data: {} ({} pairs, {} cords, {} runs). Every number below is computed by <code>capstan analyze</code> from these data; the only typed-in numbers are the thesis's published Table 3 constants. Figures: one colour per wrap throughout; dashed lines Euler-Eytelwein, dotted the thesis's Table 3, thick solid the extended model.</p>", esc(&a.source), a.obs.len(), a.obs.groups.len(), a.obs.runs.len());
    headline(&mut h, a);
    gain_section(&mut h, a, &figs);
    h.push_str("<h2>The data against the models</h2>");
    figure_html(&mut h, &figs, "t2_vs_t1");
    figure_html(&mut h, &figs, "amp_vs_t1");
    h.push_str("<h2>What Euler-Eytelwein gets wrong</h2><p>Residual trends against every column (Spearman ρ; slope per SD with cord-clustered t; η² of the column's levels with its F test, which treats rows as independent).</p>");
    h.push_str(&tables::residual_patterns(a));
    figure_html(&mut h, &figs, "residuals");
    h.push_str("<h2>Why: the mechanisms</h2>");
    h.push_str(&tables::mechanisms(a));
    h.push_str("<h3>Nested variants (ΔAIC against the reference; negative = better)</h3>");
    h.push_str(&tables::variants(a));
    figure_html(&mut h, &figs, "mechanism_evidence");
    if let Some(d) = &a.diagnosis {
        super::diagnosis::section(&mut h, d);
    }
    h.push_str("<h2>The extended model</h2><p>T1 = T1<sub>measured</sub> − e1 (a T1-path loss; a reading below e1 is a slack cord); mu = mu0·exp(q·(β − 3π))·exp(u<sub>cord</sub>)·exp(−h·H); T2 = T1·exp(mu·β), solved at each step with H the friction-load memory (dH/dt = (T2 − T1) − H/τ, carried along the run with the protocol's step timing); u<sub>cord</sub> ~ N(0, σ<sub>u</sub>²), fitted by penalised least squares with λ = σ²/σ<sub>u</sub>² re-estimated (Levenberg-Marquardt, analytic-sensitivity Jacobian). All predictions go through <code>capstan_friction::FrictionLaw::t2_n</code>, the same law the simulator runs.</p>");
    h.push_str(&tables::extended(a));
    h.push_str("<h2>The thesis's R² of amplification, reproduced</h2><p>Table 3 applied per angle, R² = 1 − SS<sub>res</sub>/SS<sub>tot</sub> of T2/T1 with both diameters pooled (the definition that reproduces the thesis's range, negative up to about 0.69).</p>");
    h.push_str(&tables::thesis_r2(a));
    h.push_str("<h2>What this protocol cannot separate</h2><ul>");
    for l in &a.mechanisms.protocol_limits {
        let _ = write!(h, "<li>{}</li>", esc(l));
    }
    h.push_str("</ul><h2>Closed loop</h2>");
    let _ = write!(h, "<p>{}</p>", esc(closed_loop_note));
    figure_html(&mut h, &figs, "closed_loop");
    let e = &a.elapsed;
    let _ = write!(h, "<h2>Reproducing</h2><p><code>predictions.csv</code> holds the input rows, the cord, the window centre used for the load memory and every model's in-sample and leave-one-cord-out prediction; <code>metrics.json</code> every number of this page. Timing: fits {:.3} s, LOCO {:.3} s, mechanisms {:.3} s, diagnose {:.3} s, closed loop {:.3} s.</p></body></html>", e.fits_s, e.loco_s, e.mechanisms_s, e.diagnose_s, e.closed_loop_s);
    Ok(h)
}
