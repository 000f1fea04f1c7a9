//! Axes of the report's charts: labelled ticks, a panel's frame (ranges and ticks), and a
//! linear plotters axis that puts its grid lines at our ticks.

use super::{finite_range, points, Panel, LEFT, RIGHT};
use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

/// A tick label with as many decimals as the spacing needs (a minus sign, never "−0").
pub(super) fn tick_label(v: f64, step: f64) -> String {
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

/// plotters' tick positions in [lo, hi] (at most `n`), labelled.
pub(super) fn auto_ticks(lo: f64, hi: f64, n: usize) -> Vec<(f64, String)> {
    // plotters' key points never finish on a range that overflows (1e154..1e308): no ticks
    // rather than a hang on such a range.
    let span = hi - lo;
    if !(span.is_finite() && span > 0.0 && span > 1e-12 * hi.abs().max(lo.abs())) {
        return Vec::new();
    }
    let keys = RangedCoordf64::from(lo..hi).key_points(n);
    let step = match keys.as_slice() {
        [a, b, ..] => b - a,
        _ => 10f64.powf((hi - lo).abs().max(1e-12).log10().floor()),
    };
    keys.into_iter().map(|v| (v, tick_label(v, step))).collect()
}

/// The label of the tick nearest `v`.
pub(super) fn label_at(ticks: &[(f64, String)], v: f64) -> String {
    ticks
        .iter()
        .min_by(|a, b| (a.0 - v).abs().total_cmp(&(b.0 - v).abs()))
        .map_or_else(String::new, |t| t.1.clone())
}

/// A panel's coordinates: ranges and labelled ticks.
pub(super) struct Frame {
    pub(super) x: (f64, f64),
    pub(super) y: (f64, f64),
    pub(super) x_ticks: Vec<(f64, String)>,
    pub(super) y_ticks: Vec<(f64, String)>,
    /// x ticks name categories: no vertical grid lines, labels at the axis-label size.
    pub(super) categorical: bool,
}

impl Frame {
    pub(super) fn of(p: &Panel, w: u32) -> Frame {
        let pts = || p.series.iter().flat_map(|s| points(s).iter());
        let x = finite_range(
            pts()
                .map(|v| v.0)
                .chain(p.x_ticks.iter().flatten().map(|t| t.0)),
        );
        let y = p
            .y_range
            .unwrap_or_else(|| finite_range(pts().map(|v| v.1).chain(p.zero_line.then_some(0.0))));
        let n = (f64::from(w.saturating_sub(LEFT + RIGHT)) / 55.0).clamp(3.0, 8.0) as usize;
        Frame {
            x,
            y,
            x_ticks: p.x_ticks.clone().unwrap_or_else(|| auto_ticks(x.0, x.1, n)),
            y_ticks: auto_ticks(y.0, y.1, 5),
            categorical: false,
        }
    }
}

/// A linear axis with given ticks (plotters' `WithKeyPoints` over `f64` takes no label
/// formatter).
pub(super) struct Axis {
    linear: RangedCoordf64,
    ticks: Vec<f64>,
}

impl Axis {
    pub(super) fn new((lo, hi): (f64, f64), ticks: &[(f64, String)]) -> Axis {
        Axis {
            linear: (lo..hi).into(),
            ticks: ticks.iter().map(|t| t.0).collect(),
        }
    }
}

impl Ranged for Axis {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, v: &f64, limit: (i32, i32)) -> i32 {
        self.linear.map(v, limit)
    }

    fn key_points<H: KeyPointHint>(&self, hint: H) -> Vec<f64> {
        // Grid lines at the ticks only (no light lines between them).
        if hint.weight().allow_light_points() {
            Vec::new()
        } else {
            self.ticks.clone()
        }
    }

    fn range(&self) -> std::ops::Range<f64> {
        self.linear.range()
    }
}

pub(super) type Coord = Cartesian2d<Axis, Axis>;
