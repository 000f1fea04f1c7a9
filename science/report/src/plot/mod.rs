//! The report's charts, drawn by `plotters` (SVG backend; text stays SVG `<text>`, so no font
//! library is needed): panels of points and lines on a grid, and grouped bar charts.
//!
//! A chart is one `<svg class="chart">` holding an `axes` layer (background, grid, axes, tick
//! labels, titles, in-panel legends) and one layer per data series or bar (`<g class="mark">`).
//! Every layer is a plotters document of the chart's full size, laid out with the same panels
//! and coordinates, so the layers overlay exactly. The layers are what `scripts/check-report`
//! counts: a chart whose data is not drawn has no, or empty, `mark` layers, whatever its axes
//! show. The figure legend is HTML (`html.rs`), from the same [`Entry`] values.

use crate::error::Result;
use plotters::coord::Shift;
use plotters::prelude::*;

mod axis;
mod bars;
pub mod legend;
pub mod panel;
pub mod text;

use axis::Coord;
#[cfg(test)]
use axis::{auto_ticks, tick_label};
pub use bars::{bar_chart, Bars};
pub use panel::cell_height;

/// A stroke pattern.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dash {
    /// Continuous.
    Solid,
    /// Long dashes ([`DASH`]).
    Dashed,
    /// Round dots ([`DOT_PERIOD`] apart).
    Dotted,
}

/// Dash and gap of a dashed line, px.
pub const DASH: (u32, u32) = (7, 4);
/// Distance between the dots of a dotted line, px (the legend's sample; plotters places the
/// dots on whole pixels, 5 px apart).
pub const DOT_PERIOD: f64 = 4.6;

/// How a line is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineStyle {
    /// Stroke colour.
    pub color: RGBColor,
    /// Stroke width, px (dotted: the dots' diameter).
    pub width: u32,
    /// Pattern.
    pub dash: Dash,
}

/// How a point is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Marker {
    /// Colour.
    pub color: RGBColor,
    /// Radius, px.
    pub radius: u32,
    /// A ring instead of a disc.
    pub hollow: bool,
    /// Opacity (points overlap).
    pub opacity: f64,
}

/// A series on a panel.
pub enum Series {
    /// Markers at (x, y).
    Points(Vec<(f64, f64)>, Marker),
    /// A line through (x, y) in drawing order (non-finite points break it).
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
    /// Custom x ticks (position, label) instead of automatic ones.
    pub x_ticks: Option<Vec<(f64, String)>>,
    /// A horizontal reference line at y = 0.
    pub zero_line: bool,
    /// Fixed y range (e.g. shared between panels) instead of the data's.
    pub y_range: Option<(f64, f64)>,
    /// Fixed x range (e.g. shared by the panels of one wrap) instead of the data's.
    pub x_range: Option<(f64, f64)>,
}

/// A chart: the SVG and its number of data layers.
pub struct Chart {
    /// `<svg class="chart">…</svg>`.
    pub svg: String,
    /// Number of `mark` layers (series or bars) in it.
    pub marks: usize,
}

const TEXT: RGBColor = RGBColor(0x22, 0x22, 0x22);
const AXIS: RGBColor = RGBColor(0x44, 0x44, 0x44);
const GRID: RGBColor = RGBColor(0xe6, 0xe6, 0xe6);
const ZERO: RGBColor = RGBColor(0x88, 0x88, 0x88);

/// `#RRGGBB`, as plotters writes colours.
pub fn hex(c: RGBColor) -> String {
    format!("#{:02X}{:02X}{:02X}", c.0, c.1, c.2)
}

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
fn line_style(l: LineStyle) -> ShapeStyle {
    l.color.stroke_width(l.width)
}

fn marker_style(m: Marker) -> ShapeStyle {
    let c = m.color.mix(m.opacity);
    if m.hollow {
        c.stroke_width(1)
    } else {
        c.filled()
    }
}

/// The data points of a series.
fn points(s: &Series) -> &[(f64, f64)] {
    match s {
        Series::Points(xy, _) | Series::Line(xy, _) => xy,
    }
}

fn finite(p: &(f64, f64)) -> bool {
    p.0.is_finite() && p.1.is_finite()
}

/// The drawable pieces of a line: its runs of two or more finite points.
fn runs(xy: &[(f64, f64)]) -> impl Iterator<Item = &[(f64, f64)]> {
    xy.split(|p| !finite(p)).filter(|r| r.len() >= 2)
}

/// True if the series draws anything.
fn drawable(s: &Series) -> bool {
    match s {
        Series::Points(xy, _) => xy.iter().any(finite),
        Series::Line(xy, _) => runs(xy).next().is_some(),
    }
}

/// A series on its panel's chart.
fn draw_data(chart: &mut ChartContext<SVGBackend, Coord>, s: &Series) -> Result<()> {
    match s {
        Series::Points(xy, m) => {
            let style = marker_style(*m);
            let pts = xy.iter().filter(|p| finite(p));
            chart.draw_series(pts.map(|p| Circle::new(*p, m.radius, style)))?;
        }
        Series::Line(xy, l) => {
            for run in runs(xy) {
                let pts = run.iter().copied();
                match l.dash {
                    Dash::Solid => {
                        chart.draw_series(LineSeries::new(pts, line_style(*l)))?;
                    }
                    Dash::Dashed => {
                        chart.draw_series(DashedLineSeries::new(
                            pts,
                            DASH.0,
                            DASH.1,
                            line_style(*l),
                        ))?;
                    }
                    Dash::Dotted => {
                        // Dots of diameter `width` (plotters' radii are whole pixels).
                        let (c, r) = (l.color, l.width / 2);
                        let spacing = DOT_PERIOD.round() as u32;
                        chart.draw_series(DottedLineSeries::new(pts, 0, spacing, move |p| {
                            Circle::new(p, r, c.filled())
                        }))?;
                    }
                }
            }
        }
    }
    Ok(())
}

/// One plotters document of `size`, with its newlines dropped (plotters ends every element
/// with one and pads text with them; the SVG is inlined in the HTML).
fn render(
    size: (u32, u32),
    draw: impl FnOnce(&DrawingArea<SVGBackend, Shift>) -> Result<()>,
) -> Result<String> {
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(&mut buf, size).into_drawing_area();
        draw(&root)?;
        root.present()?;
    }
    buf.retain(|c| c != '\n');
    Ok(buf)
}

/// A layer of a chart: its class and its document.
struct Layer {
    class: &'static str,
    svg: String,
}

/// The chart: the axes and their text under the layers.
fn compose((w, h): (u32, u32), axes: String, labels: &[text::Label], layers: Vec<Layer>) -> Chart {
    let mut svg = format!("<svg class=\"chart\" xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\"><g class=\"axes\">{axes}{}</g>", text::svg(labels));
    for l in &layers {
        svg.push_str(&format!("<g class=\"{}\">{}</g>", l.class, l.svg));
    }
    svg.push_str("</svg>");
    let marks = layers
        .iter()
        .filter(|l| l.class.starts_with("mark"))
        .count();
    Chart { svg, marks }
}

/// The size a figure is laid out to: a width (a journal column or a page), to which the panels
/// reflow, and the height of a page, which no figure exceeds (panels beyond it are left out,
/// and the figure's caption says which are drawn).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Layout {
    /// Total width, px (None: every figure at its natural size).
    pub width_px: Option<u32>,
    /// The tallest a figure may be, px, its legend included (None: no limit).
    pub max_height_px: Option<f64>,
}

/// The narrowest panel a reflowed figure uses, px.
pub const MIN_PANEL_W: u32 = 180;

impl Layout {
    /// A grid of `cols` panels of `w`×`h` px reflowed to the layout's width.
    pub fn grid(&self, cols: usize, w: u32, h: u32) -> (usize, u32, u32) {
        let Some(total) = self.width_px else {
            return (cols.max(1), w, h);
        };
        let cols = cols.min((total / MIN_PANEL_W).max(1) as usize).max(1);
        self.grid_exact(cols, w, h, 1).unwrap_or((cols, w, h))
    }

    /// Exactly `cols` panels of `w`×`h` px reflowed to the layout's width (the height in
    /// proportion, at least 150 px), or None when a panel would be narrower than `min_w` px.
    pub fn grid_exact(&self, cols: usize, w: u32, h: u32, min_w: u32) -> Option<(usize, u32, u32)> {
        let cols = cols.max(1);
        let Some(total) = self.width_px else {
            return Some((cols, w, h));
        };
        let w2 = total / cols as u32;
        let h2 = ((f64::from(h) * f64::from(w2) / f64::from(w)) as u32).max(150);
        (w2 >= min_w).then_some((cols, w2, h2))
    }

    /// A single chart of `w`×`h` px at the layout's width.
    pub fn single(&self, w: u32, h: u32) -> (u32, u32) {
        match self.width_px {
            None => (w, h),
            Some(total) => (
                total,
                ((f64::from(h) * f64::from(total) / f64::from(w)) as u32).max(220),
            ),
        }
    }

    /// How many rows of cells `cell_h` px high fit under `above_px` of legend (at least one).
    pub fn rows_that_fit(&self, cell_h: u32, above_px: f64) -> usize {
        match self.max_height_px {
            None => usize::MAX,
            // Whole pixels: the figure file's height is rounded up.
            Some(m) => {
                let room = m.floor() - above_px.ceil() - 1.0;
                ((room / f64::from(cell_h.max(1))).floor() as usize).max(1)
            }
        }
    }
}

/// Panels on a grid of `cols` columns, each `w` px wide and at least `h` px high (taller where
/// its text needs it, [`cell_height`]).
pub fn figure(panels: &[Panel], cols: usize, w: u32, h: u32) -> Result<Chart> {
    let g = panel::Grid::new(panels, cols, w, h);
    let size = g.size();
    let mut labels = Vec::new();
    let axes = render(size, |root| {
        root.fill(&WHITE)?;
        for (k, (cell, p)) in g.cells(root).iter().zip(panels).enumerate() {
            panel::draw_axes(root, cell, &g, k, p, &mut labels)?;
        }
        Ok(())
    })?;
    let mut layers = Vec::new();
    for (k, (p, f)) in panels.iter().zip(&g.frames).enumerate() {
        for s in p.series.iter().filter(|s| drawable(s)) {
            let svg = render(size, |root| {
                let cells = g.cells(root);
                let mut chart = g
                    .margins
                    .build(&cells[k], f.x, f.y, &f.x_ticks, &f.y_ticks)?;
                draw_data(&mut chart, s)
            })?;
            layers.push(Layer { class: "mark", svg });
        }
    }
    Ok(compose(size, axes, &labels, layers))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_are_short() {
        assert_eq!(tick_label(1.5, 0.5), "1.5");
        assert_eq!(tick_label(20.0, 5.0), "20");
        assert_eq!(tick_label(0.25, 0.25), "0.25");
        assert_eq!(tick_label(-0.0, 0.1), "0.0");
        assert_eq!(tick_label(-2.0, 1.0), "−2");
        let t = auto_ticks(0.13, 1.87, 6);
        assert!(t.len() >= 3 && t.iter().all(|(v, _)| (0.13..=1.87).contains(v)));
    }

    #[test]
    fn every_drawn_series_is_a_mark_layer_over_the_axes() {
        let panel = Panel {
            title: "t".into(),
            series: vec![
                Series::Points(vec![(0.0, 1.0), (1.0, 2.0)], marker()),
                Series::Line(vec![(0.0, 1.0), (f64::NAN, 0.0), (1.0, 2.0)], dashed()),
                Series::Line(vec![(0.0, 1.0), (1.0, 2.0), (2.0, 2.5)], dashed()),
            ],
            ..Panel::default()
        };
        let c = figure(&[panel], 1, 300, 200).unwrap();
        // The broken line has no two consecutive finite points: no layer.
        assert_eq!(c.marks, 2);
        assert_eq!(c.svg.matches("<g class=\"mark\">").count(), 2);
        let axes = &c.svg[..c.svg.find("<g class=\"mark\">").unwrap()];
        assert!(axes.contains("<g class=\"axes\">") && !axes.contains("#0072B2"));
        // Dashes are drawn as separate pieces.
        assert!(c.svg.matches("<polyline").count() > 3);
    }

    fn marker() -> Marker {
        Marker {
            color: RGBColor(0x00, 0x72, 0xB2),
            radius: 2,
            hollow: false,
            opacity: 0.5,
        }
    }

    fn dashed() -> LineStyle {
        LineStyle {
            color: RGBColor(0x00, 0x72, 0xB2),
            width: 2,
            dash: Dash::Dashed,
        }
    }
}
