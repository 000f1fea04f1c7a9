//! Figure files: each figure of the report as a standalone SVG (legend inside, white
//! background, sized in millimetres for a journal column), and from that same SVG a PNG
//! (resvg, 300 dpi) and a PDF (svg2pdf, text kept as text). The report embeds the same SVG, so
//! the report's figures and the files come from one code path. No external program runs.
//!
//! Sizes: the layout is `width_mm` wide, and its base text (the tick labels) comes out at
//! `font_pt`; the panels reflow to that width ([`crate::plot::Layout`]).

use crate::cells::esc;
use crate::figures::Figure;
use crate::plot::{hex, Dash, Entry, Key, Layout, DASH, DOT_PERIOD};
use anyhow::{bail, Context as _, Result};
use std::fmt::Write as _;
use std::sync::Arc;

/// A figure file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// Standalone SVG.
    Svg,
    /// PNG at [`PNG_DPI`].
    Png,
    /// PDF, one page.
    Pdf,
}

impl Format {
    /// File extension.
    pub fn ext(self) -> &'static str {
        match self {
            Format::Svg => "svg",
            Format::Png => "png",
            Format::Pdf => "pdf",
        }
    }

    /// Parse "svg,png,pdf".
    pub fn parse_list(s: &str) -> Result<Vec<Format>> {
        let mut out = Vec::new();
        for part in s.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            let f = match part.to_ascii_lowercase().as_str() {
                "svg" => Format::Svg,
                "png" => Format::Png,
                "pdf" => Format::Pdf,
                other => bail!("--figures {s}: unknown format {other:?} (svg, png or pdf)"),
            };
            if !out.contains(&f) {
                out.push(f);
            }
        }
        if out.is_empty() {
            bail!("--figures {s:?}: name at least one of svg, png, pdf");
        }
        Ok(out)
    }
}

/// Resolution of the PNG files, dots per inch.
pub const PNG_DPI: f64 = 300.0;
/// Tick-label size of the layout, px ([`crate::plot`]'s base text size).
const BASE_TEXT_PX: f64 = 12.0;
const MM_PER_PT: f64 = 25.4 / 72.0;

/// Which figure files to write, and their size.
#[derive(Clone, Debug, PartialEq)]
pub struct FigureOptions {
    /// Formats (empty: no files; the report still shows the figures).
    pub formats: Vec<Format>,
    /// Width, mm (85: one journal column; 170: the page).
    pub width_mm: f64,
    /// Size of the base text (tick labels), pt.
    pub font_pt: f64,
}

impl Default for FigureOptions {
    fn default() -> Self {
        FigureOptions {
            formats: Vec::new(),
            width_mm: 170.0,
            font_pt: 8.0,
        }
    }
}

impl FigureOptions {
    /// Check the sizes.
    pub fn check(&self) -> Result<()> {
        if !(self.width_mm.is_finite() && (40.0..=400.0).contains(&self.width_mm)) {
            bail!(
                "--width-mm {}: must be 40 to 400 (85 for a journal column, 170 for a page)",
                self.width_mm
            );
        }
        if !(self.font_pt.is_finite() && (4.0..=24.0).contains(&self.font_pt)) {
            bail!("--font-pt {}: must be 4 to 24", self.font_pt);
        }
        Ok(())
    }

    /// Pixels of the layout per millimetre: the base text at `font_pt`.
    fn px_per_mm(&self) -> f64 {
        BASE_TEXT_PX / (self.font_pt * MM_PER_PT)
    }

    /// The layout the figures are drawn to.
    pub fn layout(&self) -> Layout {
        Layout {
            width_px: Some((self.width_mm * self.px_per_mm()).round() as u32),
        }
    }
}

/// The chart's width and height, px, from its `<svg ... width=".." height="..">`.
fn chart_size(svg: &str) -> (f64, f64) {
    let attr = |name: &str| {
        let k = svg.find(&format!(" {name}=\""))? + name.len() + 3;
        svg[k..].split('"').next()?.parse::<f64>().ok()
    };
    (
        attr("width").unwrap_or(800.0),
        attr("height").unwrap_or(400.0),
    )
}

const LEGEND_PX: f64 = 12.0;
const ROW_H: f64 = 18.0;

/// The legend as SVG, in rows across `width` px: its markup and its height.
fn legend_svg(entries: &[Entry], width: f64) -> (String, f64) {
    let mut s = String::from("<g class=\"legend\">");
    let (mut x, mut y) = (6.0, 4.0);
    for e in entries {
        // Text width estimated at 0.55 em per character (Helvetica's mean).
        let w = 32.0 + 0.55 * LEGEND_PX * e.label.chars().count() as f64 + 14.0;
        if x > 6.0 && x + w > width {
            x = 6.0;
            y += ROW_H;
        }
        let cy = y + ROW_H / 2.0;
        let key = match e.key {
            Key::Marker(m) => {
                let (c, r) = (hex(m.color), f64::from(m.radius).max(4.0));
                let paint = if m.hollow {
                    format!("fill=\"none\" stroke=\"{c}\" stroke-width=\"1.3\"")
                } else {
                    format!("fill=\"{c}\"")
                };
                format!(
                    "<circle cx=\"{:.1}\" cy=\"{cy:.1}\" r=\"{r}\" {paint}/>",
                    x + 13.0
                )
            }
            Key::Line(l) => {
                let dash = match l.dash {
                    Dash::Solid => String::new(),
                    Dash::Dashed => format!(" stroke-dasharray=\"{} {}\"", DASH.0, DASH.1),
                    Dash::Dotted => format!(
                        " stroke-dasharray=\"0.1 {}\" stroke-linecap=\"round\"",
                        DOT_PERIOD - 0.1
                    ),
                };
                format!(
                    "<line x1=\"{:.1}\" y1=\"{cy:.1}\" x2=\"{:.1}\" y2=\"{cy:.1}\" stroke=\"{}\" stroke-width=\"{}\"{dash}/>",
                    x + 1.0,
                    x + 25.0,
                    hex(l.color),
                    l.width
                )
            }
        };
        let _ = write!(
            s,
            "{key}<text x=\"{:.1}\" y=\"{:.1}\" font-family=\"Helvetica, Arial, sans-serif\" font-size=\"{LEGEND_PX}\" fill=\"#222222\">{}</text>",
            x + 30.0,
            cy + 4.0,
            esc(&e.label)
        );
        x += w;
    }
    s.push_str("</g>");
    (s, y + ROW_H + 4.0)
}

/// The chart with its layers' own `<svg>` documents turned into groups: every layer has the
/// chart's size and origin, so nothing moves, and a renderer need not clip and composite one
/// full-size canvas per layer (resvg does: 50 layers made a PNG 20 times slower).
fn flatten_layers(chart: &str) -> String {
    let Some(open_end) = chart.find('>') else {
        return chart.to_string();
    };
    let Some(close) = chart.rfind("</svg>") else {
        return chart.to_string();
    };
    let (head, inner, tail) = (
        &chart[..=open_end],
        &chart[open_end + 1..close],
        &chart[close..],
    );
    let mut out = String::with_capacity(chart.len());
    out.push_str(head);
    let mut rest = inner;
    while let Some(k) = rest.find("<svg") {
        out.push_str(&rest[..k].replace("</svg>", "</g>"));
        match rest[k..].find('>') {
            Some(e) => {
                out.push_str("<g>");
                rest = &rest[k + e + 1..];
            }
            None => {
                rest = &rest[k..];
                break;
            }
        }
    }
    out.push_str(&rest.replace("</svg>", "</g>"));
    out.push_str(tail);
    out
}

/// A figure as a standalone SVG document: white background, "Figure N" and the legend above
/// the chart, `width_mm` wide (None: in pixels, as the report shows it).
pub fn standalone_svg(f: &Figure, number: usize, width_mm: Option<f64>) -> String {
    let (w, h_chart) = chart_size(&f.chart.svg);
    let (legend, legend_h) = legend_svg(&f.legend, w);
    let title_h = 20.0;
    let h = title_h + legend_h + h_chart;
    let size = match width_mm {
        Some(mm) => format!("width=\"{mm}mm\" height=\"{:.2}mm\"", mm * h / w),
        None => format!("width=\"{w}\" height=\"{h}\""),
    };
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"figure-file\" {size} viewBox=\"0 0 {w} {h}\"><rect width=\"{w}\" height=\"{h}\" fill=\"#FFFFFF\"/><text x=\"6\" y=\"15\" font-family=\"Helvetica, Arial, sans-serif\" font-size=\"13\" font-weight=\"bold\" fill=\"#222222\">Figure {number}</text><g transform=\"translate(0 {title_h})\">{legend}</g><g transform=\"translate(0 {:.1})\">{}</g></svg>",
        title_h + legend_h,
        flatten_layers(&f.chart.svg)
    )
}

/// The system's fonts, with a sans-serif family that exists (Helvetica, Arial, Liberation
/// Sans or DejaVu Sans, the first found).
fn fonts() -> Arc<resvg::usvg::fontdb::Database> {
    let mut db = resvg::usvg::fontdb::Database::new();
    db.load_system_fonts();
    let have = |name: &str| {
        db.faces()
            .any(|f| f.families.iter().any(|(n, _)| n == name))
    };
    if let Some(name) = ["Helvetica", "Arial", "Liberation Sans", "DejaVu Sans"]
        .into_iter()
        .find(|n| have(n))
    {
        db.set_sans_serif_family(name);
    }
    Arc::new(db)
}

/// Whether the system has any font to draw text with (PNG and PDF need one).
pub fn have_fonts() -> bool {
    !fonts().is_empty()
}

fn tree(svg: &str, db: &Arc<resvg::usvg::fontdb::Database>) -> Result<resvg::usvg::Tree> {
    let opt = resvg::usvg::Options {
        fontdb: db.clone(),
        ..resvg::usvg::Options::default()
    };
    resvg::usvg::Tree::from_str(svg, &opt).context("the figure's SVG does not parse")
}

fn png(t: &resvg::usvg::Tree, width_mm: f64) -> Result<Vec<u8>> {
    let size = t.size();
    let px_w = (width_mm / 25.4 * PNG_DPI).round().max(1.0);
    let scale = px_w as f32 / size.width();
    let px_h = (size.height() * scale).ceil().max(1.0);
    let mut pm = resvg::tiny_skia::Pixmap::new(px_w as u32, px_h as u32)
        .context("the figure is too large for a PNG")?;
    resvg::render(
        t,
        resvg::tiny_skia::Transform::from_scale(scale, scale),
        &mut pm.as_mut(),
    );
    pm.encode_png().context("cannot encode the PNG")
}

fn pdf(t: &resvg::usvg::Tree) -> Result<Vec<u8>> {
    svg2pdf::to_pdf(
        t,
        svg2pdf::ConversionOptions::default(),
        svg2pdf::PageOptions::default(),
    )
    .map_err(|e| anyhow::anyhow!("cannot make the PDF: {e}"))
}

/// One figure file: its name under the output directory and its bytes.
pub struct FigureFile {
    /// `figures/figure-N-ID.EXT`.
    pub name: String,
    /// Contents.
    pub bytes: Vec<u8>,
}

/// Every figure in every asked format, numbered as in the report (from 1).
pub fn figure_files(figs: &[Figure], opts: &FigureOptions) -> Result<Vec<FigureFile>> {
    let mut out = Vec::new();
    if opts.formats.is_empty() {
        return Ok(out);
    }
    let db = fonts();
    // One figure per thread (they are independent; rasterising dominates).
    let per_figure: Vec<Result<Vec<FigureFile>>> = std::thread::scope(|s| {
        let handles: Vec<_> = figs
            .iter()
            .enumerate()
            .map(|(k, f)| {
                let db = &db;
                s.spawn(move || one_figure(f, k + 1, opts, db))
            })
            .collect();
        handles
            .into_iter()
            .map(|h| {
                h.join()
                    .unwrap_or_else(|_| Err(anyhow::anyhow!("a figure's renderer panicked")))
            })
            .collect()
    });
    for files in per_figure {
        out.extend(files?);
    }
    Ok(out)
}

/// Figure `n`'s files in every asked format.
fn one_figure(
    f: &Figure,
    n: usize,
    opts: &FigureOptions,
    db: &Arc<resvg::usvg::fontdb::Database>,
) -> Result<Vec<FigureFile>> {
    let svg = standalone_svg(f, n, Some(opts.width_mm));
    let stem = format!("figures/figure-{n}-{}", f.id);
    let needs_tree = opts.formats.iter().any(|x| *x != Format::Svg);
    let t = if needs_tree {
        Some(tree(&svg, db)?)
    } else {
        None
    };
    let mut out = Vec::new();
    for fmt in &opts.formats {
        let bytes = match (fmt, &t) {
            (Format::Svg, _) => svg.clone().into_bytes(),
            (Format::Png, Some(t)) => png(t, opts.width_mm)?,
            (Format::Pdf, Some(t)) => pdf(t)?,
            _ => unreachable!("a tree is built for PNG and PDF"),
        };
        out.push(FigureFile {
            name: format!("{stem}.{}", fmt.ext()),
            bytes,
        });
    }
    Ok(out)
}

/// Checks of a written figure file (for tests and for users' scripts): the SVG parses.
pub fn svg_parses(svg: &str) -> Result<()> {
    tree(svg, &Arc::new(resvg::usvg::fontdb::Database::new())).map(|_| ())
}

/// A PNG file's size in pixels, decoding it whole.
pub fn png_decodes(bytes: &[u8]) -> Result<(u32, u32)> {
    let pm = resvg::tiny_skia::Pixmap::decode_png(bytes).context("the PNG does not decode")?;
    Ok((pm.width(), pm.height()))
}

/// The number of pages of a PDF (its `/Type /Page` objects), and whether it has its header and
/// end-of-file marker.
pub fn pdf_pages(bytes: &[u8]) -> (usize, bool) {
    let text = String::from_utf8_lossy(bytes);
    let pages = text.matches("/Type /Page").count() - text.matches("/Type /Pages").count();
    let framed = bytes.starts_with(b"%PDF-") && text.trim_end().ends_with("%%EOF");
    (pages, framed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layers_become_groups_and_the_chart_stays() {
        let c = "<svg class=\"chart\" width=\"10\"><g class=\"axes\"><svg width=\"10\"><rect/></svg></g><g class=\"mark\"><svg width=\"10\"><circle/></svg></g></svg>";
        let f = flatten_layers(c);
        assert_eq!(f, "<svg class=\"chart\" width=\"10\"><g class=\"axes\"><g><rect/></g></g><g class=\"mark\"><g><circle/></g></g></svg>");
    }

    #[test]
    fn formats_parse() {
        assert_eq!(
            Format::parse_list("svg, PNG,pdf,svg").unwrap(),
            vec![Format::Svg, Format::Png, Format::Pdf]
        );
        assert!(Format::parse_list("jpg").is_err());
        assert!(Format::parse_list(",").is_err());
    }
}
