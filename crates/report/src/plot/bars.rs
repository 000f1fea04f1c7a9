//! Grouped bar charts (the gain, the mechanisms' evidence), laid horizontally: one row of bars
//! per category with its name at the left in words (wrapped), each bar's value at its end, and
//! reference lines (a threshold) dashed across, named in the legend. Horizontal bars keep the
//! names readable in a journal column, where ten names under vertical bars would collide.

use super::axis::fitted_ticks;
use super::panel::{lines, Margins, GAP, LABEL, PAD, TICK, TICK_LEN, TITLE};
use super::text::{Anchor, Label, ASCENT, DESCENT};
use super::{compose, render, Chart, Dash, Entry, Key, Layer, LineStyle, AXIS, GRID, TEXT};
use anyhow::Result;
use plotters::prelude::*;

/// A grouped bar chart: for every category one bar per group.
pub struct Bars {
    /// Title.
    pub title: String,
    /// Label of the value axis (with unit).
    pub value_label: String,
    /// Category names (in words).
    pub categories: Vec<String>,
    /// Group names and colours (the legend).
    pub groups: Vec<(String, RGBColor)>,
    /// values[category][group]; None draws an empty outlined bar with `missing` beside it.
    pub values: Vec<Vec<Option<f64>>>,
    /// Text for a missing value.
    pub missing: String,
    /// Reference lines across the bars (a threshold): value and its legend text.
    pub lines: Vec<(f64, String)>,
    /// Decimals of the bars' value labels.
    pub decimals: usize,
}

/// Colour of the reference lines.
pub const LINE_RED: RGBColor = RGBColor(0xC0, 0x20, 0x20);

/// The reference lines' style.
pub fn line_style() -> LineStyle {
    LineStyle {
        color: LINE_RED,
        width: 2,
        dash: Dash::Dashed,
    }
}

impl Bars {
    /// Legend entries: one swatch per group, then one dashed line per reference line.
    pub fn legend(&self) -> Vec<Entry> {
        let swatches = self.groups.iter().map(|(label, color)| Entry {
            key: Key::Line(LineStyle {
                color: *color,
                width: 10,
                dash: Dash::Solid,
            }),
            label: label.clone(),
        });
        let lines = self.lines.iter().map(|(_, label)| Entry {
            key: Key::Line(line_style()),
            label: label.clone(),
        });
        swatches.chain(lines).collect()
    }

    fn label(&self, v: f64) -> String {
        let s = format!("{v:.*}", self.decimals);
        s.replace('-', "−")
    }
}

/// Height of one bar, px.
const BAR_H: f64 = 15.0;
/// Space between categories, px.
const CAT_GAP: f64 = 9.0;

/// What is drawn at the end of a bar: its value, or the missing note beside an empty bar.
struct End {
    at: f64,
    text: String,
}

/// A horizontal grouped bar chart `w` px wide, as high as its categories need: every bar a
/// layer of class `mark bar`, every missing value one of class `missing`.
pub fn bar_chart(c: &Bars, w: u32) -> Result<Chart> {
    let wf = f64::from(w);
    let title = lines(&c.title, TITLE, wf - 2.0 * PAD);
    let top = PAD + title.1.block(title.0.len()) + 2.0 * GAP;
    let xl = lines(&c.value_label, LABEL, wf - 2.0 * PAD);
    let bottom = TICK_LEN + GAP + TICK.height() + GAP + xl.1.block(xl.0.len()) + PAD;
    // Category names at most 40 % of the width, each band tall enough for its lines and bars.
    let names: Vec<(Vec<String>, _)> = c
        .categories
        .iter()
        .map(|s| lines(s, TICK, 0.4 * wf))
        .collect();
    let groups = c.groups.len().max(1) as f64;
    let bands: Vec<f64> = names
        .iter()
        .map(|(l, f)| (groups * BAR_H).max(f.block(l.len())) + CAT_GAP)
        .collect();
    let name_w = names
        .iter()
        .flat_map(|(l, f)| l.iter().map(move |s| f.width(s)))
        .fold(0.0, f64::max);
    let left = PAD + name_w + GAP + TICK_LEN;
    let right = PAD + 4.0;
    let plot_h: f64 = bands.iter().sum::<f64>().max(BAR_H);
    let h = (top + plot_h + bottom).ceil();
    let plot_h = h - top - bottom;
    let plot_w = wf - left - right;
    let ends = bar_ends(c);
    let x = value_range(c, &ends, plot_w);
    let ticks = fitted_ticks(
        None,
        x,
        plot_w,
        ((plot_w / 36.0) as usize).clamp(2, 8),
        8.0,
        |s| TICK.width(s),
    );
    let m = Margins {
        left,
        right,
        top,
        bottom,
    };
    let size = (w, h.ceil() as u32);
    let y = (0.0, plot_h);
    // Band k spans [y_k, y_k + band] from the top: data y runs upwards, so y = plot_h − offset.
    let mut offsets = Vec::new();
    let mut acc = 0.0;
    for b in &bands {
        offsets.push(acc);
        acc += b;
    }
    let bar_y = |k: usize, j: usize| {
        let slack = bands[k] - CAT_GAP - groups * BAR_H;
        let y0 = offsets[k] + CAT_GAP / 2.0 + slack / 2.0 + j as f64 * BAR_H;
        (plot_h - y0 - 1.0, plot_h - (y0 + BAR_H - 1.0))
    };
    let mut labels = Vec::new();
    let axes = render(size, |root| {
        root.fill(&WHITE)?;
        let mut chart = m.build(root, x, y, &ticks, &[])?;
        for (t, _) in &ticks {
            chart.draw_series(LineSeries::new([(*t, y.0), (*t, y.1)], GRID))?;
        }
        let lift = (ASCENT - DESCENT) / 2.0;
        let corner = chart.backend_coord(&(x.0, y.0));
        for (t, s) in &ticks {
            let (px, py) = chart.backend_coord(&(*t, y.0));
            root.draw(&PathElement::new(
                vec![(px, py), (px, py + TICK_LEN as i32)],
                AXIS,
            ))?;
            let base = f64::from(py) + TICK_LEN + GAP + ASCENT * TICK.px;
            labels.push(Label::new(
                s.clone(),
                (f64::from(px), base),
                TICK,
                Anchor::Middle,
            ));
        }
        root.draw(&PathElement::new(
            vec![corner, chart.backend_coord(&(x.1, y.0))],
            AXIS,
        ))?;
        if x.0 < 0.0 {
            chart.draw_series(LineSeries::new([(0.0, y.0), (0.0, y.1)], AXIS))?;
        }
        for (v, _) in &c.lines {
            let style = LINE_RED.stroke_width(2);
            chart.draw_series(DashedLineSeries::new(
                [(*v, y.0), (*v, y.1)],
                super::DASH.0,
                super::DASH.1,
                style,
            ))?;
        }
        // Category names, right-aligned left of the plot, centred on their band.
        for (k, (l, f)) in names.iter().enumerate() {
            let centre = f64::from(
                chart
                    .backend_coord(&(x.0, plot_h - offsets[k] - bands[k] / 2.0))
                    .1,
            );
            let first = centre - f.block(l.len()) / 2.0 + ASCENT * f.px;
            for (i, line) in l.iter().enumerate() {
                labels.push(Label::new(
                    line.clone(),
                    (
                        f64::from(corner.0) - GAP - TICK_LEN,
                        first + i as f64 * f.line(),
                    ),
                    *f,
                    Anchor::End,
                ));
            }
        }
        // Each bar's value (or the missing note) at its end.
        for (k, row) in ends.iter().enumerate() {
            for (j, e) in row.iter().enumerate() {
                let (y0, y1) = bar_y(k, j);
                let (px, py) = chart.backend_coord(&(e.at, (y0 + y1) / 2.0));
                let (dx, anchor) = if e.at < 0.0 {
                    (-GAP, Anchor::End)
                } else {
                    (GAP, Anchor::Start)
                };
                labels.push(Label {
                    halo: true,
                    ..Label::new(
                        e.text.clone(),
                        (f64::from(px) + dx, f64::from(py) + lift * TICK.px),
                        TICK,
                        anchor,
                    )
                });
            }
        }
        Ok(())
    })?;
    let mut layers = Vec::new();
    for (k, vals) in c.values.iter().enumerate() {
        for (j, (v, (_, color))) in vals.iter().zip(&c.groups).enumerate() {
            let (y0, y1) = bar_y(k, j);
            let v = v.filter(|x| x.is_finite());
            let svg = render(size, |root| {
                let mut chart = m.build(root, x, y, &ticks, &[])?;
                match v {
                    Some(v) => chart.draw_series([
                        Rectangle::new([(0.0, y0), (v, y1)], color.filled()),
                        Rectangle::new([(0.0, y0), (v, y1)], TEXT.stroke_width(1)),
                    ])?,
                    None => chart.draw_series([Rectangle::new(
                        [(0.0, y0), (missing_len(c), y1)],
                        RGBColor(0x99, 0x99, 0x99).stroke_width(1),
                    )])?,
                };
                Ok(())
            })?;
            let class = if v.is_some() { "mark bar" } else { "missing" };
            layers.push(Layer { class, svg });
        }
    }
    // The axis label under the tick labels.
    let base = top + plot_h + TICK_LEN + GAP + TICK.height() + GAP;
    let mid = left + plot_w / 2.0;
    for (i, line) in xl.0.iter().enumerate() {
        let half = xl.1.width(line) / 2.0;
        let x = mid.clamp(PAD + half, wf - PAD - half);
        labels.push(Label::new(
            line.clone(),
            (x, base + ASCENT * xl.1.px + i as f64 * xl.1.line()),
            xl.1,
            Anchor::Middle,
        ));
    }
    for (i, line) in title.0.iter().enumerate() {
        labels.push(Label::new(
            line.clone(),
            (
                wf / 2.0,
                PAD + ASCENT * title.1.px + i as f64 * title.1.line(),
            ),
            title.1,
            Anchor::Middle,
        ));
    }
    Ok(compose(size, axes, &labels, layers))
}

/// The length of an empty bar: a fifth of the largest value (1 without any).
fn missing_len(c: &Bars) -> f64 {
    let top = c
        .values
        .iter()
        .flatten()
        .flatten()
        .filter(|v| v.is_finite())
        .fold(0.0f64, |a, v| a.max(v.abs()));
    if top > 0.0 {
        0.2 * top
    } else {
        1.0
    }
}

/// Where each bar ends and what is written there.
fn bar_ends(c: &Bars) -> Vec<Vec<End>> {
    c.values
        .iter()
        .map(|row| {
            row.iter()
                .map(|v| match v.filter(|x| x.is_finite()) {
                    Some(v) => End {
                        at: v,
                        text: c.label(v),
                    },
                    None => End {
                        at: missing_len(c),
                        text: c.missing.clone(),
                    },
                })
                .collect()
        })
        .collect()
}

/// The value axis's range: zero, every bar and line, and room for each end's text.
fn value_range(c: &Bars, ends: &[Vec<End>], plot_w: f64) -> (f64, f64) {
    let vals = ends
        .iter()
        .flatten()
        .map(|e| e.at)
        .chain(c.lines.iter().map(|l| l.0))
        .filter(|v| v.is_finite());
    let (mut lo, mut hi) = vals.fold((0.0f64, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
    if hi - lo < 1e-12 {
        hi = lo + 1.0;
    }
    let room = |e: &End| GAP + TICK.width(&e.text) + 3.0;
    for _ in 0..30 {
        let scale = plot_w / (hi - lo);
        let (mut lo2, mut hi2) = (lo, hi);
        for e in ends.iter().flatten() {
            if e.at < 0.0 {
                lo2 = lo2.min(e.at - room(e) / scale);
            } else {
                hi2 = hi2.max(e.at + room(e) / scale);
            }
        }
        if lo2 == lo && hi2 == hi {
            break;
        }
        (lo, hi) = (lo2, hi2);
    }
    (lo, hi)
}
