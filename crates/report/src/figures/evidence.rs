//! The evidence figures: residuals of the baseline and the extended model, the mechanisms'
//! evidence, and the gain.

use super::{measured, Figure, Palette};
use crate::plot::{bar_chart, figure, finite_range, Bars, Panel, Series};
use anyhow::Result;
use capstan_engine::analysis::Analysis;
use plotters::style::RGBColor;

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
                    let xy = super::drawn(obs.rows_of_group(g))
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
        caption: format!("Residuals of T2 (measured − model) against T1, step and run, for Euler-Eytelwein (top) and the extended model (bottom), one colour per wrap, on a common scale. Run positions are spread by cord. From predictions.csv (t2_n − t2_baseline_n, t2_n − t2_extended_n).{}", super::drawn_note(a)),
    })
}

/// The mechanism evidence: every testable mechanism's evidence on the χ²₁ scale, alone and
/// given the named causes, with the naming threshold of its level.
pub fn mechanisms(a: &Analysis, _pal: &Palette) -> Result<Figure> {
    let ev = &a.evidence;
    let testable: Vec<&capstan_engine::evidence::Evidence> = ev.candidates.iter().collect();
    let alone = |name: &str| {
        a.mechanisms
            .get(name)
            .and_then(|m| m.evidence.as_ref())
            .map(|n| n.delta_bic_alone)
    };
    let n = ev.design.rows as f64;
    // χ² = −ΔBIC + ln N, N the level's units: rows within runs, cords or runs between.
    let chi2 = |dbic: f64, level: capstan_engine::evidence::Level| {
        let units = match level {
            capstan_engine::evidence::Level::WithinRun => n,
            capstan_engine::evidence::Level::BetweenCord => ev.design.cords as f64,
            capstan_engine::evidence::Level::BetweenRun => ev.design.runs as f64,
        };
        (-dbic + units.ln()).max(0.0)
    };
    let bars = Bars {
        title: "Evidence of each mechanism (χ²₁ scale; named when ΔBIC is below the threshold)"
            .into(),
        y_label: "evidence χ² (cluster-robust)".into(),
        categories: testable.iter().map(|e| e.effect.to_string()).collect(),
        groups: vec![
            ("alone".into(), RGBColor(0x99, 0x99, 0x99)),
            ("given the named causes".into(), RGBColor(0x00, 0x72, 0xB2)),
        ],
        values: testable
            .iter()
            .map(|e| {
                vec![
                    alone(e.effect).map(|d| chi2(d, e.level)),
                    Some(chi2(e.delta_bic, e.level)),
                ]
            })
            .collect(),
        missing: "–".into(),
    };
    let named: Vec<&str> = ev.effects.iter().map(|e| e.effect).collect();
    Ok(Figure {
        id: "mechanism_evidence",
        legend: bars.legend(),
        chart: bar_chart(&bars, 1100, 380)?,
        caption: format!(
            "The evidence engine's numbers (metrics.json: evidence.candidates, mechanisms[].evidence): each mechanism's likelihood-ratio evidence over its cluster-robust overdispersion, on the χ²₁ scale, added alone to every run's own mu (grey) and given the named causes (blue; for a named cause: dropping it). Named: {}.",
            if named.is_empty() { "none".to_string() } else { named.join(", ") }
        ),
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
