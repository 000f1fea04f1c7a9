//! A figure's legend, drawn inside the figure above the chart: one entry per colour, marker or
//! line style, set left to right in rows across the figure's width (an entry wider than the
//! figure wraps its text), measured like every other text of the figure.

use super::text::{Anchor, Font, Label, ASCENT, DESCENT};
use super::{hex, Dash, Entry, Key, DASH, DOT_PERIOD};
use std::fmt::Write as _;

/// The legend's text.
pub const FONT: Font = Font::regular(12.0);
/// Width of a key's sample, px.
const KEY_W: f64 = 26.0;
/// Space between a sample and its text, px.
const KEY_GAP: f64 = 5.0;
/// Space between entries in a row, px.
const ENTRY_GAP: f64 = 14.0;
/// Space between rows, px.
const ROW_GAP: f64 = 3.0;
/// Space at the legend's edges, px.
const PAD: f64 = 4.0;

/// A legend, laid out.
pub struct Legend {
    /// `<g class="legend">…</g>`, from (0, 0).
    pub svg: String,
    /// Its height, px (0 without entries).
    pub height: f64,
    /// Its text, where it is drawn.
    pub labels: Vec<Label>,
}

/// The sample of a key, its middle at (x + KEY_W / 2, cy).
fn sample(key: Key, x: f64, cy: f64) -> String {
    match key {
        Key::Marker(m) => {
            let (c, r) = (hex(m.color), f64::from(m.radius).max(4.0));
            let paint = if m.hollow {
                format!("fill=\"none\" stroke=\"{c}\" stroke-width=\"1.3\"")
            } else {
                format!("fill=\"{c}\"")
            };
            format!(
                "<circle cx=\"{:.1}\" cy=\"{cy:.1}\" r=\"{r}\" {paint}/>",
                x + KEY_W / 2.0
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
                x + KEY_W - 1.0,
                hex(l.color),
                l.width
            )
        }
    }
}

/// The legend of `entries` across `width` px.
pub fn legend(entries: &[Entry], width: f64) -> Legend {
    if entries.is_empty() {
        return Legend {
            svg: String::new(),
            height: 0.0,
            labels: Vec::new(),
        };
    }
    let text_max = width - 2.0 * PAD - KEY_W - KEY_GAP;
    // Each entry's lines and width.
    let laid: Vec<(Vec<String>, Font, f64)> = entries
        .iter()
        .map(|e| {
            let (lines, font) = super::panel::lines(&e.label, FONT, text_max);
            let w = lines.iter().map(|l| font.width(l)).fold(0.0, f64::max);
            (lines, font, KEY_W + KEY_GAP + w)
        })
        .collect();
    let mut svg = String::from("<g class=\"legend\">");
    let mut labels = Vec::new();
    let (mut x, mut top, mut row_h) = (PAD, PAD, 0.0f64);
    for (e, (lines, font, w)) in entries.iter().zip(&laid) {
        if x > PAD && x + w > width - PAD {
            x = PAD;
            top += row_h + ROW_GAP;
            row_h = 0.0;
        }
        let base = top + ASCENT * font.px;
        let cy = base - (ASCENT - DESCENT) / 2.0 * font.px;
        svg.push_str(&sample(e.key, x, cy));
        for (i, line) in lines.iter().enumerate() {
            labels.push(Label::new(
                line.clone(),
                (x + KEY_W + KEY_GAP, base + i as f64 * font.line()),
                *font,
                Anchor::Start,
            ));
        }
        row_h = row_h.max(font.block(lines.len()));
        x += w + ENTRY_GAP;
    }
    for l in &labels {
        let _ = write!(svg, "{}", l.svg());
    }
    svg.push_str("</g>");
    Legend {
        svg,
        height: top + row_h + PAD,
        labels,
    }
}

/// The height of a figure file's legend over a chart `width_px` wide, px (what a figure
/// leaves for its panels under [`super::Layout::max_height_px`]).
pub fn legend_height(entries: &[Entry], width_px: f64) -> f64 {
    legend(entries, width_px).height
}
