//! The evidence figures: residuals of the baseline and the extended model, the mechanisms'
//! evidence, and the gain.

use super::{measured, Figure, Palette};
use crate::plot::{bar_chart, figure, finite_range, Bars, Layout, Panel, Series};
use anyhow::Result;
use capstan_engine::analysis::Analysis;
use plotters::style::RGBColor;

/// Residuals of T2 against T1, step and run, for the baseline (top) and the extended model.
pub fn residuals(a: &Analysis, pal: &Palette, layout: &Layout) -> Result<Figure> {
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
    let (run_lo, run_hi) = obs
        .rows
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), r| {
            (a.min(r.op.run), b.max(r.op.run))
        });
    let run_span = (run_hi - run_lo).max(1.0);
    let cord_label = "cord: wrap ° (by diameter)".to_string();
    // Cord labels on the cord axis (every k-th when there are many).
    let every = obs.groups.len().div_ceil(6).max(1);
    let cord_ticks: Vec<(f64, String)> = obs
        .groups
        .iter()
        .enumerate()
        .step_by(every)
        .map(|(g, grp)| (g as f64 + 0.5, format!("{:.0}", grp.wrap_deg)))
        .collect();
    let mut panels = Vec::new();
    for (name, pred) in models {
        for (col, x_label) in [
            ("T1", "T1 (N)"),
            ("step", "step"),
            ("cord", cord_label.as_str()),
        ] {
            let x = |i: usize| {
                let r = &obs.rows[i];
                match col {
                    "T1" => r.t1_n,
                    "step" => r.step.unwrap_or(i as f64),
                    _ => r.group as f64 + 0.15 + 0.7 * (r.op.run - run_lo) / run_span,
                }
            };
            let series = obs
                .groups
                .iter()
                .enumerate()
                .map(|(g, grp)| {
                    let xy = super::drawn(obs.rows_of_group(g))
                        .into_iter()
                        .map(|i| (x(i), resid(pred, i)))
                        .collect();
                    Series::Points(xy, measured(pal.color(grp.wrap_deg)))
                })
                .collect();
            panels.push(Panel {
                title: format!("{name}: by {col}"),
                x_label: x_label.into(),
                y_label: "residual of T2 (N)".into(),
                series,
                zero_line: true,
                y_range: Some(y_range),
                x_ticks: (col == "cord").then(|| cord_ticks.clone()),
                ..Panel::default()
            });
        }
    }
    Ok(Figure {
        id: "residuals",
        legend: pal.legend(),
        chart: { let (c, w, h) = layout.grid(3, 430, 300); figure(&panels, c, w, h)? },
        caption: format!("Residuals of T2 (measured − model) against T1, step and cord, for Euler-Eytelwein (top) and the extended model (bottom), one colour per wrap, on a common scale. Residual = measured T2 − the model's T2. On the cord axis the cords come diameter by diameter (the smallest capstan's first), each labelled by its wrap in degrees (every other label when there are more than six), and each holds its runs from left (first) to right (last). From predictions.csv (t2_n − t2_baseline_n, t2_n − t2_extended_n).{}", super::drawn_note(a)),
    })
}

/// The mechanism evidence: every testable mechanism's evidence on the χ²₁ scale, alone and
/// given the named causes, with the naming threshold of its level.
pub fn mechanisms(a: &Analysis, _pal: &Palette, layout: &Layout) -> Result<Figure> {
    let ev = &a.evidence;
    let testable: Vec<&capstan_engine::evidence::Evidence> = ev.candidates.iter().collect();
    let alone = |name: &str| {
        a.mechanisms
            .get(name)
            .and_then(|m| m.evidence.as_ref())
            .map(|n| n.delta_bic_alone)
    };
    // Evidence for a mechanism is −ΔBIC (ΔBIC below minus the threshold names it).
    let th = &ev.thresholds;
    // The thresholds are ΔBIC values (negative): the line is drawn at −threshold.
    let mut lines = vec![(
        -th.within_run,
        format!("naming threshold within runs: ΔBIC = {:.0}", th.within_run),
    )];
    if (th.between - th.within_run).abs() > 1e-9 {
        lines.push((
            -th.between,
            format!("between cords or runs: ΔBIC = {:.0}", th.between),
        ));
    } else {
        lines[0].1 = format!("naming threshold: ΔBIC = {:.0}", th.within_run);
    }
    let bars = Bars {
        title: "Evidence of each mechanism: −ΔBIC (named above the threshold line of its level)"
            .into(),
        y_label: "−ΔBIC (cluster-robust)".into(),
        categories: testable.iter().map(|e| e.effect.to_string()).collect(),
        groups: vec![
            ("alone".into(), RGBColor(0x99, 0x99, 0x99)),
            ("given the named causes".into(), RGBColor(0x00, 0x72, 0xB2)),
        ],
        values: testable
            .iter()
            .map(|e| vec![alone(e.effect).map(|d| -d), Some(-e.delta_bic)])
            .collect(),
        missing: "–".into(),
        lines,
        decimals: 1,
    };
    let named: Vec<&str> = ev.effects.iter().map(|e| e.effect).collect();
    Ok(Figure {
        id: "mechanism_evidence",
        legend: bars.legend(),
        chart: { let (w, h) = layout.single(1100, 380); bar_chart(&bars, w, h)? },
        caption: format!(
            "The evidence engine's numbers (metrics.json: evidence.candidates, mechanisms[].evidence): each mechanism's −ΔBIC (its quasi-likelihood ratio over its cluster-robust overdispersion, on the BIC scale), added alone to every run's own mu (grey) and given the named causes (blue; for a named cause: dropping it). A mechanism is named when its blue bar rises above the red threshold line of its level; below zero, the data speak against it. Named: {}.",
            if named.is_empty() { "none".to_string() } else { named.join(", ") }
        ),
    })
}

/// The gain: in-sample and leave-one-cord-out RMSE of T2 per model.
pub fn gain(a: &Analysis, layout: &Layout) -> Result<Figure> {
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
        lines: Vec::new(),
        decimals: 3,
    };
    Ok(Figure {
        id: "gain",
        legend: bars.legend(),
        chart: { let (w, h) = layout.single(900, 380); bar_chart(&bars, w, h)? },
        caption: "The gain: in-sample and leave-one-cord-out RMSE of T2 per model. Table 3's published constants are set per angle and cannot be refitted without a cord, so it has no leave-one-cord-out value.".into(),
    })
}
