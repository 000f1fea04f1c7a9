//! Text of the figures: how wide and tall a string is set, word wrapping, and the SVG `<text>`
//! it becomes. Every figure is laid out with these metrics before anything is drawn, so that no
//! text leaves its canvas or lands on other text.
//!
//! The widths are the larger of DejaVu Sans and Liberation Sans (Arial's metrics) for each
//! character, regular and bold: DejaVu Sans is what a fresh Debian has (fontconfig's own
//! dependency; Liberation comes only with recommended packages), Liberation or Arial what most
//! other machines use for `Helvetica, Arial, sans-serif`, and Helvetica is narrower than both.
//! A layout that fits these fits any of them. Characters outside the table count as a full em.

use super::hex;
use plotters::style::RGBColor;
use std::fmt::Write as _;

/// The font family every text of a figure names.
pub const FAMILY: &str = "Helvetica, Arial, sans-serif";
/// Height above the baseline of a line of text, em (DejaVu Sans's ascender; Liberation's is
/// 0.905): what a browser's and resvg's text box reach.
pub const ASCENT: f64 = 0.93;
/// Depth below the baseline, em (DejaVu Sans: 0.236, Liberation: 0.212).
pub const DESCENT: f64 = 0.24;
/// Baseline-to-baseline distance of wrapped lines, em (a little over ascent + descent, so
/// that the lines' boxes do not touch).
pub const LINE: f64 = 1.22;

/// Advance widths of ' '..='~', 1/1000 em: regular.
const REGULAR_ASCII: [u16; 95] = [
    318, 401, 460, 838, 637, 951, 780, 275, 391, 391, 500, 838, 318, 361, 318, 337, 637, 637, 637,
    637, 637, 637, 637, 637, 637, 637, 337, 337, 838, 838, 838, 557, 1016, 685, 687, 723, 771, 667,
    611, 778, 752, 295, 500, 667, 558, 863, 749, 788, 667, 788, 723, 667, 611, 732, 685, 989, 686,
    667, 686, 391, 337, 391, 838, 557, 500, 613, 635, 550, 635, 616, 353, 635, 634, 278, 278, 580,
    278, 975, 634, 612, 635, 635, 412, 521, 393, 634, 592, 818, 592, 592, 525, 637, 337, 637, 838,
];
/// Advance widths of ' '..='~', 1/1000 em: bold.
const BOLD_ASCII: [u16; 95] = [
    349, 457, 521, 838, 696, 1002, 873, 307, 458, 458, 523, 838, 380, 416, 380, 366, 696, 696, 696,
    696, 696, 696, 696, 696, 696, 696, 400, 400, 838, 838, 838, 611, 1000, 774, 763, 734, 831, 684,
    684, 821, 837, 373, 557, 775, 638, 996, 837, 851, 733, 851, 771, 721, 683, 813, 774, 1104, 771,
    725, 726, 458, 366, 458, 838, 557, 500, 675, 716, 593, 716, 679, 436, 716, 712, 343, 343, 666,
    343, 1042, 712, 688, 716, 716, 494, 596, 479, 712, 652, 924, 646, 652, 583, 712, 366, 712, 838,
];
/// Other characters the figures use: (char, regular, bold), 1/1000 em.
const OTHER: [(char, u16, u16); 37] = [
    ('\u{a0}', 318, 349),
    ('°', 500, 500),
    ('²', 401, 438),
    ('³', 401, 438),
    ('−', 838, 838),
    ('–', 557, 557),
    ('—', 1000, 1000),
    ('·', 318, 380),
    ('×', 838, 838),
    ('±', 838, 838),
    ('μ', 637, 736),
    ('µ', 637, 736),
    ('Δ', 685, 774),
    ('χ', 578, 646),
    ('σ', 634, 779),
    ('λ', 592, 633),
    ('β', 639, 716),
    ('θ', 612, 688),
    ('τ', 603, 639),
    ('≤', 838, 838),
    ('≥', 838, 838),
    ('₁', 401, 438),
    ('₂', 401, 438),
    ('’', 318, 380),
    ('‘', 318, 380),
    ('“', 519, 658),
    ('”', 519, 658),
    ('é', 616, 679),
    ('…', 1000, 1000),
    ('≈', 838, 838),
    ('√', 638, 667),
    ('→', 1000, 1000),
    ('Σ', 632, 684),
    ('π', 690, 792),
    ('⁻', 528, 528),
    ('⋅', 318, 380),
    ('½', 970, 1036),
];

/// A text style: size in px (of the layout) and weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Font {
    /// Size, px.
    pub px: f64,
    /// Bold.
    pub bold: bool,
}

impl Font {
    /// Regular text of `px`.
    pub const fn regular(px: f64) -> Font {
        Font { px, bold: false }
    }

    /// Bold text of `px`.
    pub const fn bold(px: f64) -> Font {
        Font { px, bold: true }
    }

    /// The advance width of `c`, em.
    fn advance(self, c: char) -> f64 {
        let k = c as usize;
        let milli = if (0x20..0x7f).contains(&k) {
            if self.bold {
                BOLD_ASCII[k - 0x20]
            } else {
                REGULAR_ASCII[k - 0x20]
            }
        } else {
            OTHER
                .iter()
                .find(|o| o.0 == c)
                .map_or(1000, |o| if self.bold { o.2 } else { o.1 })
        };
        f64::from(milli) / 1000.0
    }

    /// The width of `s` set in this font, px.
    pub fn width(self, s: &str) -> f64 {
        s.chars().map(|c| self.advance(c)).sum::<f64>() * self.px
    }

    /// Baseline-to-baseline distance of wrapped lines, px.
    pub fn line(self) -> f64 {
        LINE * self.px
    }

    /// Height of one line's box (ascent + descent), px.
    pub fn height(self) -> f64 {
        (ASCENT + DESCENT) * self.px
    }

    /// Height of `n` lines, px (0 for none).
    pub fn block(self, n: usize) -> f64 {
        if n == 0 {
            0.0
        } else {
            self.height() + (n - 1) as f64 * self.line()
        }
    }
}

/// `s` broken at spaces into lines no wider than `max_px` (a word wider than that is a line of
/// its own, and [`fit`] shrinks it). A no-break space (U+00A0, as between a number and its
/// unit) does not break.
pub fn wrap(s: &str, font: Font, max_px: f64) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    let mut line = String::new();
    for word in s.split(' ').filter(|w| !w.is_empty()) {
        let candidate = if line.is_empty() {
            word.to_string()
        } else {
            format!("{line} {word}")
        };
        if !line.is_empty() && font.width(&candidate) > max_px {
            lines.push(std::mem::replace(&mut line, word.to_string()));
        } else {
            line = candidate;
        }
    }
    if !line.is_empty() || lines.is_empty() {
        lines.push(line);
    }
    lines
}

/// The font for `lines` to be no wider than `max_px`: `font` itself, or smaller (a long word).
pub fn fit(lines: &[String], font: Font, max_px: f64) -> Font {
    let widest = lines.iter().map(|l| font.width(l)).fold(0.0, f64::max);
    if widest <= max_px || widest <= 0.0 {
        font
    } else {
        Font {
            px: font.px * max_px / widest,
            ..font
        }
    }
}

/// Horizontal anchor of a text.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Anchor {
    /// x is the start.
    Start,
    /// x is the middle.
    Middle,
    /// x is the end.
    End,
}

/// One line of text at a baseline point, possibly turned a quarter anticlockwise (a y-axis
/// label, read from bottom to top).
#[derive(Clone, Debug, PartialEq)]
pub struct Label {
    /// The text.
    pub text: String,
    /// Anchor point, px.
    pub x: f64,
    /// Baseline, px (a turned label turns about (x, y)).
    pub y: f64,
    /// Font.
    pub font: Font,
    /// Anchor.
    pub anchor: Anchor,
    /// Turned 90° anticlockwise about (x, y).
    pub turned: bool,
    /// Colour.
    pub color: RGBColor,
    /// A white outline under the glyphs, so that a text over a line (a value beside a bar
    /// crossed by a threshold) stays legible.
    pub halo: bool,
}

impl Label {
    /// A horizontal label.
    pub fn new(text: impl Into<String>, (x, y): (f64, f64), font: Font, anchor: Anchor) -> Label {
        Label {
            text: text.into(),
            x,
            y,
            font,
            anchor,
            turned: false,
            color: super::TEXT,
            halo: false,
        }
    }

    /// The box the text occupies, px: (x0, y0, x1, y1).
    pub fn bbox(&self) -> (f64, f64, f64, f64) {
        let w = self.font.width(&self.text);
        let start = match self.anchor {
            Anchor::Start => 0.0,
            Anchor::Middle => -w / 2.0,
            Anchor::End => -w,
        };
        let (up, down) = (ASCENT * self.font.px, DESCENT * self.font.px);
        if self.turned {
            // Turned anticlockwise: the text runs upwards from (x, y), its top to the left.
            (
                self.x - up,
                self.y - start - w,
                self.x + down,
                self.y - start,
            )
        } else {
            (
                self.x + start,
                self.y - up,
                self.x + start + w,
                self.y + down,
            )
        }
    }

    /// The SVG element.
    pub fn svg(&self) -> String {
        let anchor = match self.anchor {
            Anchor::Start => "start",
            Anchor::Middle => "middle",
            Anchor::End => "end",
        };
        let mut s = format!(
            "<text x=\"{:.1}\" y=\"{:.1}\" font-family=\"{FAMILY}\" font-size=\"{:.2}\" text-anchor=\"{anchor}\" fill=\"{}\"",
            self.x,
            self.y,
            self.font.px,
            hex(self.color)
        );
        if self.font.bold {
            s.push_str(" font-weight=\"bold\"");
        }
        if self.halo {
            s.push_str(" stroke=\"#FFFFFF\" stroke-width=\"3\" stroke-linejoin=\"round\" paint-order=\"stroke\"");
        }
        if self.turned {
            let _ = write!(s, " transform=\"rotate(-90 {:.1} {:.1})\"", self.x, self.y);
        }
        let _ = write!(s, ">{}</text>", crate::cells::esc(&self.text));
        s
    }
}

/// Labels as SVG.
pub fn svg(labels: &[Label]) -> String {
    labels.iter().map(Label::svg).collect()
}

/// True if two boxes overlap by more than `tol` px both ways.
pub fn overlap(a: (f64, f64, f64, f64), b: (f64, f64, f64, f64), tol: f64) -> bool {
    a.0 + tol < b.2 && b.0 + tol < a.2 && a.1 + tol < b.3 && b.1 + tol < a.3
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn widths_are_those_of_the_wider_font() {
        let f = Font::regular(10.0);
        // DejaVu Sans's digits are 0.637 em, Liberation's 0.556.
        assert!((f.width("12") - 12.74).abs() < 1e-9);
        assert!(Font::bold(10.0).width("ab") > f.width("ab"));
        // Unknown characters count as an em.
        assert!((f.width("漢") - 10.0).abs() < 1e-9);
    }

    #[test]
    fn wrapping_keeps_words_and_the_width() {
        let f = Font::regular(12.0);
        let lines = wrap("residual of T2 against the extended model (N)", f, 120.0);
        assert!(lines.len() >= 3, "{lines:?}");
        assert!(lines.iter().all(|l| f.width(l) <= 120.0), "{lines:?}");
        assert_eq!(
            lines.join(" "),
            "residual of T2 against the extended model (N)"
        );
        let long = wrap("supercalifragilistic", f, 30.0);
        assert_eq!(long.len(), 1);
        let small = fit(&long, f, 30.0);
        assert!(small.width(&long[0]) <= 30.0 + 1e-9 && small.px < 12.0);
    }

    #[test]
    fn a_turned_label_occupies_a_column() {
        let l = Label {
            turned: true,
            ..Label::new("abc", (10.0, 100.0), Font::regular(10.0), Anchor::Middle)
        };
        let (x0, y0, x1, y1) = l.bbox();
        let w = Font::regular(10.0).width("abc");
        assert!((y1 - y0 - w).abs() < 1e-9 && (x1 - x0 - 11.7).abs() < 1e-9);
        assert!((y0 + y1) / 2.0 - 100.0 < 1e-9 && x0 < 10.0 && x1 > 10.0);
        assert!(l.svg().contains("rotate(-90 10.0 100.0)"));
    }
}
