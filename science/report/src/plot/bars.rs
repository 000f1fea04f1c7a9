//! Grouped bar charts (the gain, the mechanisms' evidence), laid horizontally: one row of bars
//! per category with its name at the left in words (wrapped), each bar's value at its end, and
//! reference lines (a threshold) dashed across, named in the legend. Horizontal bars keep the
//! names readable in a journal column, where ten names under vertical bars would collide.

use super::axis::{fitted_ticks, Coord};
use super::panel::{lines, Margins, GAP, LABEL, PAD, TICK, TICK_LEN, TITLE};
use super::text::{Anchor, Font, Label, ASCENT, DESCENT};
use super::{compose, render, Chart, Dash, Entry, Key, Layer, LineStyle, AXIS, GRID, TEXT};
use crate::error::Result;
use plotters::coord::Shift;
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

/// A bar chart laid out: its margins, value axis, bands and what every bar end says.
struct Laid {
    width: f64,
    size: (u32, u32),
    m: Margins,
    x: (f64, f64),
    y: (f64, f64),
    ticks: Vec<(f64, String)>,
    title: (Vec<String>, Font),
    value_label: (Vec<String>, Font),
    names: Vec<(Vec<String>, Font)>,
    /// Each category's band height and its offset from the top of the plot area, px.
    bands: Vec<(f64, f64)>,
    groups: f64,
    ends: Vec<Vec<End>>,
    /// The reference lines' values.
    lines: Vec<f64>,
}

impl Laid {
    /// `c` laid out `w` px wide: category names up to 40 % of the width, each band as tall as
    /// its name's lines or its bars.
    fn new(c: &Bars, w: u32) -> Laid {
        let wf = f64::from(w);
        let title = lines(&c.title, TITLE, wf - 2.0 * PAD);
        let top = PAD + title.1.block(title.0.len()) + 2.0 * GAP;
        let value_label = lines(&c.value_label, LABEL, wf - 2.0 * PAD);
        let bottom =
            TICK_LEN + GAP + TICK.height() + GAP + value_label.1.block(value_label.0.len()) + PAD;
        let names: Vec<(Vec<String>, Font)> = c
            .categories
            .iter()
            .map(|s| lines(s, TICK, 0.4 * wf))
            .collect();
        let groups = c.groups.len().max(1) as f64;
        let mut bands = Vec::new();
        let mut acc = 0.0;
        for (l, f) in &names {
            let band = (groups * BAR_H).max(f.block(l.len())) + CAT_GAP;
            bands.push((band, acc));
            acc += band;
        }
        let name_w = names
            .iter()
            .flat_map(|(l, f)| l.iter().map(move |s| f.width(s)))
            .fold(0.0, f64::max);
        let m = Margins {
            left: PAD + name_w + GAP + TICK_LEN,
            right: PAD + 4.0,
            top,
            bottom,
        };
        let h = (top + acc.max(BAR_H) + bottom).ceil();
        let plot_h = h - top - bottom;
        let plot_w = wf - m.left - m.right;
        let ends = bar_ends(c);
        let x = value_range(c, &ends, plot_w);
        let most = ((plot_w / 36.0) as usize).clamp(2, 8);
        let ticks = fitted_ticks(None, x, plot_w, most, 8.0, |s| TICK.width(s));
        Laid {
            width: wf,
            size: (w, h as u32),
            m,
            x,
            y: (0.0, plot_h),
            ticks,
            title,
            value_label,
            names,
            bands,
            groups,
            ends,
            lines: c.lines.iter().map(|l| l.0).collect(),
        }
    }

    /// The data y span of bar `j` of category `k` (data y runs upwards from the plot's foot).
    fn bar_y(&self, k: usize, j: usize) -> (f64, f64) {
        let (band, offset) = self.bands[k];
        let slack = band - CAT_GAP - self.groups * BAR_H;
        let y0 = offset + CAT_GAP / 2.0 + slack / 2.0 + j as f64 * BAR_H;
        (self.y.1 - y0 - 1.0, self.y.1 - (y0 + BAR_H - 1.0))
    }

    fn chart<'a, 'b>(
        &self,
        root: &'a DrawingArea<SVGBackend<'b>, Shift>,
    ) -> Result<ChartContext<'a, SVGBackend<'b>, Coord>> {
        self.m.build(root, self.x, self.y, &self.ticks, &[])
    }
}

/// A horizontal grouped bar chart `w` px wide, as high as its categories need: every bar a
/// layer of class `mark bar`, every missing value one of class `missing`.
pub fn bar_chart(c: &Bars, w: u32) -> Result<Chart> {
    let l = Laid::new(c, w);
    let mut labels = Vec::new();
    let axes = render(l.size, |root| {
        root.fill(&WHITE)?;
        let mut chart = l.chart(root)?;
        value_axis(root, &mut chart, &l, &c.lines, &mut labels)?;
        category_names(&chart, &l, &mut labels);
        bar_end_labels(&chart, &l, &mut labels);
        Ok(())
    })?;
    let mut layers = Vec::new();
    for (k, vals) in c.values.iter().enumerate() {
        for (j, (v, (_, color))) in vals.iter().zip(&c.groups).enumerate() {
            let (y0, y1) = l.bar_y(k, j);
            let v = v.filter(|x| x.is_finite());
            let svg = render(l.size, |root| {
                let mut chart = l.chart(root)?;
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
    title_and_value_label(&l, &mut labels);
    Ok(compose(l.size, axes, &labels, layers))
}

/// Grid, ticks and their labels, the axis line, the zero line and the reference lines.
fn value_axis(
    root: &DrawingArea<SVGBackend, Shift>,
    chart: &mut ChartContext<SVGBackend, Coord>,
    l: &Laid,
    lines: &[(f64, String)],
    labels: &mut Vec<Label>,
) -> Result<()> {
    let (x, y) = (l.x, l.y);
    for (t, _) in &l.ticks {
        chart.draw_series(LineSeries::new([(*t, y.0), (*t, y.1)], GRID))?;
    }
    for (t, s) in &l.ticks {
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
        vec![
            chart.backend_coord(&(x.0, y.0)),
            chart.backend_coord(&(x.1, y.0)),
        ],
        AXIS,
    ))?;
    if x.0 < 0.0 {
        chart.draw_series(LineSeries::new([(0.0, y.0), (0.0, y.1)], AXIS))?;
    }
    for (v, _) in lines {
        chart.draw_series(DashedLineSeries::new(
            [(*v, y.0), (*v, y.1)],
            super::DASH.0,
            super::DASH.1,
            LINE_RED.stroke_width(2),
        ))?;
    }
    Ok(())
}

/// Category names, right-aligned left of the plot, centred on their band.
fn category_names(chart: &ChartContext<SVGBackend, Coord>, l: &Laid, labels: &mut Vec<Label>) {
    let left = f64::from(chart.backend_coord(&(l.x.0, l.y.0)).0) - GAP - TICK_LEN;
    for ((lines, f), (band, offset)) in l.names.iter().zip(&l.bands) {
        let centre = f64::from(chart.backend_coord(&(l.x.0, l.y.1 - offset - band / 2.0)).1);
        let first = centre - f.block(lines.len()) / 2.0 + ASCENT * f.px;
        for (i, line) in lines.iter().enumerate() {
            labels.push(Label::new(
                line.clone(),
                (left, first + i as f64 * f.line()),
                *f,
                Anchor::End,
            ));
        }
    }
}

/// Each bar's value (or the missing note) at its end, haloed over the lines it may cross.
fn bar_end_labels(chart: &ChartContext<SVGBackend, Coord>, l: &Laid, labels: &mut Vec<Label>) {
    let lift = (ASCENT - DESCENT) / 2.0 * TICK.px;
    for (k, row) in l.ends.iter().enumerate() {
        for (j, e) in row.iter().enumerate() {
            let (y0, y1) = l.bar_y(k, j);
            let (px, py) = chart.backend_coord(&(e.at, (y0 + y1) / 2.0));
            let (dx, anchor) = if e.at < 0.0 {
                (-GAP, Anchor::End)
            } else {
                (GAP, Anchor::Start)
            };
            // Written past a reference line its text would otherwise straddle.
            let line_px: Vec<f64> = (l.lines.iter())
                .map(|v| f64::from(chart.backend_coord(&(*v, y0)).0))
                .collect();
            let room = GAP + TICK.width(&e.text) + 1.0;
            let x = label_start(f64::from(px), room, &line_px, e.at >= 0.0);
            labels.push(Label {
                halo: true,
                ..Label::new(e.text.clone(), (x + dx, f64::from(py) + lift), TICK, anchor)
            });
        }
    }
}

/// Where a bar-end label starts so that no reference line runs through its text: the bar's end
/// `at`, or the farthest line the text (`room` long, the same units) would cross, moving on past
/// each. The text runs to the right (`rightwards`: a bar at or above zero) or to the left.
fn label_start(at: f64, room: f64, lines: &[f64], rightwards: bool) -> f64 {
    let mut sorted = lines.to_vec();
    sorted.sort_by(f64::total_cmp);
    let mut start = at;
    if rightwards {
        for &v in &sorted {
            if v > start && v < start + room {
                start = v;
            }
        }
    } else {
        for &v in sorted.iter().rev() {
            if v < start && v > start - room {
                start = v;
            }
        }
    }
    start
}

/// The title above the chart and the value axis's label under its tick labels.
fn title_and_value_label(l: &Laid, labels: &mut Vec<Label>) {
    let (title, tf) = &l.title;
    for (i, line) in title.iter().enumerate() {
        let y = PAD + ASCENT * tf.px + i as f64 * tf.line();
        labels.push(Label::new(
            line.clone(),
            (l.width / 2.0, y),
            *tf,
            Anchor::Middle,
        ));
    }
    let (vl, vf) = &l.value_label;
    let base = l.m.top + l.y.1 + TICK_LEN + GAP + TICK.height() + GAP;
    let mid = l.m.left + (l.width - l.m.left - l.m.right) / 2.0;
    for (i, line) in vl.iter().enumerate() {
        let half = vf.width(line) / 2.0;
        let x = mid.clamp(PAD + half, l.width - PAD - half);
        let y = base + ASCENT * vf.px + i as f64 * vf.line();
        labels.push(Label::new(line.clone(), (x, y), *vf, Anchor::Middle));
    }
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
    let lines: Vec<f64> = c.lines.iter().map(|l| l.0).collect();
    for _ in 0..30 {
        let scale = plot_w / (hi - lo);
        let (mut lo2, mut hi2) = (lo, hi);
        for e in ends.iter().flatten() {
            // Where bar_end_labels writes it: past any line it would straddle.
            let at = label_start(e.at, room(e) / scale, &lines, e.at >= 0.0);
            if e.at < 0.0 {
                lo2 = lo2.min(at - room(e) / scale);
            } else {
                hi2 = hi2.max(at + room(e) / scale);
            }
        }
        if lo2 == lo && hi2 == hi {
            break;
        }
        (lo, hi) = (lo2, hi2);
    }
    (lo, hi)
}

#[cfg(test)]
mod tests {
    use super::label_start;

    #[test]
    fn a_label_that_would_straddle_a_line_starts_past_it() {
        let right = |at: f64, room: f64, lines: &[f64]| label_start(at, room, lines, true);
        let left = |at: f64, room: f64, lines: &[f64]| label_start(at, room, lines, false);
        // A bar ending at 1 with a threshold at 6: "1.0" (9 long) would straddle it.
        assert_eq!(right(1.0, 9.0, &[6.0]), 6.0);
        // A bar past the line, or one whose text ends before it, keeps its place.
        assert_eq!(right(10.0, 9.0, &[6.0]), 10.0);
        assert_eq!(right(1.0, 4.0, &[6.0]), 1.0);
        // A line at the bar's very end is not crossed.
        assert_eq!(right(6.0, 9.0, &[6.0]), 6.0);
        // Text running leftwards (a negative bar) moves left past a line on that side only.
        assert_eq!(left(-1.0, 9.0, &[-6.0, 6.0]), -6.0);
        assert_eq!(left(-1.0, 9.0, &[6.0]), -1.0);
        // In pixels a negative bar's end is a positive number: the direction is the caller's.
        assert_eq!(left(300.0, 40.0, &[320.0]), 300.0);
        // Two lines close together: past both.
        assert_eq!(right(0.0, 5.0, &[2.0, 6.0]), 6.0);
    }
}
