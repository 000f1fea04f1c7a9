//! `report.html`: the sections of the report around the tables and figures (self-contained:
//! inline SVG and CSS, no scripts or external resources).

use super::cells::{self, esc};
use super::export;
use super::figures::{self, Figure};
use super::tables;
use capstan_engine::analysis::closed_loop::SimCurve;
use capstan_engine::analysis::Analysis;
use std::fmt::Write as _;

pub(crate) const STYLE: &str = "body{font-family:Helvetica,Arial,sans-serif;max-width:1320px;margin:1em auto;padding:0 1em;color:#222;line-height:1.4}table{border-collapse:collapse;margin:.5em 0}td,th{border:1px solid #ccc;padding:3px 7px;font-size:13px;text-align:left;vertical-align:top}th{background:#f3f3f3}figure{margin:1.2em 0}figure svg.chart{max-width:100%;height:auto}.legend{display:flex;flex-wrap:wrap;gap:6px 22px;margin:0 12px 4px;font-size:12.5px}.legend svg{vertical-align:middle;margin-right:6px}figcaption{font-size:14px;color:#333;margin-top:.3em}.verdict-ruled_in{color:#080;font-weight:bold}.verdict-ruled_out{color:#a00}tr.worse td{background:#fbeaea}.unexplained{color:#a50}.note{background:#f8f8f0;padding:.5em 1em;border-left:3px solid #cc9}pre{background:#f6f6f6;padding:.5em;overflow-x:auto}";

/// `page` with the signs of negative numbers in its text set as minus signs
/// ([`cells::minus_signs`]): the text between tags only, and not inside `<style>`, `<code>` or
/// `<pre>` (CSS, commands and file contents keep their hyphens). The page is ours, so every `<`
/// opens a tag (text has it escaped).
pub fn typeset(page: &str) -> String {
    let mut out = String::with_capacity(page.len() + page.len() / 16);
    let mut verbatim = 0usize;
    for (i, part) in page.split('<').enumerate() {
        let (tag, text) = match (i, part.split_once('>')) {
            (0, _) => ("", part),
            (_, None) => {
                out.push('<');
                out.push_str(part);
                continue;
            }
            (_, Some((tag, text))) => (tag, text),
        };
        if i > 0 {
            out.push('<');
            out.push_str(tag);
            out.push('>');
            let name = tag.trim_start_matches('/');
            let name = name.split([' ', '/']).next().unwrap_or("");
            if matches!(name, "style" | "code" | "pre") {
                verbatim = match tag.starts_with('/') {
                    true => verbatim.saturating_sub(1),
                    false => verbatim + 1,
                };
            }
        }
        match verbatim {
            0 => out.push_str(&cells::minus_signs(text)),
            _ => out.push_str(text),
        }
    }
    out
}

/// A figure: the same standalone SVG as its file (legend inside; `data-series`: the number of
/// data layers that `scripts/check-report` expects drawn), numbered, and its caption.
pub(crate) fn figure_html(h: &mut String, figs: &[Figure], id: &str) {
    if let Some((k, f)) = figs.iter().enumerate().find(|(_, f)| f.id == id) {
        let _ = write!(
            h,
            "<figure class=\"plot\" id=\"figure-{}\" data-figure=\"{}\" data-series=\"{}\">{}<figcaption><b>Figure {}.</b> {}</figcaption></figure>",
            k + 1,
            f.id,
            f.chart.marks,
            export::standalone_svg(f, None, None),
            k + 1,
            esc(&f.caption)
        );
    }
}

fn technical_summary(h: &mut String, a: &Analysis) {
    let get = |n: &str| a.models.iter().find(|m| m.name == n);
    let (Some(b), Some(e)) = (get("baseline"), get("extended")) else {
        return;
    };
    let loco = |m: &capstan_engine::analysis::ModelMetrics| {
        m.loco_rmse_t2_uncertainty
            .as_ref()
            .map_or("not refittable".into(), cells::with_ci)
    };
    let _ = write!(h, "<h3>Technical summary</h3><ul><li>Euler-Eytelwein with one fitted mu = {}: RMSE of T2 {} N, leave-one-cord-out {} N (95 % intervals from resampling whole cords).</li>", cells::fx(a.baseline_fit.model(None).law.mu, 4), cells::with_ci(&b.rmse_t2_uncertainty), loco(b));
    if let Some(t) = get("thesis") {
        let _ = write!(h, "<li>The thesis's Table 3 double exponential ({} hand-set numbers): RMSE {} N; it cannot predict a new cord.</li>", t.n_params, cells::fx(t.rmse_t2_n, 3));
    }
    let _ = write!(h, "<li>The extended model ({} parameters: {} fixed values + {} effective degrees of freedom of the cord effects): RMSE {} N in-sample, {} N leave-one-cord-out.</li>", cells::fx(e.n_params, 1), e.n_params_detail.fixed, cells::fx(e.n_params_detail.edf_random, 1), cells::with_ci(&e.rmse_t2_uncertainty), loco(e));
    let better = a.held_out.iter().filter(|c| c.extended_better).count();
    let g = &a.gain;
    if a.held_out.len() < 2 {
        h.push_str("<li>The held-out gain: not computed (leaving one cord out needs two cords or more).</li>");
    } else {
        let _ = write!(h, "<li>The held-out gain (the whole procedure: every cord predicted by the causes chosen and fitted without it, the population-averaged curve): the extended model's leave-one-cord-out RMSE is {} of Euler-Eytelwein's (95 % interval {} to {}: {}; the cord bootstrap's percentile interval, which over-claims at this many cords, {} to {}; cord-jackknife SE {}); it predicts {better} of {} cords better: {}.</li>",
            cells::fx(g.value, 3), cells::fx(g.ci95.lo, 3), cells::fx(g.ci95.hi, 3), esc(&g.method), cells::fx(g.bootstrap_percentile_ci95.lo, 3), cells::fx(g.bootstrap_percentile_ci95.hi, 3), cells::fx(g.jackknife_se, 3), a.held_out.len(), esc(&g.verdict_words()));
    }
    let causes: Vec<String> = a
        .mechanisms
        .causes
        .iter()
        .map(|c| format!("<b>{}</b> ({})", esc(c.name), esc(c.description)))
        .collect();
    let u = &a.mechanisms.unexplained;
    if causes.is_empty() {
        h.push_str("<li>No cause of the catalogue is named.</li>");
    } else if u.flag {
        // As the verdict says: effects that improve the fit are no diagnosis beside structure
        // none of them accounts for.
        let _ = write!(h, "<li>Catalogue effects that improve the fit but do not account for what is left, so they are not a diagnosis: {}.</li>", causes.join("; "));
    } else {
        let _ = write!(h, "<li>Named causes: {}.</li>", causes.join("; "));
    }
    if u.flag {
        let _ = write!(
            h,
            "<li class=\"unexplained\"><b>Unexplained</b>: {}</li>",
            esc(&u.sentence)
        );
    }
    let _ = write!(
        h,
        "<li><code>capstan diagnose</code> on the same data (the same evidence engine): {} \
         (These are the evidence engine's values, every run its own mu; the headline's offset and \
         heating and Table 1's first rows are the extended model's, its cord-to-cord 5.0 % the \
         evidence engine's. Both write heating as \
         heat_per_n = k = h·τ in 1/N, what the data identify; h = k/τ at the catalogue's \
         τ = {} s.)</li>",
        esc(&a.evidence.verdict),
        capstan_physics::HEAT_TAU_S
    );
    h.push_str("</ul>");
}

/// The headline: at most five plain sentences ([`crate::headline`]).
fn headline_html(h: &mut String, a: &Analysis) {
    let hl = crate::headline::headline(a);
    h.push_str("<h2>Headline</h2><p class=\"headline\">");
    h.push_str(&esc(&hl.sentences.join(" ")));
    h.push_str("</p>");
}

/// What the gain's interval says, from its upper end.
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
    h.push_str("<h3>Every cord predicted from the others</h3>");
    h.push_str(&tables::held_out(a));
    if let Some(steps) = &a.ln_amp_by_step {
        let worse: Vec<String> = steps
            .iter()
            .filter(|s| s.extended_rms > s.baseline_rms || s.extended_nonpositive > 0)
            .map(|s| format!("{}", s.step))
            .collect();
        let _ = write!(h, "<h3>Where the extended model is worse: ln-amplification residuals by step</h3><p>The fits are in T2, where a low-tension row weighs little; the logarithm of the amplification shows the low tensions (over the rows where the model's T2 is above zero: a predicted T2 at or below zero has no logarithm and is counted apart). {}</p>",
            if worse.is_empty() {
                "The extended model's ln-amplification residuals are no larger than Euler-Eytelwein's at any step.".to_string()
            } else {
                format!("The extended model's RMS ln-amplification residual is larger than Euler-Eytelwein's, or it predicts T2 at or below zero, at step {} (rows marked).", worse.join(", "))
            });
        h.push_str(&tables::ln_amp_by_step(steps));
    }
}

/// The data's source as the page names it: the file in code font, and "(bundled)" after it
/// in text where the data are the thesis's that the binary carries.
fn source_html(source: &str) -> String {
    match source.strip_suffix(" (bundled)") {
        Some(file) => format!("<code>{}</code> (bundled)", esc(file)),
        None => format!("<code>{}</code>", esc(source)),
    }
}

/// The self-contained HTML report.
pub fn report_html(
    a: &Analysis,
    closed_loop: Option<&[SimCurve]>,
    closed_loop_note: &str,
    ctx: &crate::Context,
) -> crate::error::Result<(String, Vec<Figure>)> {
    let figs = figures::all(a, closed_loop, &ctx.figures.layout())?;
    let mut h = String::new();
    let _ = write!(h, "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>Capstan analysis</title><style>{STYLE}</style></head><body>");
    let _ = write!(h, "<h1>Capstan friction: what Euler-Eytelwein gets wrong on this rig</h1><p>Data: {} ({} pairs, {} cords, {} runs). Every number below is computed by <code>capstan analyze</code> from these data; the only typed-in numbers are the thesis's published Table 3 constants. Figures: one colour per wrap throughout; dashed lines Euler-Eytelwein, dotted the thesis's Table 3, thick solid the extended model. A dash (–) marks a number that is not identified on these data (too few rows, runs or spread for it).</p><p>{}.</p>", source_html(&a.source), a.obs.len(), a.obs.groups.len(), a.obs.runs.len(), esc(&capstan_engine::verdict::words::capitalised(&a.evidence.data.structure.statement)));
    headline_html(&mut h, a);
    technical_summary(&mut h, a);
    h.push_str("<h2>The fitted quantities</h2><p>Table 1: every fitted quantity once, with its unit and 95 % interval; where two estimates of one quantity differ, both rows, with the reason. <code>metrics.json</code> holds the same rows (<code>parameters</code>).</p>");
    h.push_str(&tables::parameters(a));
    gain_section(&mut h, a, &figs);
    h.push_str("<h2>The data against the models</h2>");
    figure_html(&mut h, &figs, "t2_vs_t1");
    figure_html(&mut h, &figs, "amp_vs_t1");
    h.push_str("<h2>What Euler-Eytelwein gets wrong</h2><p>Residual trends against every column (Spearman ρ; slope per SD with cord-clustered t, its p on cords − 1 degrees of freedom and that p Holm-adjusted over the model's tests; η² of the column's levels with its F test, which treats rows as independent: read it with η²).</p>");
    h.push_str(&tables::residual_patterns(a));
    let family = crate::trends::baseline_family(a);
    if !family.is_empty() {
        let _ = write!(h, "<p>{}</p>", esc(&family));
    }
    figure_html(&mut h, &figs, "residuals");
    let ev = &a.evidence;
    let _ = write!(h, "<h2>Why: the mechanisms</h2><p>Every mechanism of the catalogue is judged by the evidence engine that <code>capstan diagnose</code> uses, on these data: every run has its own mu; the effects that change the shape of T2 inside runs are selected forward, each judged by its quasi-likelihood ratio over its cluster-robust overdispersion (runs as clusters, so the serial correlation inside a run and each run's own tare count), referred to F(1, runs − 1) and put on the BIC scale; the effects on mu between cords and runs are judged on the runs' mu with cords or runs as the units. Thresholds: ΔBIC below {:.0} within runs, {:.0} between. Scatter of mu: {} % cord to cord, {} % run to run; noise {} N + {} % of T2; lag-1 autocorrelation of the residuals inside runs {}.</p>",
        ev.thresholds.within_run, ev.thresholds.between, cells::fx(ev.scatter.cord_pct, 1), cells::fx(ev.scatter.run_pct, 1), cells::fx(ev.scatter.noise_abs_n, 3), cells::fx(100.0 * ev.scatter.noise_rel, 1), cells::fx(ev.scatter.lag1_autocorrelation, 2));
    h.push_str(&tables::mechanisms(a));
    figure_html(&mut h, &figs, "mechanism_evidence");
    let u = &a.mechanisms.unexplained;
    let _ = write!(
        h,
        "<h3>What is left</h3><p class=\"note\">{} {}</p>",
        esc(&u.sentence),
        esc(&crate::trends::extended_trends(a))
    );
    let causes: Vec<&str> = a.mechanisms.causes.iter().map(|c| c.name).collect();
    let _ = write!(h, "<h2>The extended model</h2><p>Euler-Eytelwein with the named causes ({}), each through the catalogue's own term in <code>capstan_physics::FrictionLaw</code> and <code>SensorArtefacts</code> (the law the simulator runs), one population mu and a per-cord random log-mu u<sub>cord</sub> ~ N(0, σ<sub>u</sub>²), fitted by penalised least squares with λ = σ²/σ<sub>u</sub>² re-estimated and the cord effects shrunk so that the fixed values plus their effective degrees of freedom stay within {}.</p>",
        if causes.is_empty() { "none".to_string() } else { causes.join(", ") }, capstan_engine::analysis::fits::STRICT_BUDGET);
    h.push_str(&tables::extended(a));
    if !a.thesis_per_angle_r2.is_empty() {
        let r2: Vec<f64> = a.thesis_per_angle_r2.iter().map(|r| r.r2).collect();
        let (lo, hi) = r2.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |x, &v| {
            (x.0.min(v), x.1.max(v))
        });
        let _ = write!(h, "<h2>The thesis's R² of amplification, reproduced</h2><p>{}. Table 3 applied per angle; R² = 1 − SS<sub>res</sub>/SS<sub>tot</sub> of T2/T1 with both diameters pooled, from {} to {} on these data. R² compares the model's error with the spread of the amplification around its mean at that angle: a negative R² means Table 3 predicts that angle's amplification worse than its plain mean would.</p>",
            esc(&capstan_engine::verdict::words::capitalised(&ctx.thesis.why)), cells::f3(lo), cells::f3(hi));
        h.push_str(&tables::thesis_r2(a));
    }
    h.push_str("<h2>What this design cannot separate</h2><ul>");
    for l in &a.mechanisms.protocol_limits {
        let _ = write!(h, "<li>{}</li>", esc(l));
    }
    h.push_str("</ul><h2>Closed loop</h2>");
    let _ = write!(h, "<p>{}</p>", esc(closed_loop_note));
    figure_html(&mut h, &figs, "closed_loop");
    let e = &a.elapsed;
    if !a.fit_notes.is_empty() {
        h.push_str("<h2>Fits that did not converge</h2><p>Every fit has a work budget that grows with the data; these stopped at it, and the analysis went on without them (a leave-one-cord-out fold) or with their last iterate (an in-sample fit):</p><ul>");
        for n in &a.fit_notes {
            let _ = write!(h, "<li>{}</li>", esc(n));
        }
        h.push_str("</ul>");
    }
    let _ = write!(h, "<h2>Reproducing</h2><p><code>predictions.csv</code> holds the input rows, the cord, the window centre used for the load memory and every model's in-sample and leave-one-cord-out prediction; <code>metrics.json</code> every number of this page (its <code>evidence</code> object is what <code>capstan diagnose --json</code> prints; its <code>prediction_model</code> is what <code>capstan predict --from</code> reads). Made by <code>{}</code>. Thesis Table 3 comparison: {}. Timing: evidence {:.3} s, fits {:.3} s, leave-one-cord-out refits {:.3} s, tables {:.3} s, closed loop {:.3} s.</p></body></html>", esc(&ctx.provenance.line()), esc(&ctx.thesis.why), e.evidence_s, e.fits_s, e.loco_s, e.tables_s, e.closed_loop_s);
    Ok((typeset(&h), figs))
}

#[cfg(test)]
mod tests {
    #[test]
    fn signs_in_text_only() {
        let page = "<style>a{margin:-1px}</style><p class=\"x-1\">offset -0.82 N, <code>--seed -1</code> and -2</p><svg><text x=\"-3\">-5</text></svg>";
        assert_eq!(
            super::typeset(page),
            "<style>a{margin:-1px}</style><p class=\"x-1\">offset −0.82 N, <code>--seed -1</code> and −2</p><svg><text x=\"-3\">−5</text></svg>"
        );
    }
}
