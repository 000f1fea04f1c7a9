//! Panels of points and lines on a grid, with a figure legend, and grouped bar charts, drawn
//! with [`super::svg`] (inline SVG, no fonts or scripts needed).

use super::svg::{nice_ticks, text_width, tick_label, Anchor, Dash, Svg};

/// How a line is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineStyle {
    /// Stroke colour.
    pub color: &'static str,
    /// Stroke width, px.
    pub width: f64,
    /// Pattern.
    pub dash: Dash,
}

/// How a point is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Marker {
    /// Colour.
    pub color: &'static str,
    /// Radius, px.
    pub radius: f64,
    /// A ring instead of a disc.
    pub hollow: bool,
    /// Opacity (points overlap).
    pub opacity: f64,
}

/// A series on a panel.
pub enum Series {
    /// Markers at (x, y).
    Points(Vec<(f64, f64)>, Marker),
    /// A polyline through (x, y) in drawing order (non-finite points break it).
    Line(Vec<(f64, f64)>, LineStyle),
}

/// What a legend entry shows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Key {
    /// A marker.
    Marker(Marker),
    /// A line sample.
    Line(LineStyle),
}

/// One legend entry.
#[derive(Clone, Debug, PartialEq)]
pub struct Entry {
    /// The sample.
    pub key: Key,
    /// Its text.
    pub label: String,
}

/// One panel.
#[derive(Default)]
pub struct Panel {
    /// Title above the plot area.
    pub title: String,
    /// x-axis label (with unit).
    pub x_label: String,
    /// y-axis label (with unit).
    pub y_label: String,
    /// Series, drawn in order.
    pub series: Vec<Series>,
    /// Legend inside the panel (top left); empty for none.
    pub legend: Vec<Entry>,
    /// Custom x ticks (position, label) instead of automatic ones.
    pub x_ticks: Option<Vec<(f64, String)>>,
    /// A horizontal reference line at y = 0.
    pub zero_line: bool,
    /// Fixed y range (e.g. shared between panels) instead of the data's.
    pub y_range: Option<(f64, f64)>,
}

const TITLE: f64 = 14.0;
const LABEL: f64 = 13.0;
const TICK: f64 = 12.0;
const LEGEND: f64 = 12.5;
const AXIS: &str = "#444";
const GRID: &str = "#e6e6e6";

/// The range of the finite values, padded by 4 % (a unit range around a single value).
pub fn finite_range(vals: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = vals
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    if hi - lo < 1e-12 {
        return (lo - 0.5, hi + 0.5);
    }
    let pad = 0.04 * (hi - lo);
    (lo - pad, hi + pad)
}

/// The data points of a series.
fn points(s: &Series) -> &[(f64, f64)] {
    match s {
        Series::Points(xy, _) | Series::Line(xy, _) => xy,
    }
}

/// Draw a legend sample at (x, y) (y the text's middle).
fn draw_key(svg: &mut Svg, key: &Key, x: f64, y: f64) {
    match key {
        Key::Marker(m) => svg.circle((x + 11.0, y), m.radius.max(4.5), m.color, m.hollow, 1.0),
        Key::Line(l) => svg.line((x, y), (x + 24.0, y), l.color, l.width, l.dash, false),
    }
}

/// Lay out `entries` in rows no wider than `w`, starting at (x0, y0); returns the height used.
fn draw_legend(svg: &mut Svg, entries: &[Entry], x0: f64, y0: f64, w: f64) -> f64 {
    let (mut x, mut y) = (x0, y0 + 10.0);
    for e in entries {
        let ew = 30.0 + text_width(&e.label, LEGEND) + 16.0;
        if x > x0 && x + ew > x0 + w {
            x = x0;
            y += 20.0;
        }
        draw_key(svg, &e.key, x, y);
        svg.text(
            (x + 30.0, y + 4.5),
            &e.label,
            LEGEND,
            Anchor::Start,
            false,
            false,
        );
        x += ew;
    }
    if entries.is_empty() {
        0.0
    } else {
        y - y0 + 12.0
    }
}

/// Height of a figure legend of `entries` laid out in `w` px.
fn legend_height(entries: &[Entry], w: f64) -> f64 {
    let mut svg = Svg::new(1.0, 1.0);
    let h = draw_legend(&mut svg, entries, 0.0, 0.0, w);
    if h > 0.0 {
        h + 10.0
    } else {
        0.0
    }
}

/// The plot area of a panel at (ox, oy) of size w×h: (left, top, right, bottom).
fn plot_area(ox: f64, oy: f64, w: f64, h: f64) -> (f64, f64, f64, f64) {
    (ox + 62.0, oy + 26.0, ox + w - 14.0, oy + h - 46.0)
}

fn draw_panel(svg: &mut Svg, p: &Panel, ox: f64, oy: f64, w: f64, h: f64) {
    let (l, t, r, b) = plot_area(ox, oy, w, h);
    let (x0, x1) = finite_range(
        p.series
            .iter()
            .flat_map(|s| points(s).iter().map(|v| v.0))
            .chain(p.x_ticks.iter().flatten().map(|t| t.0)),
    );
    let (y0, y1) = p.y_range.unwrap_or_else(|| {
        finite_range(
            p.series
                .iter()
                .flat_map(|s| points(s).iter().map(|v| v.1))
                .chain(p.zero_line.then_some(0.0)),
        )
    });
    let sx = |x: f64| l + (x - x0) / (x1 - x0) * (r - l);
    let sy = |y: f64| b - (y - y0) / (y1 - y0) * (b - t);
    svg.text(
        (ox + w / 2.0, oy + 17.0),
        &p.title,
        TITLE,
        Anchor::Middle,
        true,
        false,
    );
    // Grid and ticks.
    let (yt, ys) = nice_ticks(y0, y1, 5);
    for v in &yt {
        svg.line((l, sy(*v)), (r, sy(*v)), GRID, 1.0, Dash::Solid, false);
        svg.text(
            (l - 6.0, sy(*v) + 4.0),
            &tick_label(*v, ys),
            TICK,
            Anchor::End,
            false,
            false,
        );
    }
    let xt: Vec<(f64, String)> = p.x_ticks.clone().unwrap_or_else(|| {
        let (xt, xs) = nice_ticks(x0, x1, ((r - l) / 70.0).clamp(3.0, 8.0) as usize);
        xt.iter().map(|v| (*v, tick_label(*v, xs))).collect()
    });
    for (v, s) in &xt {
        svg.line((sx(*v), t), (sx(*v), b), GRID, 1.0, Dash::Solid, false);
        svg.line(
            (sx(*v), b),
            (sx(*v), b + 4.0),
            AXIS,
            1.0,
            Dash::Solid,
            false,
        );
        svg.text((sx(*v), b + 17.0), s, TICK, Anchor::Middle, false, false);
    }
    if p.zero_line {
        svg.line((l, sy(0.0)), (r, sy(0.0)), "#888", 1.2, Dash::Solid, false);
    }
    svg.line((l, b), (r, b), AXIS, 1.2, Dash::Solid, false);
    svg.line((l, t), (l, b), AXIS, 1.2, Dash::Solid, false);
    svg.text(
        ((l + r) / 2.0, oy + h - 10.0),
        &p.x_label,
        LABEL,
        Anchor::Middle,
        false,
        false,
    );
    svg.text(
        (ox + 15.0, (t + b) / 2.0),
        &p.y_label,
        LABEL,
        Anchor::Middle,
        false,
        true,
    );
    // Data.
    for s in &p.series {
        match s {
            Series::Points(xy, m) => {
                for (x, y) in xy.iter().filter(|v| v.0.is_finite() && v.1.is_finite()) {
                    svg.circle((sx(*x), sy(*y)), m.radius, m.color, m.hollow, m.opacity);
                }
            }
            Series::Line(xy, st) => {
                for run in xy.split(|v| !(v.0.is_finite() && v.1.is_finite())) {
                    let pts: Vec<(f64, f64)> = run.iter().map(|v| (sx(v.0), sy(v.1))).collect();
                    svg.polyline(&pts, st.color, st.width, st.dash);
                }
            }
        }
    }
    if !p.legend.is_empty() {
        draw_legend(svg, &p.legend, l + 8.0, t + 2.0, r - l - 16.0);
    }
}

/// Panels on a grid of `cols` columns, each `w`×`h` px, under a figure legend (`legend`,
/// empty for none): one SVG document.
pub fn figure(panels: &[Panel], cols: usize, w: f64, h: f64, legend: &[Entry]) -> String {
    let cols = cols.max(1);
    let rows = panels.len().div_ceil(cols);
    let total_w = w * cols as f64;
    let lh = legend_height(legend, total_w - 24.0);
    let mut svg = Svg::new(total_w, lh + h * rows as f64);
    draw_legend(&mut svg, legend, 12.0, 4.0, total_w - 24.0);
    for (k, p) in panels.iter().enumerate() {
        let (row, col) = (k / cols, k % cols);
        draw_panel(&mut svg, p, col as f64 * w, lh + row as f64 * h, w, h);
    }
    svg.finish()
}

/// A grouped bar chart: for every category one bar per group.
pub struct Bars {
    /// Title.
    pub title: String,
    /// y-axis label.
    pub y_label: String,
    /// Category names (x axis).
    pub categories: Vec<String>,
    /// Group names and colours (the legend).
    pub groups: Vec<(String, &'static str)>,
    /// values[category][group]; None draws an empty outlined slot with `missing`.
    pub values: Vec<Vec<Option<f64>>>,
    /// Text for a missing value.
    pub missing: String,
}

/// A grouped bar chart, `w`×`h` px, y from zero, each bar labelled with its value.
pub fn bar_chart(c: &Bars, w: f64, h: f64) -> String {
    let legend: Vec<Entry> = c
        .groups
        .iter()
        .map(|(label, color)| Entry {
            key: Key::Line(LineStyle {
                color,
                width: 10.0,
                dash: Dash::Solid,
            }),
            label: label.clone(),
        })
        .collect();
    let lh = legend_height(&legend, w - 24.0);
    let mut svg = Svg::new(w, h + lh);
    draw_legend(&mut svg, &legend, 12.0, 4.0, w - 24.0);
    let (l, t, r, b) = plot_area(0.0, lh, w, h);
    let top = c
        .values
        .iter()
        .flatten()
        .flatten()
        .fold(0.0f64, |a, v| a.max(*v))
        * 1.12;
    let top = if top > 0.0 { top } else { 1.0 };
    let sy = |y: f64| b - y / top * (b - t);
    svg.text(
        (w / 2.0, lh + 17.0),
        &c.title,
        TITLE,
        Anchor::Middle,
        true,
        false,
    );
    let (yt, ys) = nice_ticks(0.0, top, 5);
    for v in &yt {
        svg.line((l, sy(*v)), (r, sy(*v)), GRID, 1.0, Dash::Solid, false);
        svg.text(
            (l - 6.0, sy(*v) + 4.0),
            &tick_label(*v, ys),
            TICK,
            Anchor::End,
            false,
            false,
        );
    }
    let slot = (r - l) / c.categories.len().max(1) as f64;
    let ng = c.groups.len().max(1) as f64;
    let bw = (slot * 0.7 / ng).min(70.0);
    for (k, (name, vals)) in c.categories.iter().zip(&c.values).enumerate() {
        let cx = l + slot * (k as f64 + 0.5);
        svg.text((cx, b + 18.0), name, LABEL, Anchor::Middle, false, false);
        for (j, (v, (_, color))) in vals.iter().zip(&c.groups).enumerate() {
            let x = cx - bw * ng / 2.0 + bw * j as f64 + 2.0;
            match v {
                Some(v) => {
                    svg.rect(x, sy(*v), bw - 4.0, b - sy(*v), color, "#222", "mark bar");
                    svg.text(
                        (x + bw / 2.0 - 2.0, sy(*v) - 5.0),
                        &format!("{v:.3}"),
                        TICK,
                        Anchor::Middle,
                        false,
                        false,
                    );
                }
                None => {
                    let y = sy(top * 0.3);
                    svg.rect(x, y, bw - 4.0, b - y, "none", "#999", "missing");
                    svg.text(
                        (x + bw / 2.0 + 2.0, b - 8.0),
                        &c.missing,
                        TICK,
                        Anchor::Start,
                        false,
                        true,
                    );
                }
            }
        }
    }
    svg.line((l, b), (r, b), AXIS, 1.2, Dash::Solid, false);
    svg.line((l, t), (l, b), AXIS, 1.2, Dash::Solid, false);
    svg.text(
        (15.0, (t + b) / 2.0),
        &c.y_label,
        LABEL,
        Anchor::Middle,
        false,
        true,
    );
    svg.finish()
}
