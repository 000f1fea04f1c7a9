//! The report's figures. One colour per wrap in every figure (Okabe-Ito, safe for the common
//! colour-vision deficiencies), one line style per model (Euler-Eytelwein dashed, Table 3
//! dotted, extended solid and thick), a legend above each figure. Every curve of a model is
//! drawn through that model's predictions as written to `predictions.csv`; the evidence panels
//! come from `metrics.json`. Every name on a figure is in words (the catalogue's labels, the
//! models' names as the report writes them), and no figure is taller than the layout's page:
//! where a data set has more cords, diameters or runs than fit, the figure draws an evenly
//! spaced selection and its caption says so.
//!
//! * [`cord_grid`]: the cords' panels as the experiment's diameter × wrap table.
//! * [`curves`]: T2 and amplification against T1 with the three models, and the closed loop.
//! * [`evidence`]: residuals, the mechanism evidence, and the gain (RMSE by model).
//! * [`tracking`]: force control's target against the measured T2, and its Bode plot.

pub mod cord_grid;
pub mod curves;
pub mod evidence;
pub mod tracking;

use super::plot::{Chart, Dash, Entry, Key, Layout, LineStyle, Marker};
use capstan_engine::analysis::closed_loop::SimCurve;
use capstan_engine::analysis::Analysis;
use capstan_engine::fit::stats::distinct;
use plotters::style::RGBColor;

/// The most markers (or line vertices) drawn per cord and series: a million-row data set
/// would otherwise make an SVG of hundreds of megabytes that no browser opens.
pub const MAX_DRAWN_PER_CORD: usize = 2_000;

/// At most [`MAX_DRAWN_PER_CORD`] of `v`, evenly spaced (every k-th, in the given order).
pub fn drawn<T>(v: Vec<T>) -> Vec<T> {
    let k = v.len().div_ceil(MAX_DRAWN_PER_CORD).max(1);
    v.into_iter().step_by(k).collect()
}

/// The caption's sentence when some cord has more rows than are drawn (empty otherwise).
pub fn drawn_note(a: &Analysis) -> String {
    let most = (0..a.obs.groups.len())
        .map(|g| a.obs.rows_of_group(g).len())
        .max()
        .unwrap_or(0);
    if most <= MAX_DRAWN_PER_CORD {
        return String::new();
    }
    format!(
        " With up to {most} rows per cord, every {}-th is drawn (at most {MAX_DRAWN_PER_CORD} \
         per cord and series); every statistic uses all {} rows.",
        most.div_ceil(MAX_DRAWN_PER_CORD),
        a.obs.len()
    )
}

/// The Okabe-Ito palette without yellow (poor on white) and black (kept for annotations).
pub const OKABE_ITO: [RGBColor; 6] = [
    RGBColor(0x00, 0x72, 0xB2),
    RGBColor(0xE6, 0x9F, 0x00),
    RGBColor(0x00, 0x9E, 0x73),
    RGBColor(0xD5, 0x5E, 0x00),
    RGBColor(0xCC, 0x79, 0xA7),
    RGBColor(0x56, 0xB4, 0xE9),
];
/// Neutral colour of the model line samples in legends and of annotations.
pub const INK: RGBColor = RGBColor(0x33, 0x33, 0x33);

/// Euler-Eytelwein with one mu: thin dashes.
pub fn baseline_style(color: RGBColor) -> LineStyle {
    LineStyle {
        color,
        width: 2,
        dash: Dash::Dashed,
    }
}

/// The thesis's Table 3: dots.
pub fn thesis_style(color: RGBColor) -> LineStyle {
    LineStyle {
        color,
        width: 2,
        dash: Dash::Dotted,
    }
}

/// The extended model: thick and solid.
pub fn extended_style(color: RGBColor) -> LineStyle {
    LineStyle {
        color,
        width: 3,
        dash: Dash::Solid,
    }
}

/// The extended model as the sensors would read it: thin and solid.
pub fn as_read_style(color: RGBColor) -> LineStyle {
    LineStyle {
        color,
        width: 1,
        dash: Dash::Solid,
    }
}

/// A measured point.
pub fn measured(color: RGBColor) -> Marker {
    Marker {
        color,
        radius: 2,
        hollow: false,
        opacity: 0.5,
    }
}

/// A per-cord summary point: a disc on the smallest capstan, a ring on the others.
pub fn cord_marker(color: RGBColor, hollow: bool) -> Marker {
    Marker {
        color,
        radius: 5,
        hollow,
        opacity: 0.9,
    }
}

/// Colours by wrap angle.
pub struct Palette {
    wraps: Vec<f64>,
}

impl Palette {
    /// The data's wraps, in order.
    pub fn new(a: &Analysis) -> Self {
        Palette {
            wraps: distinct(a.obs.groups.iter().map(|g| g.wrap_deg)),
        }
    }

    /// The colour of `wrap_deg` (colours repeat after six wraps).
    pub fn color(&self, wrap_deg: f64) -> RGBColor {
        let k = self.wraps.iter().position(|w| *w == wrap_deg).unwrap_or(0);
        OKABE_ITO[k % OKABE_ITO.len()]
    }

    /// Index of `wrap_deg` among the wraps.
    pub fn index(&self, wrap_deg: f64) -> usize {
        self.wraps.iter().position(|w| *w == wrap_deg).unwrap_or(0)
    }

    /// Number of wraps.
    pub fn len(&self) -> usize {
        self.wraps.len()
    }

    /// True without wraps.
    pub fn is_empty(&self) -> bool {
        self.wraps.is_empty()
    }

    /// Legend entries: one coloured disc per wrap; with more wraps than colours, one per
    /// colour naming its wraps (the first three and how many more).
    pub fn legend(&self) -> Vec<Entry> {
        let n = OKABE_ITO.len().min(self.wraps.len());
        (0..n)
            .map(|k| {
                let wraps: Vec<String> = self
                    .wraps
                    .iter()
                    .skip(k)
                    .step_by(OKABE_ITO.len())
                    .map(|w| format!("{w:.0}°"))
                    .collect();
                let label = match wraps.len() {
                    1 => format!("{} wrap", wraps[0]),
                    m if m <= 3 => format!("{} wraps", wraps.join(", ")),
                    m => format!("{} and {} more wraps", wraps[..3].join(", "), m - 3),
                };
                Entry {
                    key: Key::Marker(Marker {
                        opacity: 1.0,
                        ..measured(OKABE_ITO[k])
                    }),
                    label,
                }
            })
            .collect()
    }
}

/// A model's name in words ([`capstan_engine::analysis::ModelMetrics::name`] is an identifier).
pub fn model_label(name: &str) -> String {
    match name {
        "baseline" => "Euler-Eytelwein, one mu".into(),
        "baseline_per_cord" => "Euler-Eytelwein, a mu per cord".into(),
        "thesis" => "thesis Table 3".into(),
        "extended" => "extended model".into(),
        other => other.replace('_', " "),
    }
}

/// How many panels of a grid fit the layout's page: the rows of cells (`cols` of `w` px, at
/// least `h` high, with these titles and x label) under the legend, times the columns.
pub fn panels_that_fit(
    layout: &Layout,
    (cols, w, h): (usize, u32, u32),
    titles: &[&str],
    x_label: &str,
    legend: &[Entry],
) -> usize {
    let cell_h = crate::plot::cell_height(titles, &[x_label], w, h);
    let above = super::plot::legend::legend_height(legend, f64::from(w) * cols as f64);
    layout.rows_that_fit(cell_h, above).saturating_mul(cols)
}

/// The caption's sentence when `shown` of `n` things (cords, diameters, runs) have a panel.
pub fn selection_note(shown: usize, n: usize, what: &str) -> String {
    if shown >= n {
        String::new()
    } else {
        format!(
            " {shown} of the {n} {what} are drawn (as many as fit a page), evenly spaced in their order; predictions.csv and the tables hold every one."
        )
    }
}

/// Legend entries of the three models (line styles in a neutral colour).
pub fn model_legend(with_thesis: bool) -> Vec<Entry> {
    let mut v = vec![Entry {
        key: Key::Line(baseline_style(INK)),
        label: "Euler-Eytelwein, one mu (baseline)".into(),
    }];
    if with_thesis {
        v.push(Entry {
            key: Key::Line(thesis_style(INK)),
            label: "thesis Table 3".into(),
        });
    }
    v.push(Entry {
        key: Key::Line(extended_style(INK)),
        label: "extended model, friction law alone".into(),
    });
    v.push(Entry {
        key: Key::Line(as_read_style(INK)),
        label: "extended model, as the sensors would read".into(),
    });
    v
}

/// Legend entries for the capstan diameters (disc: smallest, ring: others).
pub fn diameter_legend(a: &Analysis) -> Vec<Entry> {
    a.obs
        .diameters()
        .iter()
        .enumerate()
        .map(|(k, d)| Entry {
            key: Key::Marker(cord_marker(INK, k > 0)),
            label: format!("D = {d} mm"),
        })
        .collect()
}

/// A figure of the report.
pub struct Figure {
    /// `data-figure` id.
    pub id: &'static str,
    /// The legend above the chart (HTML).
    pub legend: Vec<Entry>,
    /// The chart.
    pub chart: Chart,
    /// Caption.
    pub caption: String,
}

/// Every figure, in report order.
pub fn all(
    a: &Analysis,
    closed_loop: Option<&[SimCurve]>,
    layout: &Layout,
) -> crate::error::Result<Vec<Figure>> {
    let pal = Palette::new(a);
    let mut figs = vec![
        evidence::gain(a, layout)?,
        curves::t2_vs_t1(a, &pal, layout)?,
        curves::amp_vs_t1(a, &pal, layout)?,
        evidence::residuals(a, &pal, layout)?,
        evidence::mechanisms(a, &pal, layout)?,
    ];
    if let Some(cl) = closed_loop {
        figs.push(curves::closed_loop(a, &pal, cl, layout)?);
    }
    Ok(figs)
}
