//! A minimal SVG writer for the report's figures: lines, polylines, markers, rectangles and
//! text, with true dash patterns, plus axis ticks. Data marks carry `class="mark"` so that a
//! rendering check (`scripts/check-report`) can tell drawn data from axes.

use std::fmt::Write as _;

/// A stroke pattern.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dash {
    /// Continuous.
    Solid,
    /// Long dashes.
    Dashed,
    /// Round dots.
    Dotted,
}

impl Dash {
    fn attrs(self) -> &'static str {
        match self {
            Dash::Solid => "",
            Dash::Dashed => " stroke-dasharray=\"7 4\"",
            Dash::Dotted => " stroke-dasharray=\"0.1 4.5\" stroke-linecap=\"round\"",
        }
    }
}

/// Escape text for SVG/HTML.
pub fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// Text anchor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Anchor {
    /// Left-aligned at x.
    Start,
    /// Centred on x.
    Middle,
    /// Right-aligned at x.
    End,
}

/// An SVG document being written.
pub struct Svg {
    buf: String,
}

impl Svg {
    /// A `w`×`h` px document on a white background.
    pub fn new(w: f64, h: f64) -> Self {
        let mut buf = String::new();
        let _ = write!(
            buf,
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w:.0}\" height=\"{h:.0}\" viewBox=\"0 0 {w:.0} {h:.0}\" font-family=\"Helvetica, Arial, sans-serif\"><rect width=\"{w:.0}\" height=\"{h:.0}\" fill=\"#fff\"/>"
        );
        Svg { buf }
    }

    /// A straight segment (`mark`: a data mark rather than an axis or grid line).
    pub fn line(
        &mut self,
        a: (f64, f64),
        b: (f64, f64),
        stroke: &str,
        width: f64,
        dash: Dash,
        mark: bool,
    ) {
        let _ = write!(
            self.buf,
            "<line{} x1=\"{:.1}\" y1=\"{:.1}\" x2=\"{:.1}\" y2=\"{:.1}\" stroke=\"{stroke}\" stroke-width=\"{width}\"{}/>",
            if mark { " class=\"mark\"" } else { "" },
            a.0,
            a.1,
            b.0,
            b.1,
            dash.attrs()
        );
    }

    /// A polyline through `pts` (a data mark).
    pub fn polyline(&mut self, pts: &[(f64, f64)], stroke: &str, width: f64, dash: Dash) {
        if pts.len() < 2 {
            return;
        }
        let _ = write!(self.buf, "<polyline class=\"mark\" fill=\"none\" stroke=\"{stroke}\" stroke-width=\"{width}\" stroke-linejoin=\"round\"{} points=\"", dash.attrs());
        for (k, (x, y)) in pts.iter().enumerate() {
            let _ = write!(self.buf, "{}{x:.1},{y:.1}", if k == 0 { "" } else { " " });
        }
        self.buf.push_str("\"/>");
    }

    /// A circular marker (a data mark): filled with `color`, or a ring if `hollow`.
    pub fn circle(&mut self, c: (f64, f64), r: f64, color: &str, hollow: bool, opacity: f64) {
        let paint = if hollow {
            format!("fill=\"#fff\" fill-opacity=\"0\" stroke=\"{color}\" stroke-width=\"1.3\" stroke-opacity=\"{opacity}\"")
        } else {
            format!("fill=\"{color}\" fill-opacity=\"{opacity}\"")
        };
        let _ = write!(
            self.buf,
            "<circle class=\"mark\" cx=\"{:.1}\" cy=\"{:.1}\" r=\"{r}\" {paint}/>",
            c.0, c.1
        );
    }

    /// A rectangle; `class` names it (`bar` for data bars).
    #[allow(clippy::too_many_arguments)]
    pub fn rect(&mut self, x: f64, y: f64, w: f64, h: f64, fill: &str, stroke: &str, class: &str) {
        let _ = write!(
            self.buf,
            "<rect class=\"{class}\" x=\"{x:.1}\" y=\"{y:.1}\" width=\"{:.1}\" height=\"{:.1}\" fill=\"{fill}\" stroke=\"{stroke}\"/>",
            w.max(0.0),
            h.max(0.0)
        );
    }

    /// Text at (x, y) (baseline), optionally rotated by −90° about that point.
    pub fn text(
        &mut self,
        p: (f64, f64),
        s: &str,
        size: f64,
        anchor: Anchor,
        bold: bool,
        vertical: bool,
    ) {
        let anchor = match anchor {
            Anchor::Start => "start",
            Anchor::Middle => "middle",
            Anchor::End => "end",
        };
        let rot = if vertical {
            format!(" transform=\"rotate(-90 {:.1} {:.1})\"", p.0, p.1)
        } else {
            String::new()
        };
        let _ = write!(
            self.buf,
            "<text x=\"{:.1}\" y=\"{:.1}\" font-size=\"{size}\" text-anchor=\"{anchor}\" fill=\"#222\"{}{rot}>{}</text>",
            p.0,
            p.1,
            if bold { " font-weight=\"bold\"" } else { "" },
            esc(s)
        );
    }

    /// The finished document.
    pub fn finish(mut self) -> String {
        self.buf.push_str("</svg>");
        self.buf
    }
}

/// Rough width of `s` in px at font size `size` (for laying out legends).
pub fn text_width(s: &str, size: f64) -> f64 {
    0.56 * size * s.chars().count() as f64
}

/// "Nice" tick positions (1, 2, 2.5 or 5 × 10ᵏ apart) inside [lo, hi], about `n` of them, and
/// their spacing.
pub fn nice_ticks(lo: f64, hi: f64, n: usize) -> (Vec<f64>, f64) {
    let span = (hi - lo).abs().max(1e-12);
    let raw = span / n.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    ((first..=last).map(|k| k as f64 * step).collect(), step)
}

/// A tick label with as many decimals as the spacing needs (a minus sign, never "−0").
pub fn tick_label(v: f64, step: f64) -> String {
    let decimals = (0..6)
        .find(|&d| {
            let s = step * 10f64.powi(d);
            (s - s.round()).abs() < 1e-6 * s.max(1.0)
        })
        .unwrap_or(6) as usize;
    let s = format!("{v:.decimals$}");
    if s.chars().all(|c| matches!(c, '-' | '0' | '.')) {
        s.trim_start_matches('-').to_string()
    } else {
        s.replace('-', "−")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_nice_and_labels_short() {
        let (t, s) = nice_ticks(0.13, 1.87, 5);
        assert_eq!(s, 0.5);
        assert_eq!(t, vec![0.5, 1.0, 1.5]);
        assert_eq!(tick_label(1.5, 0.5), "1.5");
        assert_eq!(tick_label(20.0, 5.0), "20");
        assert_eq!(tick_label(0.25, 0.25), "0.25");
        assert_eq!(tick_label(-0.0, 0.1), "0.0");
        assert_eq!(tick_label(-2.0, 1.0), "−2");
    }
}
