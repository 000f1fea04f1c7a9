//! SVG figures (plotters, SVG backend only: text is emitted as SVG <text>, so no font library
//! is needed at build or run time).

use plotters::prelude::*;

/// A series on a panel.
pub enum Series {
    /// Markers.
    Points {
        /// (x, y).
        xy: Vec<(f64, f64)>,
        /// Colour.
        color: RGBColor,
        /// Legend label.
        label: String,
        /// Marker radius, px.
        size: u32,
    },
    /// A polyline.
    Line {
        /// (x, y) in drawing order.
        xy: Vec<(f64, f64)>,
        /// Colour.
        color: RGBColor,
        /// Legend label.
        label: String,
        /// Stroke width.
        width: u32,
    },
}

/// One panel.
pub struct Panel {
    /// Caption.
    pub title: String,
    /// x-axis label.
    pub x_label: String,
    /// y-axis label.
    pub y_label: String,
    /// Series.
    pub series: Vec<Series>,
    /// Draw a legend.
    pub legend: bool,
}

/// Palette.
pub const COLORS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(90, 90, 90),
];

fn range(series: &[Series], pick: fn(&(f64, f64)) -> f64) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for s in series {
        let xy = match s {
            Series::Points { xy, .. } | Series::Line { xy, .. } => xy,
        };
        for p in xy {
            let v = pick(p);
            if v.is_finite() {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    if hi - lo < 1e-12 {
        return (lo - 0.5, hi + 0.5);
    }
    let pad = 0.05 * (hi - lo);
    (lo - pad, hi + pad)
}

/// Panels on a grid of `cols` columns, each `w`×`h` px: an SVG document.
pub fn grid(panels: &[Panel], cols: usize, w: u32, h: u32) -> anyhow::Result<String> {
    let rows = panels.len().div_ceil(cols.max(1));
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(&mut buf, (w * cols as u32, h * rows as u32))
            .into_drawing_area();
        root.fill(&WHITE).map_err(|e| anyhow::anyhow!("{e:?}"))?;
        let areas = root.split_evenly((rows, cols));
        for (panel, area) in panels.iter().zip(areas.iter()) {
            draw_panel(panel, area).map_err(|e| anyhow::anyhow!("{e:?}"))?;
        }
        root.present().map_err(|e| anyhow::anyhow!("{e:?}"))?;
    }
    Ok(buf)
}

fn draw_panel<DB: DrawingBackend>(
    p: &Panel,
    area: &DrawingArea<DB, plotters::coord::Shift>,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let (x0, x1) = range(&p.series, |v| v.0);
    let (y0, y1) = range(&p.series, |v| v.1);
    let mut chart = ChartBuilder::on(area)
        .caption(&p.title, ("sans-serif", 14))
        .margin(6)
        .x_label_area_size(32)
        .y_label_area_size(46)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    chart
        .configure_mesh()
        .x_desc(p.x_label.as_str())
        .y_desc(p.y_label.as_str())
        .label_style(("sans-serif", 11))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()?;
    for s in &p.series {
        match s {
            Series::Points {
                xy,
                color,
                label,
                size,
            } => {
                let c = *color;
                let r = *size;
                let ann = chart.draw_series(
                    xy.iter()
                        .filter(|v| v.0.is_finite() && v.1.is_finite())
                        .map(move |v| Circle::new(*v, r, c.mix(0.55).filled())),
                )?;
                if !label.is_empty() {
                    ann.label(label.as_str())
                        .legend(move |(x, y)| Circle::new((x + 8, y), 3, c.filled()));
                }
            }
            Series::Line {
                xy,
                color,
                label,
                width,
            } => {
                let c = *color;
                let style = ShapeStyle::from(&c).stroke_width(*width);
                let pts: Vec<(f64, f64)> = xy
                    .iter()
                    .copied()
                    .filter(|v| v.0.is_finite() && v.1.is_finite())
                    .collect();
                let ann = chart.draw_series(LineSeries::new(pts, style))?;
                if !label.is_empty() {
                    ann.label(label.as_str()).legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 16, y)], c.stroke_width(2))
                    });
                }
            }
        }
    }
    if p.legend {
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(RGBColor(200, 200, 200))
            .label_font(("sans-serif", 11))
            .position(SeriesLabelPosition::UpperLeft)
            .draw()?;
    }
    Ok(())
}
