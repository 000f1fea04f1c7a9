//! The evidence figures: residuals of the baseline and the extended model, the mechanism
//! evidence (intercepts, memory time, low-tension loss, cord effects), and the gain.

use super::{cord_marker, diameter_legend, measured, Figure, Palette, INK};
use crate::analysis::Analysis;
use crate::report::plot::{
    bar_chart, figure, finite_range, Bars, Dash, Entry, Key, LineStyle, Panel, Series,
};
use anyhow::Result;
use plotters::style::RGBColor;
use serde_json::Value;

/// Residuals of T2 against T1, step and run, for the baseline (top) and the extended model.
pub fn residuals(a: &Analysis, pal: &Palette) -> Result<Figure> {
    let obs = &a.obs;
    let models = [
        ("Euler-Eytelwein", &a.pred.baseline),
        ("extended", &a.pred.extended),
    ];
    let resid = |pred: &[f64], i: usize| obs.rows[i].t2_n - pred[i];
    // One y range for all panels, so that the two models compare at a glance.
    let y_range = finite_range(
        models
            .iter()
            .flat_map(|(_, p)| (0..obs.len()).map(move |i| resid(p, i))),
    );
    let ng = obs.groups.len().max(1) as f64;
    let mut panels = Vec::new();
    for (name, pred) in models {
        for (col, x_label) in [
            ("T1", "T1 (N)"),
            ("step", "step"),
            ("run", "run (spread by cord)"),
        ] {
            let x = |i: usize| {
                let r = &obs.rows[i];
                match col {
                    "T1" => r.t1_n,
                    "step" => r.step.unwrap_or(i as f64),
                    _ => r.op.run + 0.5 * (r.group as f64 + 0.5 - ng / 2.0) / ng,
                }
            };
            let series = obs
                .groups
                .iter()
                .enumerate()
                .map(|(g, grp)| {
                    let xy = obs
                        .rows_of_group(g)
                        .into_iter()
                        .map(|i| (x(i), resid(pred, i)))
                        .collect();
                    Series::Points(xy, measured(pal.color(grp.wrap_deg)))
                })
                .collect();
            panels.push(Panel {
                title: format!("{name}: residual against {col}"),
                x_label: x_label.into(),
                y_label: "T2 measured − model (N)".into(),
                series,
                zero_line: true,
                y_range: Some(y_range),
                ..Panel::default()
            });
        }
    }
    Ok(Figure {
        id: "residuals",
        legend: pal.legend(),
        chart: figure(&panels, 3, 430, 300)?,
        caption: "Residuals of T2 (measured − model) against T1, step and run, for Euler-Eytelwein (top) and the extended model (bottom), one colour per wrap, on a common scale. Run positions are spread by cord. From predictions.csv (t2_n − t2_baseline_n, t2_n − t2_extended_n).".into(),
    })
}

fn num(v: &Value, k: &str) -> Option<f64> {
    v.get(k).and_then(Value::as_f64)
}

/// Points per cord coloured by wrap, a disc on the smallest capstan and a ring on the others.
fn cord_points(
    a: &Analysis,
    pal: &Palette,
    pts: impl Iterator<Item = (usize, f64, f64)>,
) -> Vec<Series> {
    let small = a.obs.diameters().first().copied().unwrap_or(f64::NAN);
    pts.map(|(g, x, y)| {
        let grp = &a.obs.groups[g];
        Series::Points(
            vec![(x, y)],
            cord_marker(pal.color(grp.wrap_deg), grp.diameter_mm != small),
        )
    })
    .collect()
}

fn group_of(a: &Analysis, label: &str) -> usize {
    a.obs
        .groups
        .iter()
        .position(|g| g.label == label)
        .unwrap_or(0)
}

/// The mechanism evidence: four panels.
pub fn mechanisms(a: &Analysis, pal: &Palette) -> Result<Figure> {
    let m = &a.mechanisms;
    let annotation = |width, dash| LineStyle {
        color: INK,
        width,
        dash,
    };
    // Intercept against slope, with the weighted line.
    let mut series = cord_points(
        a,
        pal,
        m.cord_lines
            .iter()
            .map(|c| (group_of(a, &c.cord), c.slope, c.intercept_n)),
    );
    let mut legend = Vec::new();
    if let (Some(ai), Some(bi)) = (
        num(&m.intercept_vs_slope, "a"),
        num(&m.intercept_vs_slope, "b"),
    ) {
        let (lo, hi) = finite_range(m.cord_lines.iter().map(|c| c.slope));
        series.push(Series::Line(
            vec![(lo, ai + bi * lo), (hi, ai + bi * hi)],
            annotation(2, Dash::Dashed),
        ));
        legend.push(Entry {
            key: Key::Line(annotation(2, Dash::Dashed)),
            label: format!("weighted fit c = {ai:.2} + {bi:.2}·s"),
        });
    }
    let isl = Panel {
        title: "Intercept against slope of T2(T1), steps ≥ 5".into(),
        x_label: "slope s of T2 = c + s·T1".into(),
        y_label: "intercept c (N)".into(),
        series,
        legend,
        ..Panel::default()
    };
    // Profile over τ (x: ln τ, labelled in s).
    let prof: Vec<(f64, f64)> = m
        .tau_profile
        .iter()
        .map(|p| (p.tau_s.ln(), p.aic))
        .collect();
    let tau_fit = a.extended_fit.model(None).law.heat_tau_s;
    let (ylo, yhi) = finite_range(prof.iter().map(|p| p.1));
    let tau = Panel {
        title: "Profile over the load-memory time τ".into(),
        x_label: "τ (s, log scale)".into(),
        y_label: "AIC (lower is better)".into(),
        series: vec![
            Series::Line(prof.clone(), annotation(2, Dash::Solid)),
            Series::Points(prof, cord_marker(INK, false)),
            Series::Line(
                vec![(tau_fit.ln(), ylo), (tau_fit.ln(), yhi)],
                annotation(2, Dash::Dashed),
            ),
        ],
        legend: vec![Entry {
            key: Key::Line(annotation(2, Dash::Dashed)),
            label: format!("fitted τ = {tau_fit:.2} s"),
        }],
        x_ticks: Some(
            m.tau_profile
                .iter()
                .map(|p| (p.tau_s.ln(), format!("{}", p.tau_s)))
                .collect(),
        ),
        ..Panel::default()
    };
    // Low-tension loss by diameter, cords spread by wrap.
    let nw = pal.len().max(1) as f64;
    let spread = |d: f64, w: f64| d + 1.2 * (pal.index(w) as f64 - (nw - 1.0) / 2.0) / nw;
    let low = Panel {
        title: "Low-tension (T1 < 2 N) loss without e1, per cord".into(),
        x_label: "capstan diameter (mm)".into(),
        y_label: "mean ln-amp residual".into(),
        series: cord_points(
            a,
            pal,
            m.low_tension_by_cord.iter().map(|(label, d, r)| {
                let g = group_of(a, label);
                (g, spread(*d, a.obs.groups[g].wrap_deg), *r)
            }),
        ),
        x_ticks: Some(
            a.obs
                .diameters()
                .iter()
                .map(|d| (*d, format!("{d}")))
                .collect(),
        ),
        ..Panel::default()
    };
    // Cord effects.
    let u = Panel {
        title: "Per-cord log-mu offsets u (extended)".into(),
        x_label: "wrap (deg)".into(),
        y_label: "u (ln mu)".into(),
        series: cord_points(
            a,
            pal,
            a.extended_fit
                .u
                .iter()
                .enumerate()
                .map(|(g, u)| (g, a.obs.groups[g].wrap_deg, *u)),
        ),
        x_ticks: Some(
            crate::fit::stats::distinct(a.obs.groups.iter().map(|g| g.wrap_deg))
                .into_iter()
                .map(|w| (w, format!("{w:.0}")))
                .collect(),
        ),
        zero_line: true,
        ..Panel::default()
    };
    let mut legend = pal.legend();
    legend.extend(diameter_legend(a));
    Ok(Figure {
        id: "mechanism_evidence",
        legend,
        chart: figure(&[isl, tau, low, u], 2, 560, 360)?,
        caption: "Evidence for the mechanisms, one point per cord (colour: wrap; disc: small capstan, ring: large). Intercepts grow with slope, which zero offsets cannot do; the memory time τ is short; the low-tension loss is not larger on the small capstan (no bending signature); cord-to-cord mu scatter. From metrics.json: cord_lines, intercept_vs_slope, tau_profile, low_tension_by_cord, extended_fit.cord_log_mu.".into(),
    })
}

/// The gain: in-sample and leave-one-cord-out RMSE of T2 per model.
pub fn gain(a: &Analysis) -> Result<Figure> {
    let bars = Bars {
        title: "RMSE of T2 by model".into(),
        y_label: "RMSE of T2 (N)".into(),
        categories: a.models.iter().map(|m| m.name.clone()).collect(),
        groups: vec![
            ("in-sample".into(), RGBColor(0x55, 0x55, 0x55)),
            ("leave one cord out".into(), RGBColor(0x56, 0xB4, 0xE9)),
        ],
        values: a
            .models
            .iter()
            .map(|m| vec![Some(m.rmse_t2_n), m.loco_rmse_t2_n])
            .collect(),
        missing: "not refittable".into(),
    };
    Ok(Figure {
        id: "gain",
        legend: bars.legend(),
        chart: bar_chart(&bars, 900, 380)?,
        caption: "The gain: in-sample and leave-one-cord-out RMSE of T2 per model. Table 3's published constants are set per angle and cannot be refitted without a cord, so it has no leave-one-cord-out value.".into(),
    })
}
