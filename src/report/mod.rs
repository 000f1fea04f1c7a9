//! The outputs of `capstan analyze`: `metrics.json`, `predictions.csv` and a self-contained
//! `report.html` (inline SVG figures, no external resources).

pub mod plot;

pub use crate::analysis::closed_loop::SimCurve;

use crate::analysis::{Analysis, ModelMetrics};
use crate::data::Dataset;
use plot::{grid, Panel, Series, COLORS};
use serde_json::{json, Value};
use std::fmt::Write as _;

/// The contents of `metrics.json`.
pub fn metrics_json(a: &Analysis, closed_loop: &Value) -> Value {
    let ext = a.models.iter().find(|m| m.name == "extended");
    json!({
        "data": {
            "source": a.source,
            "rows": a.obs.len(),
            "cords": a.obs.groups.len(),
            "runs": a.obs.runs.len(),
            "timing_source": a.obs.timing,
            "timing_note": "Without a time_s column, step k of the thesis protocol starts 10k + 0.5 s after the trigger, its conditioning window (2 s after the change to 1 s before the next) is centred at 10k + 6 s, and it ends at 10k + 10.5 s; the load memory starts at zero at the first kept step of each run.",
        },
        "models": a.models,
        "n_params_note": ext.map(|m| format!(
            "n_params of the extended model counts fixed effects + variance components ({} + {} = {}), the standard mixed-model convention that the ≤ 12 budget uses: the per-cord effects are predicted from one fitted variance, not free. Counted strictly by their effective degrees of freedom ({:.2}), the model uses {:.2}; with the cord effects shrunk until fixed + edf = 12 its in-sample RMSE is {:.3} N.",
            m.n_params_detail.fixed, m.n_params_detail.variance_components, m.n_params, m.n_params_detail.edf_random, m.n_params_strict, a.extended.strict12.rmse_t2_n)),
        "causes": a.mechanisms.causes,
        "mechanisms": a.mechanisms.tests,
        "variants": a.mechanisms.variants,
        "tau_profile": a.mechanisms.tau_profile,
        "intercept_vs_slope": a.mechanisms.intercept_vs_slope,
        "cord_lines": a.mechanisms.cord_lines,
        "residual_patterns": a.residual_patterns,
        "thesis_per_angle_r2": a.thesis_per_angle_r2,
        "extended_fit": a.extended,
        "protocol_limits": a.mechanisms.protocol_limits,
        "closed_loop": closed_loop,
        "elapsed_s": a.elapsed,
    })
}

fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v}")
    } else {
        String::new()
    }
}

/// `predictions.csv`: the input rows (columns as read) plus the cord, the step timing used, and
/// every model's prediction.
pub fn predictions_csv(ds: &Dataset, a: &Analysis) -> String {
    let mut s = String::new();
    let mut header: Vec<String> = ds.header.clone();
    header.extend(
        [
            "cord",
            "window_centre_s",
            "t2_baseline_n",
            "t2_baseline_per_cord_n",
            "t2_thesis_n",
            "t2_extended_n",
            "t2_extended_population_n",
            "t2_baseline_loco_n",
            "t2_baseline_per_cord_loco_n",
            "t2_extended_loco_n",
            "h_extended_ns",
        ]
        .map(String::from),
    );
    let _ = writeln!(s, "{}", header.join(","));
    let p = &a.pred;
    for (i, pair) in ds.pairs.iter().enumerate() {
        let mut cells: Vec<String> = ds
            .header
            .iter()
            .map(|h| match h.as_str() {
                "capstan_diameter_mm" => pair.capstan_diameter_mm.map_or(String::new(), num),
                "wrap_deg" => num(pair.wrap_deg),
                "drive_v" => pair.drive_v.map_or(String::new(), num),
                "run" => pair.run.map_or(String::new(), num),
                "step" => pair.step.map_or(String::new(), num),
                "time_s" => pair.time_s.map_or(String::new(), num),
                "t1_n" => num(pair.t1_n),
                "t2_n" => num(pair.t2_n),
                other => ds
                    .extra_columns
                    .iter()
                    .position(|c| c == other)
                    .map_or(String::new(), |k| num(pair.extra[k])),
            })
            .collect();
        let row = &a.obs.rows[i];
        cells.push(a.obs.groups[row.group].label.clone());
        cells.push(num(row.timing.centre_s));
        for v in [
            p.baseline[i],
            p.baseline_per_cord[i],
            p.thesis[i],
            p.extended[i],
            p.extended_population[i],
            p.baseline_loco[i],
            p.baseline_per_cord_loco[i],
            p.extended_loco[i],
            p.extended_load_memory_ns[i],
        ] {
            cells.push(num(v));
        }
        let _ = writeln!(s, "{}", cells.join(","));
    }
    s
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

fn f3(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.3}")
    } else {
        "–".into()
    }
}

/// Step means (over the runs of a cord) of x and y, in step order.
fn step_means(
    a: &Analysis,
    g: usize,
    x: impl Fn(usize) -> f64,
    y: impl Fn(usize) -> f64,
) -> Vec<(f64, f64)> {
    let mut by_step: std::collections::BTreeMap<i64, (f64, f64, f64)> = Default::default();
    for (i, r) in a.obs.rows.iter().enumerate() {
        if r.group == g {
            let k = r.step.map_or(i as i64, |s| s.round() as i64);
            let e = by_step.entry(k).or_default();
            e.0 += x(i);
            e.1 += y(i);
            e.2 += 1.0;
        }
    }
    let mut v: Vec<(f64, f64)> = by_step.values().map(|(a, b, n)| (a / n, b / n)).collect();
    v.sort_by(|a, b| a.0.total_cmp(&b.0));
    v
}

fn t1_grid(a: &Analysis, g: usize) -> Vec<f64> {
    let hi = a
        .obs
        .rows
        .iter()
        .filter(|r| r.group == g)
        .map(|r| r.t1_n)
        .fold(0.0, f64::max);
    (1..=80).map(|k| hi * k as f64 / 80.0).collect()
}

/// A figure element.
struct Figure {
    id: &'static str,
    svg: String,
    caption: String,
}

fn figures(a: &Analysis, closed_loop: Option<&[SimCurve]>) -> anyhow::Result<Vec<Figure>> {
    let mut figs = Vec::new();
    let obs = &a.obs;
    let mu = a.baseline_fit.model(None).law.mu;
    let diameters: Vec<f64> = {
        let mut d: Vec<f64> = obs.groups.iter().map(|g| g.diameter_mm).collect();
        d.dedup();
        d
    };
    // T2 vs T1 per diameter.
    let mut panels = Vec::new();
    for &dia in &diameters {
        let mut series = Vec::new();
        for (g, grp) in obs
            .groups
            .iter()
            .enumerate()
            .filter(|(_, g)| g.diameter_mm == dia)
        {
            let c = COLORS[g % 5];
            let xy: Vec<(f64, f64)> = obs
                .rows
                .iter()
                .filter(|r| r.group == g)
                .map(|r| (r.t1_n, r.t2_n))
                .collect();
            series.push(Series::Points {
                xy,
                color: c,
                label: format!("{:.0}°", grp.wrap_deg),
                size: 2,
            });
            let beta = grp.wrap_deg.to_radians();
            let grid_t1 = t1_grid(a, g);
            series.push(Series::Line {
                xy: grid_t1
                    .iter()
                    .map(|t| (*t, t * (mu * beta).exp()))
                    .collect(),
                color: c,
                label: String::new(),
                width: 1,
            });
            if crate::analysis::thesis::thesis_amp(grp.wrap_deg, 1.0).is_some() {
                series.push(Series::Line {
                    xy: grid_t1
                        .iter()
                        .map(|t| {
                            (
                                *t,
                                t * crate::analysis::thesis::thesis_amp(grp.wrap_deg, *t)
                                    .unwrap_or(f64::NAN),
                            )
                        })
                        .collect(),
                    color: COLORS[5],
                    label: String::new(),
                    width: 1,
                });
            }
            series.push(Series::Line {
                xy: step_means(a, g, |i| obs.rows[i].t1_n, |i| a.pred.extended[i]),
                color: c,
                label: String::new(),
                width: 3,
            });
        }
        panels.push(Panel {
            title: format!("D = {dia} mm"),
            x_label: "T1 (N)".into(),
            y_label: "T2 (N)".into(),
            series,
            legend: true,
        });
    }
    figs.push(Figure { id: "t2_vs_t1", svg: grid(&panels, 2, 520, 400)?, caption: "T2 against T1, one colour per wrap. Points: measured. Thin line: Euler-Eytelwein (global mu); grey: thesis Table 3; thick: extended model (mean of the cord's runs at each step).".into() });
    // Amplification vs T1 per cord.
    let mut panels = Vec::new();
    for (g, grp) in obs.groups.iter().enumerate() {
        let beta = grp.wrap_deg.to_radians();
        let pts: Vec<(f64, f64)> = obs
            .rows
            .iter()
            .filter(|r| r.group == g)
            .map(|r| (r.t1_n, r.t2_n / r.t1_n))
            .collect();
        let grid_t1 = t1_grid(a, g);
        let mut series = vec![
            Series::Points {
                xy: pts,
                color: COLORS[0],
                label: "measured".into(),
                size: 2,
            },
            Series::Line {
                xy: grid_t1.iter().map(|t| (*t, (mu * beta).exp())).collect(),
                color: COLORS[1],
                label: "Euler-Eytelwein".into(),
                width: 2,
            },
        ];
        if crate::analysis::thesis::thesis_amp(grp.wrap_deg, 1.0).is_some() {
            series.push(Series::Line {
                xy: grid_t1
                    .iter()
                    .map(|t| {
                        (
                            *t,
                            crate::analysis::thesis::thesis_amp(grp.wrap_deg, *t)
                                .unwrap_or(f64::NAN),
                        )
                    })
                    .collect(),
                color: COLORS[5],
                label: "thesis Table 3".into(),
                width: 2,
            });
        }
        series.push(Series::Line {
            xy: step_means(
                a,
                g,
                |i| obs.rows[i].t1_n,
                |i| a.pred.extended[i] / obs.rows[i].t1_n,
            ),
            color: COLORS[3],
            label: "extended".into(),
            width: 2,
        });
        panels.push(Panel {
            title: grp.label.clone(),
            x_label: "T1 (N)".into(),
            y_label: "T2/T1".into(),
            series,
            legend: g == 0,
        });
    }
    figs.push(Figure { id: "amp_vs_t1", svg: grid(&panels, 5, 300, 250)?, caption: "Amplification T2/T1 against T1 per cord (diameter/wrap). Extended: step means over the cord's six runs, with the cord's own mu.".into() });
    // Residuals.
    let mut panels = Vec::new();
    for (name, pred) in [
        ("baseline", &a.pred.baseline),
        ("extended", &a.pred.extended),
    ] {
        for (col, xf) in [("T1 (N)", 0usize), ("step", 1), ("run", 2)] {
            let xy: Vec<(f64, f64)> = obs
                .rows
                .iter()
                .enumerate()
                .map(|(i, r)| {
                    let x = match xf {
                        0 => r.t1_n,
                        1 => r.step.unwrap_or(i as f64),
                        _ => r.op.run + 0.08 * (r.group as f64 - 4.5),
                    };
                    (x, r.t2_n - pred[i])
                })
                .collect();
            panels.push(Panel {
                title: format!("{name}: residual vs {col}"),
                x_label: col.into(),
                y_label: "T2 measured − model (N)".into(),
                series: vec![Series::Points {
                    xy,
                    color: if name == "baseline" {
                        COLORS[1]
                    } else {
                        COLORS[3]
                    },
                    label: String::new(),
                    size: 2,
                }],
                legend: false,
            });
        }
    }
    figs.push(Figure { id: "residuals", svg: grid(&panels, 3, 340, 260)?, caption: "Residuals of T2 (measured − model) against T1, step and run, for the baseline (top) and the extended model (bottom). Run positions are spread by cord.".into() });
    // Intercept against slope.
    let lines = &a.mechanisms.cord_lines;
    let mut series = vec![Series::Points {
        xy: lines.iter().map(|c| (c.slope, c.intercept_n)).collect(),
        color: COLORS[0],
        label: "cords (steps ≥ 5)".into(),
        size: 4,
    }];
    if let (Some(ai), Some(bi)) = (
        a.mechanisms
            .intercept_vs_slope
            .get("a")
            .and_then(Value::as_f64),
        a.mechanisms
            .intercept_vs_slope
            .get("b")
            .and_then(Value::as_f64),
    ) {
        let smin = lines.iter().map(|c| c.slope).fold(f64::INFINITY, f64::min);
        let smax = lines
            .iter()
            .map(|c| c.slope)
            .fold(f64::NEG_INFINITY, f64::max);
        series.push(Series::Line {
            xy: vec![(smin, ai + bi * smin), (smax, ai + bi * smax)],
            color: COLORS[3],
            label: format!("WLS: c = {ai:.2} + {bi:.2}·s"),
            width: 2,
        });
    }
    let mut ev = vec![Panel {
        title: "Intercept vs slope of T2(T1) per cord".into(),
        x_label: "slope s".into(),
        y_label: "intercept c (N)".into(),
        series,
        legend: true,
    }];
    // τ profile.
    ev.push(Panel {
        title: "Profile over the memory time τ".into(),
        x_label: "ln τ (τ in s)".into(),
        y_label: "AIC".into(),
        series: vec![
            Series::Line {
                xy: a
                    .mechanisms
                    .tau_profile
                    .iter()
                    .map(|p| (p.tau_s.ln(), p.aic))
                    .collect(),
                color: COLORS[2],
                label: String::new(),
                width: 2,
            },
            Series::Points {
                xy: a
                    .mechanisms
                    .tau_profile
                    .iter()
                    .map(|p| (p.tau_s.ln(), p.aic))
                    .collect(),
                color: COLORS[2],
                label: String::new(),
                size: 4,
            },
        ],
        legend: false,
    });
    // Low-tension loss by diameter.
    ev.push(Panel {
        title: "Low-tension (T1 < 2 N) ln-amp residual, no e1".into(),
        x_label: "capstan diameter (mm)".into(),
        y_label: "mean ln residual".into(),
        series: vec![Series::Points {
            xy: a
                .mechanisms
                .low_tension_by_cord
                .iter()
                .map(|c| (c.1, c.2))
                .collect(),
            color: COLORS[4],
            label: String::new(),
            size: 4,
        }],
        legend: false,
    });
    // Cord effects.
    ev.push(Panel {
        title: "Per-cord log-mu offsets (extended)".into(),
        x_label: "wrap (deg)".into(),
        y_label: "u (ln mu)".into(),
        series: diameters
            .iter()
            .enumerate()
            .map(|(k, d)| Series::Points {
                xy: obs
                    .groups
                    .iter()
                    .zip(&a.extended_fit.u)
                    .filter(|(g, _)| g.diameter_mm == *d)
                    .map(|(g, u)| (g.wrap_deg, *u))
                    .collect(),
                color: COLORS[k],
                label: format!("D = {d} mm"),
                size: 4,
            })
            .collect(),
        legend: true,
    });
    figs.push(Figure { id: "mechanism_evidence", svg: grid(&ev, 2, 460, 320)?, caption: "Evidence for the mechanisms: intercepts are not zero offsets (they grow with slope, which offsets cannot do); the memory time τ is short; the low-tension loss is not larger on the small capstan (no bending signature); cord-to-cord mu scatter.".into() });
    // Gain.
    let mut gp = Vec::new();
    for (k, m) in a.models.iter().enumerate() {
        gp.push(Series::Points {
            xy: vec![(k as f64, m.rmse_t2_n)],
            color: COLORS[0],
            label: if k == 0 {
                "in-sample RMSE".into()
            } else {
                String::new()
            },
            size: 6,
        });
        if let Some(l) = m.loco_rmse_t2_n {
            gp.push(Series::Points {
                xy: vec![(k as f64, l)],
                color: COLORS[3],
                label: if k == 0 {
                    "leave-one-cord-out RMSE".into()
                } else {
                    String::new()
                },
                size: 6,
            });
        }
    }
    let names: Vec<String> = a
        .models
        .iter()
        .enumerate()
        .map(|(k, m)| format!("{k}={}", m.name))
        .collect();
    figs.push(Figure {
        id: "gain",
        svg: grid(
            &[Panel {
                title: format!("RMSE of T2 by model ({})", names.join(", ")),
                x_label: "model".into(),
                y_label: "RMSE T2 (N)".into(),
                series: gp,
                legend: true,
            }],
            1,
            760,
            300,
        )?,
        caption: "The gain: in-sample and leave-one-cord-out RMSE of T2.".into(),
    });
    if let Some(cl) = closed_loop {
        let mut panels = Vec::new();
        for (g, grp) in obs.groups.iter().enumerate() {
            let pts: Vec<(f64, f64)> = obs
                .rows
                .iter()
                .filter(|r| r.group == g)
                .map(|r| (r.t1_n, r.t2_n / r.t1_n))
                .collect();
            let mut series = vec![Series::Points {
                xy: pts,
                color: COLORS[0],
                label: "measured".into(),
                size: 2,
            }];
            for (k, (cg, sim)) in cl.iter().filter(|(cg, _)| *cg == g).enumerate() {
                let _ = cg;
                series.push(Series::Line {
                    xy: sim.clone(),
                    color: COLORS[3],
                    label: if k == 0 {
                        "simulated (extended plant)".into()
                    } else {
                        String::new()
                    },
                    width: 2,
                });
            }
            panels.push(Panel {
                title: grp.label.clone(),
                x_label: "T1 (N)".into(),
                y_label: "T2/T1".into(),
                series,
                legend: g == 0,
            });
        }
        figs.push(Figure { id: "closed_loop", svg: grid(&panels, 5, 300, 250)?, caption: "Closed loop: the firmware run against the simulated plant with the extended model (per-cord mu, heating, T1-path loss); simulated amplification (lines) over the measured points.".into() });
    }
    Ok(figs)
}

fn model_row(m: &ModelMetrics) -> String {
    format!(
        "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{:.1}</td><td>{:.1}</td><td>{}</td></tr>",
        esc(&m.name),
        if m.n_params_strict != m.n_params { format!("{} (strict {:.1})", m.n_params, m.n_params_strict) } else { format!("{}", m.n_params) },
        f3(m.rmse_t2_n),
        f3(m.rmse_ln_amp),
        m.loco_rmse_t2_n.map_or("not refittable".into(), f3),
        f3(m.per_cord_r2_amp_median),
        m.aic,
        m.bic,
        m.per_cord_r2_amp.iter().map(|c| format!("{:.2}", c.r2)).collect::<Vec<_>>().join(" "),
    )
}

/// The self-contained HTML report.
pub fn report_html(
    a: &Analysis,
    closed_loop: Option<&[SimCurve]>,
    closed_loop_note: &str,
) -> anyhow::Result<String> {
    let figs = figures(a, closed_loop)?;
    let get = |n: &str| a.models.iter().find(|m| m.name == n);
    let mut h = String::new();
    h.push_str("<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>Capstan analysis</title><style>body{font-family:sans-serif;max-width:1600px;margin:1em auto;padding:0 1em;color:#222}table{border-collapse:collapse;margin:.5em 0}td,th{border:1px solid #ccc;padding:3px 7px;font-size:13px;text-align:left}th{background:#f3f3f3}figure{margin:1em 0}figure svg{max-width:100%;height:auto}.verdict-ruled_in{color:#080;font-weight:bold}.verdict-ruled_out{color:#a00}.note{background:#f8f8f0;padding:.5em 1em;border-left:3px solid #cc9}</style></head><body>");
    let _ = write!(h, "<h1>Capstan friction: what Euler-Eytelwein gets wrong on this rig</h1><p>Data: {} ({} pairs, {} cords, {} runs). Every number below is computed by <code>capstan analyze</code> from these data; the only typed-in numbers are the thesis's published Table 3 constants.</p>", esc(&a.source), a.obs.len(), a.obs.groups.len(), a.obs.runs.len());
    // Headline.
    if let (Some(b), Some(e)) = (get("baseline"), get("extended")) {
        let t = get("thesis");
        let _ = write!(h, "<h2>Headline</h2><ul><li>Euler-Eytelwein with one fitted mu = {:.4}: RMSE of T2 {:.3} N, leave-one-cord-out {:.3} N.</li>", a.baseline_fit.model(None).law.mu, b.rmse_t2_n, b.loco_rmse_t2_n.unwrap_or(f64::NAN));
        if let Some(t) = t {
            let _ = write!(h, "<li>The thesis's Table 3 double exponential ({} hand-set numbers): RMSE {:.3} N; it cannot predict a new cord.</li>", t.n_params, t.rmse_t2_n);
        }
        let _ = write!(h, "<li>The extended model ({} fitted values: {} fixed + {} variance component; strictly {:.1} with the cord effects' effective dof): RMSE {:.3} N in-sample, {:.3} N leave-one-cord-out.</li>", e.n_params, e.n_params_detail.fixed, e.n_params_detail.variance_components, e.n_params_strict, e.rmse_t2_n, e.loco_rmse_t2_n.unwrap_or(f64::NAN));
        let causes: Vec<String> = a
            .mechanisms
            .causes
            .iter()
            .map(|c| format!("<b>{}</b>: {}", esc(&c.name), esc(&c.description)))
            .collect();
        let _ = write!(h, "<li>Named causes: {}.</li></ul>", causes.join("; "));
    }
    // Gain table.
    h.push_str("<h2>The gain</h2><table><tr><th>model</th><th>fitted values</th><th>RMSE T2 (N)</th><th>RMSE ln(T2/T1)</th><th>LOCO RMSE T2 (N)</th><th>median per-cord R² amp</th><th>AIC</th><th>BIC</th><th>per-cord R² of amplification</th></tr>");
    for m in &a.models {
        h.push_str(&model_row(m));
    }
    h.push_str("</table>");
    for m in &a.models {
        let _ = write!(
            h,
            "<p><b>{}</b>: {} (count: {}).</p>",
            esc(&m.name),
            esc(&m.description),
            esc(m.n_params_detail.rule)
        );
    }
    if let Some(e) = get("extended") {
        let _ = write!(h, "<p class=\"note\">Parameter count. The ≤ 12 budget is read with the standard mixed-model convention: fixed effects ({}) plus variance components ({}), {} in all; the ten per-cord offsets are predictions governed by one fitted variance, not free values. Counted strictly by their effective degrees of freedom ({:.2}), the model uses {:.2} values; shrinking the cord effects until fixed + edf = 12 gives an in-sample RMSE of {:.3} N (λ = {:.0}), {} 0.80 N. AIC/BIC in the table use the mixed count; with the strict count AIC = {:.1}, BIC = {:.1}.</p>",
            e.n_params_detail.fixed, e.n_params_detail.variance_components, e.n_params, e.n_params_detail.edf_random, e.n_params_strict, a.extended.strict12.rmse_t2_n, a.extended.strict12.lambda,
            if a.extended.strict12.rmse_t2_n <= 0.80 { "within" } else { "just above" }, e.aic_strict, e.bic_strict);
    }
    let mut figs_iter = figs.iter();
    let mut fig = |h: &mut String, id: &str| {
        if let Some(f) = figs_iter.by_ref().find(|f| f.id == id) {
            let _ = write!(
                h,
                "<figure class=\"plot\" data-figure=\"{}\">{}<figcaption>{}</figcaption></figure>",
                f.id,
                f.svg,
                esc(&f.caption)
            );
        }
    };
    fig(&mut h, "t2_vs_t1");
    fig(&mut h, "amp_vs_t1");
    // What is wrong.
    h.push_str("<h2>What Euler-Eytelwein gets wrong</h2><p>Residual trends against every column (Spearman ρ; slope per SD with cord-clustered t; η² of the column's levels with its F test, which treats rows as independent).</p><table><tr><th>model</th><th>residual</th><th>column</th><th>ρ</th><th>slope/SD</th><th>t (cluster)</th><th>p (cluster)</th><th>η²</th><th>F</th><th>p (F)</th></tr>");
    for p in &a.residual_patterns {
        let _ = write!(h, "<tr><td>{}</td><td>{}</td><td>{}</td><td>{:.3}</td><td>{:.4}</td><td>{:.2}</td><td>{:.3}</td><td>{:.3}</td><td>{:.1}</td><td>{:.2e}</td></tr>", p.model, p.residual, esc(&p.column), p.spearman_rho, p.slope_per_sd, p.slope_t_cluster, p.slope_p_cluster, p.eta2, p.f, p.f_p);
    }
    h.push_str("</table>");
    fig(&mut h, "residuals");
    // Why.
    h.push_str("<h2>Why: the mechanisms</h2><table><tr><th>mechanism</th><th>verdict</th><th>evidence</th><th>rule</th></tr>");
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
    h.push_str("</table><h3>Nested variants (ΔAIC against the reference; negative = better)</h3><table><tr><th>variant</th><th>reference</th><th>values</th><th>RMSE T2</th><th>RMSE ln amp</th><th>ΔAIC</th><th>ΔBIC</th><th>fitted</th></tr>");
    for v in &a.mechanisms.variants {
        let vals: Vec<String> = v
            .values
            .iter()
            .map(|(k, x)| format!("{k} = {x:.4}"))
            .collect();
        let _ = write!(h, "<tr><td>{}</td><td>{}</td><td>{}</td><td>{:.3}</td><td>{:.3}</td><td>{:+.1}</td><td>{:+.1}</td><td>{}</td></tr>", esc(&v.description), esc(&v.reference), v.n_params, v.rmse_t2_n, v.rmse_ln_amp, v.delta_aic, v.delta_bic, esc(&vals.join(", ")));
    }
    h.push_str("</table>");
    fig(&mut h, "mechanism_evidence");
    // Extended model.
    h.push_str("<h2>The extended model</h2><p>T1 = T1<sub>measured</sub> − e1 (a T1-path loss; a reading below e1 is a slack cord); mu = mu0·exp(q·(β − 3π))·exp(u<sub>cord</sub>)·exp(−h·H); T2 = T1·exp(mu·β), solved at each step with H the friction-load memory (dH/dt = (T2 − T1) − H/τ, carried along the run with the protocol's step timing); u<sub>cord</sub> ~ N(0, σ<sub>u</sub>²), fitted by penalised least squares with λ = σ²/σ<sub>u</sub>² re-estimated (Levenberg-Marquardt, analytic-sensitivity Jacobian). All predictions go through <code>capstan_friction::FrictionLaw::t2_n</code>, the same law the simulator runs.</p><table><tr><th>value</th><th>estimate</th><th>Gauss-Newton SE</th><th>jackknife SE (LOCO)</th></tr>");
    for ((k, v), (_, se)) in a.extended.values.iter().zip(&a.extended.standard_errors) {
        let jk = a
            .extended
            .jackknife_se
            .iter()
            .find(|x| &x.0 == k)
            .map_or(f64::NAN, |x| x.1);
        let _ = write!(
            h,
            "<tr><td>{k}</td><td>{v:.5}</td><td>{}</td><td>{}</td></tr>",
            if se.abs() < 1e3 {
                format!("{se:.5}")
            } else {
                "unidentified alone".into()
            },
            if jk.is_finite() {
                format!("{jk:.5}")
            } else {
                "–".into()
            }
        );
    }
    let hj = a
        .extended
        .jackknife_se
        .iter()
        .find(|x| x.0 == "heat_per_ns*heat_tau_s")
        .map_or(f64::NAN, |x| x.1);
    let _ = write!(h, "<tr><td>h·τ (1/N)</td><td>{:.5}</td><td></td><td>{hj:.5}</td></tr></table><p>σ<sub>u</sub> = {:.4} (ln mu), λ = {:.1}, edf of the cord effects {:.2}; population-only RMSE (u = 0) {:.3} N. h and τ trade off when τ is short; their product (steady-state ln-mu loss per newton of friction load) is what the data fix: mu × {:.3} at T2 − T1 = 40 N.</p>",
        a.extended.heat_per_n_steady, a.extended.sigma_u, a.extended.lambda, a.extended.edf_random, a.extended.rmse_population_t2_n, a.extended.mu_factor_at_40n_load);
    h.push_str("<table><tr><th>cord</th><th>u (ln mu)</th></tr>");
    for (c, u) in &a.extended.cord_log_mu {
        let _ = write!(h, "<tr><td>{}</td><td>{u:+.4}</td></tr>", esc(c));
    }
    h.push_str("</table>");
    // Thesis R².
    h.push_str("<h2>The thesis's R² of amplification, reproduced</h2><p>Table 3 applied per angle, R² = 1 − SS<sub>res</sub>/SS<sub>tot</sub> of T2/T1 with both diameters pooled (the definition that reproduces the thesis's range, negative up to about 0.69).</p><table><tr><th>angle (deg)</th><th>R²</th><th>rows</th></tr>");
    for r in &a.thesis_per_angle_r2 {
        let _ = write!(
            h,
            "<tr><td>{}</td><td>{:.3}</td><td>{}</td></tr>",
            r.wrap_deg, r.r2, r.rows
        );
    }
    h.push_str("</table>");
    // Protocol limits.
    h.push_str("<h2>What this protocol cannot separate</h2><ul>");
    for l in &a.mechanisms.protocol_limits {
        let _ = write!(h, "<li>{}</li>", esc(l));
    }
    h.push_str("</ul>");
    fig(&mut h, "gain");
    h.push_str("<h2>Closed loop</h2>");
    let _ = write!(h, "<p>{}</p>", esc(closed_loop_note));
    fig(&mut h, "closed_loop");
    let _ = write!(h, "<h2>Reproducing</h2><p><code>predictions.csv</code> holds the input rows, the cord, the window centre used for the load memory and every model's in-sample and leave-one-cord-out prediction; <code>metrics.json</code> every number of this page. Timing: fits {:.3} s, LOCO {:.3} s, mechanisms {:.3} s, closed loop {:.3} s.</p></body></html>", a.elapsed.fits_s, a.elapsed.loco_s, a.elapsed.mechanisms_s, a.elapsed.closed_loop_s);
    Ok(h)
}
