//! The evidence figures: residuals of the baseline and the extended model, the mechanisms'
//! evidence, and the gain.

use super::{measured, model_label, Figure, Palette};
use crate::error::Result;
use crate::plot::{bar_chart, figure, finite_range, Bars, Layout, Panel, Series};
use capstan_engine::analysis::Analysis;
use plotters::style::RGBColor;

/// Residuals of T2 against T1, step and cord, for the baseline and the extended model: a row
/// per model where three columns fit, a column per model where two do, else one under the
/// other; the caption says which.
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
    let cord_label = "cord, by capstan diameter (mm)".to_string();
    // The cord axis names the diameters, at the middle of each one's cords (the colours name
    // the wraps); the layout keeps every k-th where the names would collide.
    let cord_ticks: Vec<(f64, String)> = obs
        .diameters()
        .iter()
        .filter_map(|d| {
            let at: Vec<f64> = (obs.groups.iter().enumerate())
                .filter(|(_, grp)| grp.diameter_mm == *d)
                .map(|(g, _)| g as f64 + 0.5)
                .collect();
            (!at.is_empty()).then(|| (at.iter().sum::<f64>() / at.len() as f64, format!("{d}")))
        })
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
                title: format!("{name}, by\u{a0}{col}"),
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
    let (cols, w, h) = layout.grid(3, 430, 300);
    let (panels, first, second) = arranged(panels, cols);
    Ok(Figure {
        id: "residuals",
        legend: pal.legend(),
        chart: figure(&panels, cols, w, h)?,
        caption: format!("Residuals of T2 (measured − model) against T1, step and cord, for Euler-Eytelwein ({}) and the extended model ({}), one colour per wrap, on a common scale. Residual = measured T2 − the model's T2. On the cord axis the cords come diameter by diameter (the smallest capstan's first; the ticks name the diameters), coloured by wrap, and each cord holds its runs from left (first) to right (last). From predictions.csv (t2_n − t2_baseline_n, t2_n − t2_extended_n).{}", first, second, super::drawn_note(a)),
    })
}

/// The six residual panels (model by model) for `cols` columns: a row per model with three, a
/// column per model with two, one under the other with one; and where each model's panels are.
fn arranged(panels: Vec<Panel>, cols: usize) -> (Vec<Panel>, &'static str, &'static str) {
    match cols {
        3 => (panels, "top row", "bottom row"),
        2 => {
            let mut by: Vec<Option<Panel>> = panels.into_iter().map(Some).collect();
            let order = [0, 3, 1, 4, 2, 5];
            let p = order.iter().filter_map(|&k| by[k].take()).collect();
            (p, "left column", "right column")
        }
        _ => (panels, "first three panels", "last three"),
    }
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
    // The thresholds are ΔBIC values (negative): the line is drawn at −threshold, and named in
    // the axis's quantity (−ΔBIC = 6, not ΔBIC = −6 on an axis of −ΔBIC).
    let minus = |v: f64| format!("{:.0}", -v).replace('-', "−");
    let mut lines = vec![(
        -th.within_run,
        format!(
            "naming threshold within runs (−ΔBIC = {})",
            minus(th.within_run)
        ),
    )];
    if (th.between - th.within_run).abs() > 1e-9 {
        lines.push((
            -th.between,
            format!(
                "naming threshold between cords or runs (−ΔBIC = {})",
                minus(th.between)
            ),
        ));
    } else {
        lines[0].1 = format!("naming threshold (−ΔBIC = {})", minus(th.within_run));
    }
    let bars = Bars {
        title: "Evidence of each mechanism".into(),
        value_label: "evidence, −ΔBIC (cluster-robust)".into(),
        categories: testable
            .iter()
            .map(|e| e.kind.entry().label.to_string())
            .collect(),
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
    let named: Vec<&str> = ev
        .effects
        .iter()
        .filter_map(|e| capstan_physics::EffectKind::from_name(e.effect))
        .map(|k| k.entry().label)
        .collect();
    Ok(Figure {
        id: "mechanism_evidence",
        legend: bars.legend(),
        chart: bar_chart(&bars, layout.single(1100, 380).0)?,
        caption: format!(
            "The evidence engine's numbers (metrics.json: evidence.candidates, mechanisms[].evidence): each mechanism's −ΔBIC (its quasi-likelihood ratio over its cluster-robust overdispersion, on the BIC scale), added alone to every run's own mu (grey) and given the named causes (blue; for a named cause: dropping it). A mechanism is named when its blue bar reaches past the red dashed threshold line of its level; a bar left of zero means the data speak against it. Named: {}.",
            if named.is_empty() { "none".to_string() } else { named.join(", ") }
        ),
    })
}

/// The gain: in-sample and leave-one-cord-out RMSE of T2 per model.
pub fn gain(a: &Analysis, layout: &Layout) -> Result<Figure> {
    let bars = Bars {
        title: "RMSE of T2 by model".into(),
        value_label: "RMSE of T2 (N)".into(),
        // "one mu" and "a mu per cord" stay together when a narrow figure wraps the name.
        categories: (a.models.iter())
            .map(|m| {
                model_label(&m.name)
                    .replace("one mu", "one\u{a0}mu")
                    .replace("a mu per cord", "a\u{a0}mu\u{a0}per\u{a0}cord")
            })
            .collect(),
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
        chart: bar_chart(&bars, layout.single(900, 380).0)?,
        caption: "The gain: in-sample and leave-one-cord-out RMSE of T2 per model. Table 3's published constants are set per angle and cannot be refitted without a cord, so it has no leave-one-cord-out value.".into(),
    })
}
