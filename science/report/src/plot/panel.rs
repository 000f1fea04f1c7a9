//! A grid of panels laid out for its text: every title, tick label and axis label is measured
//! ([`super::text`]) and the plot areas are what is left, the same in every panel of a figure
//! (so that they align). Titles and axis labels wrap (and shrink only where one word is wider
//! than its room); tick labels thin out until neighbours keep apart; a cell grows to keep its
//! plot area [`MIN_PLOT_H`] high.

use super::axis::{fitted_ticks, ranges, Axis, Coord};
use super::text::{fit, wrap, Anchor, Font, Label, ASCENT, DESCENT};
use super::{Panel, AXIS, GRID, ZERO};
use crate::error::Result;
use plotters::coord::Shift;
use plotters::prelude::*;

/// Panel titles.
pub const TITLE: Font = Font::bold(14.0);
/// Axis labels.
pub const LABEL: Font = Font::regular(13.0);
/// Tick labels: the layout's base size (the `font_pt` of the figure files).
pub const TICK: Font = Font::regular(12.0);
/// Space at a cell's edges, px.
pub(super) const PAD: f64 = 3.0;
/// Space between a text and what it labels, px.
pub(super) const GAP: f64 = 3.0;
/// Length of a tick mark, px.
pub(super) const TICK_LEN: f64 = 4.0;
/// The least height of a plot area, px.
pub const MIN_PLOT_H: f64 = 100.0;
/// The least space between neighbouring tick labels, px.
const TICK_GAP: f64 = 8.0;

/// `s` wrapped to `max` px in `font` (shrunk where one word is wider): its lines and font.
pub(super) fn lines(s: &str, font: Font, max: f64) -> (Vec<String>, Font) {
    if s.trim().is_empty() {
        return (Vec::new(), font);
    }
    let l = wrap(s, font, max);
    let f = fit(&l, font, max);
    (l, f)
}

/// The space above a plot area for titles wrapped to a `w` px cell.
fn top(titles: &[&str], w: f64) -> f64 {
    let block = titles
        .iter()
        .map(|t| {
            let (l, f) = lines(t, TITLE, w - 2.0 * PAD);
            f.block(l.len())
        })
        .fold(0.0, f64::max);
    if block > 0.0 {
        PAD + block + 2.0 * GAP
    } else {
        PAD + 2.0 * GAP
    }
}

/// The space below a plot area: tick marks and labels, and the x labels wrapped to the cell.
fn bottom(x_labels: &[&str], w: f64) -> f64 {
    let block = x_labels
        .iter()
        .map(|t| {
            let (l, f) = lines(t, LABEL, w - 2.0 * PAD);
            f.block(l.len())
        })
        .fold(0.0, f64::max);
    TICK_LEN + GAP + TICK.height() + if block > 0.0 { GAP + block } else { 0.0 } + PAD
}

/// The height of a cell `w` px wide for panels with these titles and x labels: at least
/// `h`, and enough for a plot area of [`MIN_PLOT_H`].
pub fn cell_height(titles: &[&str], x_labels: &[&str], w: u32, h: u32) -> u32 {
    let w = f64::from(w);
    let need = top(titles, w) + bottom(x_labels, w) + MIN_PLOT_H;
    h.max(need.ceil() as u32)
}

/// The margins of the plot area inside a cell, px.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct Margins {
    pub(super) left: f64,
    pub(super) right: f64,
    pub(super) top: f64,
    pub(super) bottom: f64,
}

impl Margins {
    /// Plotters' plot area inside a cell: the margins in whole pixels.
    pub(super) fn build<'a, 'b>(
        &self,
        cell: &'a DrawingArea<SVGBackend<'b>, Shift>,
        x: (f64, f64),
        y: (f64, f64),
        x_ticks: &[(f64, String)],
        y_ticks: &[(f64, String)],
    ) -> Result<ChartContext<'a, SVGBackend<'b>, Coord>> {
        Ok(ChartBuilder::on(cell)
            .margin_left(self.left.round() as u32)
            .margin_right(self.right.round() as u32)
            .margin_top(self.top.round() as u32)
            .margin_bottom(self.bottom.round() as u32)
            .build_cartesian_2d(Axis::new(x, x_ticks), Axis::new(y, y_ticks))?)
    }
}

/// One panel's coordinates and text, laid out.
pub(super) struct Frame {
    pub(super) x: (f64, f64),
    pub(super) y: (f64, f64),
    pub(super) x_ticks: Vec<(f64, String)>,
    pub(super) y_ticks: Vec<(f64, String)>,
    title: (Vec<String>, Font),
    x_label: (Vec<String>, Font),
    y_label: (Vec<String>, Font),
}

/// A grid of panels, laid out.
pub(super) struct Grid {
    pub(super) cols: usize,
    pub(super) rows: usize,
    pub(super) cell: (u32, u32),
    pub(super) margins: Margins,
    pub(super) frames: Vec<Frame>,
}

impl Frame {
    /// Panel `p`'s ranges, y ticks and wrapped text in a cell `w` px wide whose plot area is
    /// `plot_h` px high (its x ticks come with the plot's width, [`fit_x_ticks`]).
    fn new(p: &Panel, w: f64, plot_h: f64) -> Frame {
        let (x, y) = ranges(p);
        let most = ((plot_h / (TICK.height() + 8.0)) as usize).clamp(2, 6);
        Frame {
            x,
            y,
            x_ticks: Vec::new(),
            y_ticks: fitted_ticks(None, y, plot_h, most, 4.0, |_| TICK.height()),
            title: lines(&p.title, TITLE, w - 2.0 * PAD),
            x_label: lines(&p.x_label, LABEL, w - 2.0 * PAD),
            y_label: lines(&p.y_label, LABEL, plot_h),
        }
    }

    /// The space left of the plot area: the turned y label and the y tick labels.
    fn left(&self) -> f64 {
        let widest = (self.y_ticks.iter())
            .map(|t| TICK.width(&t.1))
            .fold(0.0, f64::max);
        let label = self.y_label.1.block(self.y_label.0.len());
        PAD + if label > 0.0 { label + GAP } else { 0.0 } + widest + GAP + TICK_LEN
    }
}

/// The x ticks of every frame for a plot area between `left` and the right margin, and that
/// margin: what the last x tick label reaches past the plot area (fit the ticks, widen, fit
/// again).
fn fit_x_ticks(frames: &mut [Frame], panels: &[Panel], w: f64, left: f64) -> f64 {
    let mut right = PAD + 6.0;
    for _ in 0..3 {
        let plot_w = w - left - right;
        let mut reach = 0.0f64;
        for (f, p) in frames.iter_mut().zip(panels) {
            let most = ((plot_w / 36.0) as usize).clamp(2, 8);
            f.x_ticks = fitted_ticks(p.x_ticks.as_ref(), f.x, plot_w, most, TICK_GAP, |s| {
                TICK.width(s)
            });
            for (v, s) in &f.x_ticks {
                let at = super::axis::px(*v, f.x, plot_w);
                reach = reach.max(at + TICK.width(s) / 2.0 - plot_w);
            }
        }
        let need = PAD + reach.max(6.0);
        if need <= right {
            break;
        }
        right = need;
    }
    right
}

impl Grid {
    /// `panels` on `cols` columns of cells `w` px wide and at least `h` high.
    pub(super) fn new(panels: &[Panel], cols: usize, w: u32, h: u32) -> Grid {
        let cols = cols.max(1);
        let titles: Vec<&str> = panels.iter().map(|p| p.title.as_str()).collect();
        let xl: Vec<&str> = panels.iter().map(|p| p.x_label.as_str()).collect();
        let h = cell_height(&titles, &xl, w, h);
        let wf = f64::from(w);
        let (t, b) = (top(&titles, wf), bottom(&xl, wf));
        let plot_h = f64::from(h) - t - b;
        let mut frames: Vec<Frame> = panels.iter().map(|p| Frame::new(p, wf, plot_h)).collect();
        let left = frames.iter().map(Frame::left).fold(0.0, f64::max);
        let right = fit_x_ticks(&mut frames, panels, wf, left);
        Grid {
            cols,
            rows: panels.len().div_ceil(cols).max(1),
            cell: (w, h),
            margins: Margins {
                left,
                right,
                top: t,
                bottom: b,
            },
            frames,
        }
    }

    /// The whole grid's size, px.
    pub(super) fn size(&self) -> (u32, u32) {
        (
            self.cell.0 * self.cols as u32,
            self.cell.1 * self.rows as u32,
        )
    }

    /// The top-left corner of panel `k`, px.
    fn origin(&self, k: usize) -> (f64, f64) {
        (
            f64::from(self.cell.0) * (k % self.cols) as f64,
            f64::from(self.cell.1) * (k / self.cols) as f64,
        )
    }

    /// The cells, in panel order.
    pub(super) fn cells<'b>(
        &self,
        root: &DrawingArea<SVGBackend<'b>, Shift>,
    ) -> Vec<DrawingArea<SVGBackend<'b>, Shift>> {
        root.split_evenly((self.rows, self.cols))
    }
}

/// Grid lines, axes, tick marks and the zero line of panel `k` (on `root`, whose pixels are
/// the backend's), and its text as labels.
pub(super) fn draw_axes(
    root: &DrawingArea<SVGBackend, Shift>,
    cell: &DrawingArea<SVGBackend, Shift>,
    g: &Grid,
    k: usize,
    p: &Panel,
    labels: &mut Vec<Label>,
) -> Result<()> {
    let f = &g.frames[k];
    let mut chart = g.margins.build(cell, f.x, f.y, &f.x_ticks, &f.y_ticks)?;
    for (t, _) in &f.x_ticks {
        chart.draw_series(LineSeries::new([(*t, f.y.0), (*t, f.y.1)], GRID))?;
    }
    for (t, _) in &f.y_ticks {
        chart.draw_series(LineSeries::new([(f.x.0, *t), (f.x.1, *t)], GRID))?;
    }
    if p.zero_line && f.y.0 < 0.0 && f.y.1 > 0.0 {
        chart.draw_series(LineSeries::new([(f.x.0, 0.0), (f.x.1, 0.0)], ZERO))?;
    }
    let corner = chart.backend_coord(&(f.x.0, f.y.0));
    let far = chart.backend_coord(&(f.x.1, f.y.1));
    root.draw(&PathElement::new(
        vec![(corner.0, far.1), corner, (far.0, corner.1)],
        AXIS,
    ))?;
    let tick = TICK_LEN as i32;
    let below = f64::from(corner.1) + TICK_LEN + GAP;
    for (t, s) in &f.x_ticks {
        let (x, y) = chart.backend_coord(&(*t, f.y.0));
        root.draw(&PathElement::new(vec![(x, y), (x, y + tick)], AXIS))?;
        let at = (f64::from(x), below + ASCENT * TICK.px);
        labels.push(Label::new(s.clone(), at, TICK, Anchor::Middle));
    }
    let lift = (ASCENT - DESCENT) / 2.0 * TICK.px;
    for (t, s) in &f.y_ticks {
        let (x, y) = chart.backend_coord(&(f.x.0, *t));
        root.draw(&PathElement::new(vec![(x - tick, y), (x, y)], AXIS))?;
        let at = (f64::from(x) - TICK_LEN - GAP, f64::from(y) + lift);
        labels.push(Label::new(s.clone(), at, TICK, Anchor::End));
    }
    let plot = (
        (f64::from(corner.0), f64::from(far.1)),
        (f64::from(far.0), f64::from(corner.1)),
    );
    panel_text(g, k, plot, labels);
    Ok(())
}

/// Panel `k`'s title (centred on its cell), x label (under the tick labels, centred on the
/// plot area but inside the cell) and y label (turned, at the cell's left, centred on the plot
/// area); `plot` is the plot area's top-left and bottom-right corner, px.
fn panel_text(g: &Grid, k: usize, plot: ((f64, f64), (f64, f64)), labels: &mut Vec<Label>) {
    let f = &g.frames[k];
    let (ox, oy) = g.origin(k);
    let w = f64::from(g.cell.0);
    let ((x0, y0), (x1, y1)) = plot;
    let (tl, tf) = &f.title;
    for (i, line) in tl.iter().enumerate() {
        let y = oy + PAD + ASCENT * tf.px + i as f64 * tf.line();
        labels.push(Label::new(
            line.clone(),
            (ox + w / 2.0, y),
            *tf,
            Anchor::Middle,
        ));
    }
    let below = y1 + TICK_LEN + GAP + TICK.height() + GAP;
    let (xl, xf) = &f.x_label;
    for (i, line) in xl.iter().enumerate() {
        let half = xf.width(line) / 2.0;
        let x = ((x0 + x1) / 2.0).clamp(ox + PAD + half, ox + w - PAD - half);
        let y = below + ASCENT * xf.px + i as f64 * xf.line();
        labels.push(Label::new(line.clone(), (x, y), *xf, Anchor::Middle));
    }
    let (yl, yf) = &f.y_label;
    for (i, line) in yl.iter().enumerate() {
        let x = ox + PAD + ASCENT * yf.px + i as f64 * yf.line();
        labels.push(Label {
            turned: true,
            ..Label::new(line.clone(), (x, (y0 + y1) / 2.0), *yf, Anchor::Middle)
        });
    }
}
