//! Figure files: each figure of the report as a standalone SVG (legend inside, white
//! background, sized in millimetres for a journal column), and from that same SVG a PNG
//! (resvg, 300 dpi) and a PDF (svg2pdf, text kept as text). The report embeds the same SVG, so
//! the report's figures and the files come from one code path. No external program runs.
//!
//! Sizes: the layout is `width_mm` wide, and its base text (the tick labels) comes out at
//! `font_pt`; the panels reflow to that width and no figure is taller than
//! [`MAX_HEIGHT_MM`] ([`crate::plot::Layout`]). Every file has its physical size: the SVG's
//! width and height in mm, the PDF's page in points (1 pt = 1/72 in), the PNG's resolution in
//! its `pHYs` chunk, so that a word processor or LaTeX places each at `width_mm`.

use crate::error::{FigureError, Result};
use crate::figures::Figure;
use crate::plot::legend::legend;
use crate::plot::Layout;
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
                other => {
                    return Err(FigureError::UnknownFormat {
                        list: s.to_string(),
                        format: other.to_string(),
                    })
                }
            };
            if !out.contains(&f) {
                out.push(f);
            }
        }
        if out.is_empty() {
            return Err(FigureError::NoFormat(s.to_string()));
        }
        Ok(out)
    }
}

/// Resolution of the PNG files, dots per inch.
pub const PNG_DPI: f64 = 300.0;
/// Tick-label size of the layout, px ([`crate::plot`]'s base text size).
const BASE_TEXT_PX: f64 = 12.0;
const MM_PER_PT: f64 = 25.4 / 72.0;
/// The tallest a figure file is, mm: an A4 or US-letter page's text block (297 or 279 mm less
/// 25 mm margins) with room for the caption.
pub const MAX_HEIGHT_MM: f64 = 225.0;
/// Height of the "Figure N" line above a figure's legend (with `--figure-numbers`), px.
const NUMBER_H: f64 = 20.0;

/// Which figure files to write, and their size.
#[derive(Clone, Debug, PartialEq)]
pub struct FigureOptions {
    /// Formats (empty: no files; the report still shows the figures).
    pub formats: Vec<Format>,
    /// Width, mm (85: one journal column; 170: the page).
    pub width_mm: f64,
    /// Size of the base text (tick labels), pt.
    pub font_pt: f64,
    /// "Figure N" in each file, above its legend (off: the caption numbers the figure).
    pub numbers: bool,
}

impl Default for FigureOptions {
    fn default() -> Self {
        FigureOptions {
            formats: Vec::new(),
            width_mm: 170.0,
            font_pt: 8.0,
            numbers: false,
        }
    }
}

impl FigureOptions {
    /// Check the sizes.
    pub fn check(&self) -> Result<()> {
        if !(self.width_mm.is_finite() && (40.0..=400.0).contains(&self.width_mm)) {
            return Err(FigureError::Width(self.width_mm));
        }
        if !(self.font_pt.is_finite() && (4.0..=24.0).contains(&self.font_pt)) {
            return Err(FigureError::FontPt(self.font_pt));
        }
        Ok(())
    }

    /// Pixels of the layout per millimetre: the base text at `font_pt`.
    pub fn px_per_mm(&self) -> f64 {
        BASE_TEXT_PX / (self.font_pt * MM_PER_PT)
    }

    /// The layout the figures are drawn to: `width_mm` wide, at most [`MAX_HEIGHT_MM`] high
    /// (the "Figure N" line, when asked for, included).
    pub fn layout(&self) -> Layout {
        let number = if self.numbers { NUMBER_H } else { 0.0 };
        Layout {
            width_px: Some((self.width_mm * self.px_per_mm()).round() as u32),
            max_height_px: Some(MAX_HEIGHT_MM * self.px_per_mm() - number),
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

/// A figure as a standalone SVG document: white background, the legend above the chart
/// ("Figure N" above it when `number` is given), `width_mm` wide (None: in pixels, as the
/// report shows it).
pub fn standalone_svg(f: &Figure, number: Option<usize>, width_mm: Option<f64>) -> String {
    let (w, h_chart) = chart_size(&f.chart.svg);
    let title_h = if number.is_some() { NUMBER_H } else { 0.0 };
    let leg = legend(&f.legend, w);
    let h = (title_h + leg.height + h_chart).ceil();
    let size = match width_mm {
        Some(mm) => format!("width=\"{mm}mm\" height=\"{:.3}mm\"", mm * h / w),
        None => format!("width=\"{w}\" height=\"{h}\""),
    };
    let title = match number {
        Some(n) => crate::plot::text::Label::new(
            format!("Figure {n}"),
            (6.0, 15.0),
            crate::plot::text::Font::bold(13.0),
            crate::plot::text::Anchor::Start,
        )
        .svg(),
        None => String::new(),
    };
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"figure-file\" {size} viewBox=\"0 0 {w} {h}\"><rect width=\"{w}\" height=\"{h}\" fill=\"#FFFFFF\"/>{title}<g transform=\"translate(0 {title_h})\">{}</g><g transform=\"translate(0 {:.1})\">{}</g></svg>",
        leg.svg,
        title_h + leg.height,
        flatten_layers(&f.chart.svg)
    )
}

/// The system's fonts, with a sans-serif family that exists (Helvetica, Arial, Liberation
/// Sans or DejaVu Sans, the first found).
pub(crate) fn fonts() -> Arc<resvg::usvg::fontdb::Database> {
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
    resvg::usvg::Tree::from_str(svg, &opt).map_err(FigureError::Svg)
}

/// The PNG's size in pixels for a tree of `size` at `width_mm`: the width is exactly
/// `width_mm` at [`PNG_DPI`], the height in proportion.
pub fn png_size(size: (f32, f32), width_mm: f64) -> (u32, u32) {
    let px_w = (width_mm / 25.4 * PNG_DPI).round().max(1.0);
    let px_h = (f64::from(size.1) * px_w / f64::from(size.0))
        .ceil()
        .max(1.0);
    (px_w as u32, px_h as u32)
}

fn png(t: &resvg::usvg::Tree, width_mm: f64) -> Result<Vec<u8>> {
    let size = t.size();
    let (px_w, px_h) = png_size((size.width(), size.height()), width_mm);
    let scale = px_w as f32 / size.width();
    let mut pm = resvg::tiny_skia::Pixmap::new(px_w, px_h).ok_or(FigureError::TooLarge)?;
    // The background is white and opaque: the pixels are RGB.
    pm.fill(resvg::tiny_skia::Color::WHITE);
    resvg::render(
        t,
        resvg::tiny_skia::Transform::from_scale(scale, scale),
        &mut pm.as_mut(),
    );
    let rgb: Vec<u8> = pm
        .pixels()
        .iter()
        .flat_map(|p| {
            let c = p.demultiply();
            [c.red(), c.green(), c.blue()]
        })
        .collect();
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, px_w, px_h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        // pHYs: pixels per metre, so that the file is placed at `width_mm`.
        let ppm = (PNG_DPI / 0.0254).round() as u32;
        enc.set_pixel_dims(Some(png::PixelDimensions {
            xppu: ppm,
            yppu: ppm,
            unit: png::Unit::Meter,
        }));
        let mut w = enc.write_header().map_err(FigureError::PngEncode)?;
        w.write_image_data(&rgb).map_err(FigureError::PngEncode)?;
    }
    Ok(out)
}

fn pdf(t: &resvg::usvg::Tree) -> Result<Vec<u8>> {
    // usvg's units are CSS pixels (96 per inch): at 96 dpi the page is the SVG's size in mm.
    svg2pdf::to_pdf(
        t,
        svg2pdf::ConversionOptions::default(),
        svg2pdf::PageOptions { dpi: 96.0 },
    )
    .map_err(|e| FigureError::Pdf(e.to_string()))
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
            .map(|h| h.join().unwrap_or_else(|_| Err(FigureError::Panicked)))
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
    let svg = standalone_svg(f, opts.numbers.then_some(n), Some(opts.width_mm));
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
    let pm = resvg::tiny_skia::Pixmap::decode_png(bytes)
        .map_err(|e| FigureError::PngDecode(Box::new(e)))?;
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
