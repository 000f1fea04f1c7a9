//! Grouped bar charts (the gain figure).

use super::axis::{auto_ticks, Coord, Frame};
use super::{
    build, compose, draw_axes, font, render, Chart, Dash, Entry, Key, Layer, LineStyle, Panel,
    TEXT, TICK,
};
use anyhow::Result;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// A grouped bar chart: for every category one bar per group.
pub struct Bars {
    /// Title.
    pub title: String,
    /// y-axis label.
    pub y_label: String,
    /// Category names (x axis).
    pub categories: Vec<String>,
    /// Group names and colours (the legend).
    pub groups: Vec<(String, RGBColor)>,
    /// values[category][group]; None draws an empty outlined slot with `missing`.
    pub values: Vec<Vec<Option<f64>>>,
    /// Text for a missing value.
    pub missing: String,
    /// Horizontal reference lines (a threshold): value and label.
    pub lines: Vec<(f64, String)>,
    /// Decimals of the bars' value labels.
    pub decimals: usize,
}

impl Bars {
    /// Legend entries: one swatch per group.
    pub fn legend(&self) -> Vec<Entry> {
        self.groups
            .iter()
            .map(|(label, color)| Entry {
                key: Key::Line(LineStyle {
                    color: *color,
                    width: 10,
                    dash: Dash::Solid,
                }),
                label: label.clone(),
            })
            .collect()
    }
}

/// A grouped bar chart, `w`×`h` px, y from zero, each bar labelled with its value; every bar
/// is a layer of class `mark bar`, every missing value one of class `missing`.
pub fn bar_chart(c: &Bars, w: u32, h: u32) -> Result<Chart> {
    let finite = || {
        c.values
            .iter()
            .flatten()
            .flatten()
            .copied()
            .chain(c.lines.iter().map(|l| l.0))
            .filter(|v| v.is_finite())
    };
    let top = finite().fold(0.0f64, f64::max) * 1.12;
    let top = if top > 0.0 { top } else { 1.0 };
    let bottom = finite().fold(0.0f64, f64::min) * 1.12;
    let n = c.categories.len().max(1) as f64;
    let panel = Panel {
        title: c.title.clone(),
        y_label: c.y_label.clone(),
        ..Panel::default()
    };
    let f = Frame {
        x: (0.0, n),
        y: (bottom, top),
        // The category names are drawn below (staggered when they would collide).
        x_ticks: (0..c.categories.len())
            .map(|k| (k as f64 + 0.5, String::new()))
            .collect(),
        y_ticks: auto_ticks(bottom, top, 5),
        categorical: true,
    };
    let size = (w, h);
    let axes = render(size, |root| {
        root.fill(&WHITE)?;
        draw_axes(root, &panel, &f)?;
        let mut chart = build(root, &f)?;
        let slot_px = f64::from(w.saturating_sub(super::LEFT + super::RIGHT)) / n;
        draw_categories(&mut chart, &c.categories, slot_px, bottom)?;
        if bottom < 0.0 {
            chart.draw_series(LineSeries::new([(0.0, 0.0), (n, 0.0)], super::ZERO))?;
        }
        draw_lines(&mut chart, &c.lines, n)
    })?;
    // Bars fill 70 % of each category's slot, with a small gap between neighbours.
    let bw = 0.7 / c.groups.len().max(1) as f64;
    let mut layers = Vec::new();
    for (k, vals) in c.values.iter().enumerate() {
        for (j, (v, (_, color))) in vals.iter().zip(&c.groups).enumerate() {
            let x0 = k as f64 + 0.15 + bw * j as f64 + 0.01;
            let x1 = x0 + bw - 0.02;
            let svg = render(size, |root| {
                let mut chart = build(root, &f)?;
                // A value that is not identified is drawn as missing, never as "NaN".
                match v.filter(|x| x.is_finite()) {
                    Some(v) => draw_bar(&mut chart, (x0, x1), v, *color, c.decimals),
                    None => draw_missing(&mut chart, (x0, x1), top, &c.missing),
                }
            })?;
            let class = if v.is_some_and(|x| x.is_finite()) {
                "mark bar"
            } else {
                "missing"
            };
            layers.push(Layer { class, svg });
        }
    }
    Ok(compose(size, axes, layers))
}

/// The category names below the axis, staggered in two rows when the widest would not fit
/// its slot (`slot_px` wide).
fn draw_categories(
    chart: &mut ChartContext<SVGBackend, Coord>,
    categories: &[String],
    slot_px: f64,
    bottom: f64,
) -> Result<()> {
    let widest = categories
        .iter()
        .map(|s| s.chars().count())
        .max()
        .unwrap_or(0);
    let stagger = 0.6 * super::LABEL * widest as f64 > 0.95 * slot_px;
    for (k, name) in categories.iter().enumerate() {
        let dy = if stagger && k % 2 == 1 { 22 } else { 6 };
        let style = font(super::LABEL, false).pos(Pos::new(HPos::Center, VPos::Top));
        chart.draw_series(std::iter::once(
            EmptyElement::at((k as f64 + 0.5, bottom)) + Text::new(name.clone(), (0, dy), style),
        ))?;
    }
    Ok(())
}

/// The horizontal reference lines (a threshold), dashed red, each labelled at the right end.
fn draw_lines(
    chart: &mut ChartContext<SVGBackend, Coord>,
    lines: &[(f64, String)],
    n: f64,
) -> Result<()> {
    let red = RGBColor(0xC0, 0x20, 0x20);
    for (y, label) in lines {
        chart.draw_series(DashedLineSeries::new(
            [(0.0, *y), (n, *y)],
            super::DASH.0,
            super::DASH.1,
            red.stroke_width(2),
        ))?;
        let style = font(TICK, false)
            .color(&red)
            .pos(Pos::new(HPos::Right, VPos::Bottom));
        chart.draw_series(std::iter::once(
            EmptyElement::at((n, *y)) + Text::new(label.clone(), (-4, -3), style),
        ))?;
    }
    Ok(())
}

/// One bar from 0 to `v` between `x0` and `x1`, outlined, its value above it.
fn draw_bar(
    chart: &mut ChartContext<SVGBackend, Coord>,
    (x0, x1): (f64, f64),
    v: f64,
    color: RGBColor,
    decimals: usize,
) -> Result<()> {
    let label = font(TICK, false).pos(Pos::new(HPos::Center, VPos::Bottom));
    chart.draw_series([
        Rectangle::new([(x0, 0.0), (x1, v)], color.filled()),
        Rectangle::new([(x0, 0.0), (x1, v)], TEXT.stroke_width(1)),
    ])?;
    chart.draw_series(std::iter::once(
        EmptyElement::at(((x0 + x1) / 2.0, v))
            + Text::new(format!("{v:.*}", decimals), (0, -4), label),
    ))?;
    Ok(())
}

/// An empty grey slot (30 % of the axis high) with `missing` written up it.
fn draw_missing(
    chart: &mut ChartContext<SVGBackend, Coord>,
    (x0, x1): (f64, f64),
    top: f64,
    missing: &str,
) -> Result<()> {
    let label = font(TICK, false)
        .transform(FontTransform::Rotate270)
        .pos(Pos::new(HPos::Left, VPos::Center));
    let grey = RGBColor(0x99, 0x99, 0x99);
    chart.draw_series([Rectangle::new(
        [(x0, 0.0), (x1, 0.3 * top)],
        grey.stroke_width(1),
    )])?;
    chart.draw_series(std::iter::once(
        EmptyElement::at(((x0 + x1) / 2.0, 0.0)) + Text::new(missing.to_string(), (0, -8), label),
    ))?;
    Ok(())
}
