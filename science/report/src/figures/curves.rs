//! T2 and amplification against T1 with the three models, and the closed-loop overlay.

use super::{
    as_read_style, baseline_style, extended_style, measured, model_legend, panels_that_fit,
    selection_note, thesis_style, Figure, Palette, INK,
};
use crate::error::Result;
use crate::plot::{figure, Entry, Key, Layout, Panel, Series};
use capstan_engine::analysis::closed_loop::evenly;
use capstan_engine::analysis::closed_loop::SimCurve;
use capstan_engine::analysis::Analysis;
use plotters::style::RGBColor;
use std::collections::BTreeMap;

/// (T1, y(i)) of cord `g`'s rows, sorted by T1: a model that depends on T1 and the cord only
/// (Euler-Eytelwein, Table 3) traces its curve through its predictions.
fn by_t1(a: &Analysis, g: usize, y: impl Fn(usize) -> f64) -> Vec<(f64, f64)> {
    let mut v: Vec<(f64, f64)> = a
        .obs
        .rows_of_group(g)
        .into_iter()
        .map(|i| (a.obs.rows[i].t1_n, y(i)))
        .collect();
    v.sort_by(|p, q| p.0.total_cmp(&q.0));
    super::drawn(v)
}

/// Step means (over the runs of cord `g`) of x and y, in T1 order: the extended model, whose
/// prediction also depends on each run's load history.
fn step_means(a: &Analysis, g: usize, y: impl Fn(usize) -> f64) -> Vec<(f64, f64)> {
    let mut by_step: BTreeMap<i64, (f64, f64, f64)> = BTreeMap::new();
    for i in a.obs.rows_of_group(g) {
        let r = &a.obs.rows[i];
        let e = by_step
            .entry(r.step.map_or(i as i64, |s| s.round() as i64))
            .or_default();
        e.0 += r.t1_n;
        e.1 += y(i);
        e.2 += 1.0;
    }
    let mut v: Vec<(f64, f64)> = by_step.values().map(|(x, y, n)| (x / n, y / n)).collect();
    v.sort_by(|p, q| p.0.total_cmp(&q.0));
    v
}

/// The three models' curves of cord `g` in its wrap's colour; `amp` divides by T1.
fn model_series(a: &Analysis, g: usize, color: RGBColor, amp: bool) -> Vec<Series> {
    let t1 = |i: usize| if amp { a.obs.rows[i].t1_n } else { 1.0 };
    let p = &a.pred;
    let mut s = vec![Series::Line(
        by_t1(a, g, |i| p.baseline[i] / t1(i)),
        baseline_style(color),
    )];
    if a.obs
        .rows_of_group(g)
        .iter()
        .all(|&i| p.thesis[i].is_finite())
    {
        s.push(Series::Line(
            by_t1(a, g, |i| p.thesis[i] / t1(i)),
            thesis_style(color),
        ));
    }
    // The extended model twice: the physics (the friction law alone, sensor terms removed,
    // at the true T1) thick, and what the sensors would read thin.
    s.push(Series::Line(physical(a, g, amp), extended_style(color)));
    s.push(Series::Line(
        step_means(a, g, |i| p.extended[i] / t1(i)),
        as_read_style(color),
    ));
    s
}

/// The extended model's physical curve of cord `g` (its own mu, the friction law alone):
/// (true T1, T2 or T2/T1) at the step means of the cord's runs. The law never lets T2 fall
/// below T1, so the amplification stays at or above 1.
fn physical(a: &Analysis, g: usize, amp: bool) -> Vec<(f64, f64)> {
    let m = a.extended_fit.model(Some(g));
    let mut by_step: BTreeMap<i64, (f64, f64, f64)> = BTreeMap::new();
    for i in a.obs.rows_of_group(g) {
        let r = &a.obs.rows[i];
        let t1 = m.sensors.true_t1_n(r.t1_n);
        if t1.is_nan() || t1 <= 0.0 {
            continue;
        }
        let mut op = r.op;
        op.load_memory_ns = a.pred.extended_load_memory_ns[i];
        let t2 = m.law.t2_n(t1, &op);
        let e = by_step
            .entry(r.step.map_or(i as i64, |s| s.round() as i64))
            .or_default();
        e.0 += t1;
        e.1 += if amp { t2 / t1 } else { t2 };
        e.2 += 1.0;
    }
    let mut v: Vec<(f64, f64)> = by_step.values().map(|(x, y, n)| (x / n, y / n)).collect();
    v.sort_by(|p, q| p.0.total_cmp(&q.0));
    v
}

fn measured_points(a: &Analysis, g: usize, amp: bool) -> Vec<(f64, f64)> {
    super::drawn(a.obs.rows_of_group(g))
        .into_iter()
        .map(|i| {
            let r = &a.obs.rows[i];
            (r.t1_n, if amp { r.t2_n / r.t1_n } else { r.t2_n })
        })
        .collect()
}

fn has_thesis(a: &Analysis) -> bool {
    a.pred.thesis.iter().any(|v| v.is_finite())
}

fn legend(a: &Analysis, pal: &Palette) -> Vec<Entry> {
    let mut l = pal.legend();
    l.extend(model_legend(has_thesis(a)));
    l
}

/// T2 against T1, one panel per capstan diameter (as many as fit a page).
pub fn t2_vs_t1(a: &Analysis, pal: &Palette, layout: &Layout) -> Result<Figure> {
    const X: &str = "T1, servo-side tension (N)";
    let diameters = a.obs.diameters();
    let title = |d: f64| format!("capstan diameter {d}\u{a0}mm");
    let grid = layout.grid(2, 650, 470);
    let legend = legend(a, pal);
    let titles: Vec<String> = diameters.iter().map(|d| title(*d)).collect();
    let refs: Vec<&str> = titles.iter().map(String::as_str).collect();
    let fit = panels_that_fit(layout, grid, &refs, X, &legend);
    let shown = evenly(diameters.len(), fit);
    let mut panels = Vec::new();
    for &k in &shown {
        let dia = diameters[k];
        let mut series = Vec::new();
        for (g, grp) in a.obs.groups.iter().enumerate() {
            if grp.diameter_mm != dia {
                continue;
            }
            let c = pal.color(grp.wrap_deg);
            series.push(Series::Points(measured_points(a, g, false), measured(c)));
            series.extend(model_series(a, g, c, false));
        }
        panels.push(Panel {
            title: title(dia),
            x_label: X.into(),
            y_label: "T2, load-side tension (N)".into(),
            series,
            ..Panel::default()
        });
    }
    share_y(&mut panels);
    let shared = if panels.len() > 1 {
        " The panels share the y-scale."
    } else {
        ""
    };
    Ok(Figure {
        id: "t2_vs_t1",
        legend,
        chart: figure(&panels, grid.0, grid.1, grid.2)?,
        caption: format!("T2 against T1, one panel per capstan diameter, one colour per wrap. Points: measured pairs. Dashed: Euler-Eytelwein with one global mu; dotted: the thesis's Table 3; thick solid: the extended model's friction law alone (its offset and sensor terms removed, against the true T1); thin solid: what the sensors would read under it (mean over the cord's runs at each step, as in predictions.csv).{shared}{}{}", selection_note(shown.len(), diameters.len(), "capstan diameters"), super::drawn_note(a)),
    })
}

/// Amplification T2/T1 against T1, one panel per cord (as many as fit a page).
pub fn amp_vs_t1(a: &Analysis, pal: &Palette, layout: &Layout) -> Result<Figure> {
    let legend = legend(a, pal);
    let titles: Vec<String> = (0..a.obs.groups.len()).map(|g| cord_title(a, g)).collect();
    let refs: Vec<&str> = titles.iter().map(String::as_str).collect();
    let (grid, cords, arranged) =
        match super::cord_grid::cord_table(a, layout, (260, 230), &refs, "T1 (N)", &legend) {
            Some(t) => (t.grid, t.cords, t.note),
            None => {
                let grid = layout.grid(pal.len().clamp(1, 5), 260, 230);
                (grid, panel_cords(a, layout, grid, &legend), "")
            }
        };
    let mut panels: Vec<Panel> = cords
        .iter()
        .map(|&g| {
            let c = pal.color(a.obs.groups[g].wrap_deg);
            amp_panel(a, g, c, model_series(a, g, c, true))
        })
        .collect();
    share_y(&mut panels);
    share_x_by_wrap(a, &cords, &mut panels);
    Ok(Figure {
        id: "amp_vs_t1",
        legend,
        chart: figure(&panels, grid.0, grid.1, grid.2)?,
        caption: format!("Amplification T2/T1 against T1 per cord, one colour per wrap, on one y-scale (the panels of one wrap on one T1 scale too). Points: the measured readings. Dashed: Euler-Eytelwein (one global mu, so a flat line); dotted: Table 3 (thesis data only); thick solid: the extended model's friction law alone (with the cord's own mu, its offset and sensor terms removed, against the true T1), which cannot fall below 1; thin solid: what the sensors would read under the extended model (its fitted offsets included: the T2 offset pulls it below 1 at low T1, and where it predicts T2 at or below zero, below 0, which no reading does: the constant offset does not hold at the lowest tensions). Step means over the cord's runs.{arranged}{}{}", selection_note(cords.len(), a.obs.groups.len(), "cords"), super::drawn_note(a)),
    })
}

/// One x-range for the panels of one wrap (`cords[k]` is panel k's cord): the diameters of a
/// wrap compare at a glance, and a wrap's column of the cord table has one T1 scale.
fn share_x_by_wrap(a: &Analysis, cords: &[usize], panels: &mut [Panel]) {
    let wraps: Vec<u64> = (cords.iter())
        .map(|&g| a.obs.groups[g].wrap_deg.to_bits())
        .collect();
    share_x_by(&wraps, panels);
}

/// One x-range for the panels of one `key` (panel k's is `keys[k]`): the range of all their
/// series' x.
fn share_x_by(keys: &[u64], panels: &mut [Panel]) {
    let ranges: Vec<(f64, f64)> = (keys.iter())
        .map(|key| {
            let same = (panels.iter().zip(keys)).filter(|(_, k)| *k == key);
            let xs = same
                .flat_map(|(p, _)| p.series.iter())
                .flat_map(|s| match s {
                    Series::Points(xy, _) | Series::Line(xy, _) => xy.iter().map(|v| v.0),
                });
            crate::plot::finite_range(xs)
        })
        .collect();
    for (p, r) in panels.iter_mut().zip(ranges) {
        p.x_range = Some(r);
    }
}

/// One y-range for every panel of a figure (the panels compare at a glance).
fn share_y(panels: &mut [Panel]) {
    let range = crate::plot::finite_range(panels.iter().flat_map(|p| p.series.iter()).flat_map(
        |s| match s {
            Series::Points(xy, _) | Series::Line(xy, _) => xy.iter().map(|v| v.1),
        },
    ));
    for p in panels {
        p.y_range = Some(range);
    }
}

/// The most cords drawn one panel each, whatever the page holds.
pub const MAX_CORD_PANELS: usize = 24;

/// The title of cord `g`'s panel.
fn cord_title(a: &Analysis, g: usize) -> String {
    let grp = &a.obs.groups[g];
    format!(
        "{:.0}°, D\u{a0}=\u{a0}{}\u{a0}mm",
        grp.wrap_deg, grp.diameter_mm
    )
}

/// The cords drawn one panel each: all, or as many as fit a page (and
/// [`MAX_CORD_PANELS`]), evenly spaced.
fn panel_cords(
    a: &Analysis,
    layout: &Layout,
    grid: (usize, u32, u32),
    legend: &[Entry],
) -> Vec<usize> {
    let titles: Vec<String> = (0..a.obs.groups.len()).map(|g| cord_title(a, g)).collect();
    let refs: Vec<&str> = titles.iter().map(String::as_str).collect();
    let fit = panels_that_fit(layout, grid, &refs, "T1 (N)", legend).min(MAX_CORD_PANELS);
    evenly(a.obs.groups.len(), fit)
}

/// One cord's amplification panel: its measured points, then `curves` over them.
fn amp_panel(
    a: &Analysis,
    g: usize,
    c: RGBColor,
    curves: impl IntoIterator<Item = Series>,
) -> Panel {
    let mut series = vec![Series::Points(measured_points(a, g, true), measured(c))];
    series.extend(curves);
    Panel {
        title: cord_title(a, g),
        x_label: "T1 (N)".into(),
        y_label: "amplification T2/T1".into(),
        series,
        ..Panel::default()
    }
}

/// The named causes the closed-loop plant carries, as a caption fragment (", a, b").
fn plant_causes(a: &Analysis) -> String {
    a.mechanisms
        .causes
        .iter()
        .map(|c| format!(", {}", c.name))
        .collect()
}

/// A cord's largest T1 and largest T2, N.
type Tops = (f64, f64);

/// Where the simulated runs end short of the measured T1 (below 90 % of the cord's largest), a
/// caption sentence that says so and why: one cord spring for every cord, fitted to the
/// thesis's mean T1 per step and wrap with T2 kept under the firmware's over-force limit
/// (`sim/plant`'s `CordConfig`), which some of the thesis's cords exceeded; so at the servo's
/// last angle the plant reaches less T1 than the largest the rig measured on the cord.
fn short_note(a: &Analysis, curves: &[SimCurve], shown: &[usize]) -> String {
    let top = |v: &mut dyn Iterator<Item = f64>| v.fold(0.0f64, f64::max);
    // Per cord shown: its largest simulated and measured (T1, T2), N.
    let short: Vec<(usize, Tops, Tops)> = shown
        .iter()
        .filter_map(|&g| {
            let sim = || {
                curves
                    .iter()
                    .filter(|(cg, _)| *cg == g)
                    .flat_map(|(_, v)| v)
            };
            let sim = (
                top(&mut sim().map(|p| p.0)),
                top(&mut sim().map(|p| p.0 * p.1)),
            );
            let rows = || a.obs.rows_of_group(g).into_iter().map(|i| &a.obs.rows[i]);
            let measured = (
                top(&mut rows().map(|r| r.t1_n)),
                top(&mut rows().map(|r| r.t2_n)),
            );
            (sim.0 > 0.0 && sim.0 < 0.9 * measured.0).then_some((g, sim, measured))
        })
        .collect();
    let Some(&(g, sim, measured)) = short
        .iter()
        .min_by(|x, y| (x.1 .0 / x.2 .0).total_cmp(&(y.1 .0 / y.2 .0)))
    else {
        return String::new();
    };
    format!(
        " At {} of the {} cords shown the simulated run ends short of the measured T1, below 90 % of the largest T1 measured on the cord (most at {}: T1 {:.1} N of {:.1} N, T2 {:.1} N of {:.1} N). The runs step the servo through the thesis's angles against one cord spring for every cord, fitted to the thesis's mean T1 per step and wrap (pooled over diameters and runs) with T2 kept under the firmware's over-force limit at 720°, which some of the rig's cords exceeded: so at the last angle the plant reaches less T1 than the largest the rig measured, the more so the more the capstan amplifies.",
        short.len(),
        shown.len(),
        cord_title(a, g),
        sim.0,
        measured.0,
        sim.1,
        measured.1
    )
}

/// The closed loop: simulated amplification over the measured points, per cord (as many as fit
/// a page).
pub fn closed_loop(
    a: &Analysis,
    pal: &Palette,
    curves: &[SimCurve],
    layout: &Layout,
) -> Result<Figure> {
    let mut legend = pal.legend();
    legend.push(Entry {
        key: Key::Line(extended_style(INK)),
        label: "closed-loop simulation (firmware + extended plant)".into(),
    });
    let mut simulated: Vec<usize> = curves.iter().map(|(g, _)| *g).collect();
    simulated.dedup();
    let titles: Vec<String> = simulated.iter().map(|&g| cord_title(a, g)).collect();
    let refs: Vec<&str> = titles.iter().map(String::as_str).collect();
    // Every cord simulated: laid out as figure 3 lays them out (the experiment's table).
    let table = (simulated.len() == a.obs.groups.len())
        .then(|| super::cord_grid::cord_table(a, layout, (260, 230), &refs, "T1 (N)", &legend))
        .flatten();
    let (grid, shown, arranged) = match table {
        Some(t) => (t.grid, t.cords, t.note),
        None => {
            let grid = layout.grid(pal.len().clamp(1, 5), 260, 230);
            let fit = panels_that_fit(layout, grid, &refs, "T1 (N)", &legend).min(MAX_CORD_PANELS);
            let shown = (evenly(simulated.len(), fit).into_iter())
                .map(|k| simulated[k])
                .collect();
            (grid, shown, "")
        }
    };
    let mut panels: Vec<Panel> = shown
        .iter()
        .map(|&g| {
            let c = pal.color(a.obs.groups[g].wrap_deg);
            let sims = curves.iter().filter(|(cg, _)| *cg == g);
            amp_panel(
                a,
                g,
                c,
                sims.map(|(_, sim)| Series::Line(sim.clone(), extended_style(c))),
            )
        })
        .collect();
    share_y(&mut panels);
    share_x_by_wrap(a, &shown, &mut panels);
    let n = a.obs.groups.len();
    let simulated_note = if simulated.len() < n {
        format!(
            " {} of the {n} cords are simulated, evenly spaced in the cord order.",
            simulated.len()
        )
    } else {
        String::new()
    };
    Ok(Figure {
        id: "closed_loop",
        legend,
        chart: figure(&panels, grid.0, grid.1, grid.2)?,
        caption: format!("Closed loop: the firmware run against the simulated plant with the extended model (per-cord mu{}), one run per cord; simulated amplification (thick line) over the measured points, one colour per wrap, on one y-scale (the panels of one wrap on one T1 scale too).{arranged}{simulated_note}{}{}{}", plant_causes(a), short_note(a, curves, &shown), selection_note(shown.len(), simulated.len(), "simulated cords"), super::drawn_note(a)),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two panels of one wrap take the range of both; a third, of another wrap, keeps its own.
    #[test]
    fn the_panels_of_one_wrap_share_their_x_range() {
        let panel = |xs: &[f64]| Panel {
            series: vec![Series::Points(
                xs.iter().map(|&x| (x, 1.0)).collect(),
                measured(INK),
            )],
            ..Panel::default()
        };
        let mut panels = vec![panel(&[0.0, 10.0]), panel(&[0.0, 20.0]), panel(&[1.0, 5.0])];
        share_x_by(&[720, 630, 720], &mut panels);
        let both = crate::plot::finite_range([0.0, 10.0, 1.0, 5.0].into_iter());
        assert_eq!(panels[0].x_range, Some(both));
        assert_eq!(panels[2].x_range, Some(both));
        assert_eq!(
            panels[1].x_range,
            Some(crate::plot::finite_range([0.0, 20.0].into_iter()))
        );
    }
}
