//! Checks of a figure file as it is rendered (for the tests, and for users' scripts): every
//! text's box, as resvg lays it out with a given set of fonts (the boxes the PNG and the PDF
//! draw), inside the canvas and clear of every other text; and the files' physical sizes (the
//! SVG's width in mm, the PNG's pixels and resolution, the PDF's page).

use crate::error::FileCheckError;
use resvg::usvg::{self, fontdb, Node};
use std::sync::Arc;

/// One text of a rendered figure: its content and its box in the canvas, px.
#[derive(Clone, Debug, PartialEq)]
pub struct TextBox {
    /// The text.
    pub text: String,
    /// (x0, y0, x1, y1).
    pub rect: (f64, f64, f64, f64),
}

/// The fonts a fresh Debian machine has (DejaVu Sans, fontconfig's own dependency), from the
/// files under `dir` (`/usr/share/fonts/truetype/dejavu`): None if they are not there.
pub fn fresh_machine_fonts(dir: &std::path::Path) -> Option<Arc<fontdb::Database>> {
    let mut db = fontdb::Database::new();
    for f in ["DejaVuSans.ttf", "DejaVuSans-Bold.ttf"] {
        db.load_font_file(dir.join(f)).ok()?;
    }
    db.set_sans_serif_family("DejaVu Sans");
    Some(Arc::new(db))
}

/// The system's fonts, as the figure files are rendered with.
pub fn system_fonts() -> Arc<fontdb::Database> {
    crate::export::fonts()
}

fn collect(g: &usvg::Group, out: &mut Vec<TextBox>) {
    for n in g.children() {
        match n {
            Node::Group(g) => collect(g, out),
            Node::Text(t) => {
                let r = t.abs_bounding_box();
                let text: String = t.chunks().iter().map(|c| c.text()).collect();
                out.push(TextBox {
                    text,
                    rect: (
                        f64::from(r.left()),
                        f64::from(r.top()),
                        f64::from(r.right()),
                        f64::from(r.bottom()),
                    ),
                });
            }
            _ => {}
        }
    }
}

/// Every text of `svg` laid out with `fonts`, and the canvas's size (px).
pub fn text_boxes(
    svg: &str,
    fonts: &Arc<fontdb::Database>,
) -> Result<(Vec<TextBox>, (f64, f64)), FileCheckError> {
    let opt = usvg::Options {
        fontdb: fonts.clone(),
        ..usvg::Options::default()
    };
    let tree = usvg::Tree::from_str(svg, &opt).map_err(FileCheckError::Svg)?;
    let mut out = Vec::new();
    collect(tree.root(), &mut out);
    let s = tree.size();
    Ok((out, (f64::from(s.width()), f64::from(s.height()))))
}

/// What is wrong with the text of `svg` laid out with `fonts`: each text outside the canvas,
/// each pair of texts on each other (boxes overlapping by more than `tol` px), and each text
/// that was not laid out (no font for it). Empty: nothing.
pub fn text_problems(
    svg: &str,
    fonts: &Arc<fontdb::Database>,
    tol: f64,
) -> Result<Vec<String>, FileCheckError> {
    let (boxes, (w, h)) = text_boxes(svg, fonts)?;
    let expected = svg.matches("<text").count();
    let mut out = Vec::new();
    if boxes.len() != expected {
        out.push(format!(
            "{} of {expected} texts laid out (no font for the others?)",
            boxes.len()
        ));
    }
    for b in &boxes {
        let (x0, y0, x1, y1) = b.rect;
        if x0 < -tol || y0 < -tol || x1 > w + tol || y1 > h + tol {
            out.push(format!(
                "{:?} outside the canvas {w:.1}×{h:.1}: {x0:.1},{y0:.1} to {x1:.1},{y1:.1}",
                b.text
            ));
        }
    }
    for (i, a) in boxes.iter().enumerate() {
        for b in &boxes[i + 1..] {
            if crate::plot::text::overlap(a.rect, b.rect, tol) {
                out.push(format!(
                    "{:?} on {:?}: {:?} and {:?}",
                    a.text, b.text, a.rect, b.rect
                ));
            }
        }
    }
    Ok(out)
}

/// An SVG file's width and height attributes, mm.
pub fn svg_size_mm(svg: &str) -> Result<(f64, f64), FileCheckError> {
    let head = &svg[..svg.find('>').unwrap_or(svg.len())];
    let attr = |name: &'static str| -> Result<f64, FileCheckError> {
        let k = head
            .find(&format!(" {name}=\""))
            .ok_or(FileCheckError::NoAttribute(name))?
            + name.len()
            + 3;
        let v = head[k..].split('"').next().unwrap_or("");
        let Some(mm) = v.strip_suffix("mm") else {
            return Err(FileCheckError::NotMm {
                name,
                value: v.to_string(),
            });
        };
        mm.parse().map_err(|source| FileCheckError::NotNumber {
            name,
            value: v.to_string(),
            source,
        })
    };
    Ok((attr("width")?, attr("height")?))
}

/// What a PNG says of its size.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PngInfo {
    /// Width and height, px.
    pub px: (u32, u32),
    /// Resolution in pixels per metre, x and y (None: no `pHYs` chunk, or not in metres).
    pub per_metre: Option<(u32, u32)>,
}

/// A PNG's size in pixels and its resolution.
pub fn png_info(bytes: &[u8]) -> Result<PngInfo, FileCheckError> {
    let dec = png::Decoder::new(bytes);
    let reader = dec.read_info().map_err(FileCheckError::Png)?;
    let info = reader.info();
    let dims = info
        .pixel_dims
        .filter(|d| d.unit == png::Unit::Meter)
        .map(|d| (d.xppu, d.yppu));
    Ok(PngInfo {
        px: (info.width, info.height),
        per_metre: dims,
    })
}

/// A one-page PDF's page size, pt (its `/MediaBox`).
pub fn pdf_page_pt(bytes: &[u8]) -> Result<(f64, f64), FileCheckError> {
    let text = String::from_utf8_lossy(bytes);
    let k = text.find("/MediaBox").ok_or(FileCheckError::NoMediaBox)?;
    let inside = text[k..]
        .split('[')
        .nth(1)
        .and_then(|s| s.split(']').next())
        .ok_or(FileCheckError::MediaBoxEmpty)?;
    let v: Vec<f64> = inside
        .split_whitespace()
        .map(str::parse)
        .collect::<Result<_, _>>()
        .map_err(FileCheckError::MediaBoxNotNumbers)?;
    if v.len() != 4 {
        return Err(FileCheckError::MediaBoxCount(v.len()));
    }
    Ok((v[2] - v[0], v[3] - v[1]))
}
