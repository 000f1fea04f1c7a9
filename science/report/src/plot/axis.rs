//! Axes of the report's charts: labelled ticks, a panel's frame (ranges and ticks), and a
//! linear plotters axis that puts its grid lines at our ticks.

use super::{finite_range, points, Panel};
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

/// A panel's data ranges.
pub(super) fn ranges(p: &Panel) -> ((f64, f64), (f64, f64)) {
    let pts = || p.series.iter().flat_map(|s| points(s).iter());
    let x = p.x_range.unwrap_or_else(|| {
        finite_range(
            pts()
                .map(|v| v.0)
                .chain(p.x_ticks.iter().flatten().map(|t| t.0)),
        )
    });
    let y = p
        .y_range
        .unwrap_or_else(|| finite_range(pts().map(|v| v.1).chain(p.zero_line.then_some(0.0))));
    (x, y)
}

/// The pixel position of `v` on an axis from `lo` to `hi` drawn over `len` px.
pub(super) fn px(v: f64, (lo, hi): (f64, f64), len: f64) -> f64 {
    (v - lo) / (hi - lo) * len
}

/// True if neighbouring labels along an axis of `len` px keep `gap` px apart, each taking its
/// `size` along the axis.
fn spaced(
    ticks: &[(f64, String)],
    range: (f64, f64),
    len: f64,
    gap: f64,
    size: impl Fn(&str) -> f64,
) -> bool {
    ticks.windows(2).all(|t| {
        let d = (px(t[1].0, range, len) - px(t[0].0, range, len)).abs();
        d >= (size(&t[0].1) + size(&t[1].1)) / 2.0 + gap
    })
}

/// Every `k`-th of `ticks`, for the smallest `k` whose labels keep apart.
fn thinned(
    ticks: &[(f64, String)],
    range: (f64, f64),
    len: f64,
    gap: f64,
    size: impl Fn(&str) -> f64 + Copy,
) -> Vec<(f64, String)> {
    for k in 1..=ticks.len().max(1) {
        let t: Vec<(f64, String)> = ticks.iter().step_by(k).cloned().collect();
        if spaced(&t, range, len, gap, size) {
            return t;
        }
    }
    ticks.iter().take(1).cloned().collect()
}

/// Labelled ticks along an axis of `len` px: the panel's own (thinned to what fits) or the
/// most automatic ones (at most `most`) whose labels keep `gap` px apart.
pub(super) fn fitted_ticks(
    given: Option<&Vec<(f64, String)>>,
    range: (f64, f64),
    len: f64,
    most: usize,
    gap: f64,
    size: impl Fn(&str) -> f64 + Copy,
) -> Vec<(f64, String)> {
    if let Some(t) = given {
        return thinned(t, range, len, gap, size);
    }
    // The most ticks that keep apart, two at least where two do.
    let mut best: Option<Vec<(f64, String)>> = None;
    for n in (2..=most.max(2)).rev() {
        let t = auto_ticks(range.0, range.1, n);
        if spaced(&t, range, len, gap, size) && t.len() > best.as_ref().map_or(0, Vec::len) {
            best = Some(t);
            if best.as_ref().is_some_and(|b| b.len() >= 2) {
                break;
            }
        }
    }
    best.unwrap_or_else(|| thinned(&auto_ticks(range.0, range.1, 2), range, len, gap, size))
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
