//! Force control's figures (issue 43): the T2 target against the measured T2 over each run,
//! and the closed loop's Bode plot from a stepped sine sweep (gain in dB and phase against
//! frequency, on a log axis drawn as log10 with decade labels).

use super::{Figure, INK, OKABE_ITO};
use crate::error::Result;
use crate::plot::{figure, Dash, Entry, Key, Layout, LineStyle, Marker, Panel, Series};
use capstan_tracking::{BodePoint, Trace};

/// One run of a force session, for the figures.
pub struct RunTrace<'a> {
    /// Its name ("run 1").
    pub label: &'a str,
    /// Target and measured T2 over time.
    pub trace: &'a Trace,
    /// Its sine sweep's points (empty without one).
    pub bode: &'a [BodePoint],
}

/// A run's name in words: the raw logs' `d12.7_w720_v10_run2` (capstan diameter, wrap, drive
/// voltage, run) as "run 2: D = 12.7 mm, 720°, 10 V"; any other name as it is.
pub fn run_words(label: &str) -> String {
    let parse = || -> Option<String> {
        let rest = label.strip_prefix('d')?;
        let (d, rest) = rest.split_once("_w")?;
        let (w, rest) = rest.split_once("_v")?;
        let (v, run) = rest.split_once("_run")?;
        for x in [d, w, v, run] {
            x.parse::<f64>().ok()?;
        }
        Some(format!("run {run}: D = {d}\u{a0}mm, {w}°, {v}\u{a0}V"))
    };
    parse().unwrap_or_else(|| label.to_string())
}

/// The most points drawn per line: every k-th sample beyond it.
const MAX_POINTS: usize = 4_000;

fn thin(v: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
    let k = v.len().div_ceil(MAX_POINTS).max(1);
    v.into_iter().step_by(k).collect()
}

fn target_style() -> LineStyle {
    LineStyle {
        color: INK,
        width: 2,
        dash: Dash::Dashed,
    }
}

fn measured_style(k: usize) -> LineStyle {
    LineStyle {
        color: OKABE_ITO[k % OKABE_ITO.len()],
        width: 1,
        dash: Dash::Solid,
    }
}

/// Target (dashed) and measured T2 (solid) against time, one panel per run (as many as fit a
/// page).
pub fn target_vs_measured(runs: &[RunTrace], layout: &Layout) -> Result<Figure> {
    const X: &str = "time since the trigger (s)";
    let mut legend = vec![Entry {
        key: Key::Line(target_style()),
        label: "T2 target".into(),
    }];
    legend.extend(
        runs.iter()
            .enumerate()
            .take(OKABE_ITO.len())
            .map(|(k, r)| Entry {
                key: Key::Line(measured_style(k)),
                label: format!("T2 measured, {}", run_words(r.label)),
            }),
    );
    if runs.len() > OKABE_ITO.len() {
        legend.truncate(1);
        legend.push(Entry {
            key: Key::Line(measured_style(0)),
            label: format!(
                "T2 measured (one colour per run, repeating after {})",
                OKABE_ITO.len()
            ),
        });
    }
    let grid = layout.grid(1, 1100, 300);
    let titles: Vec<String> = runs.iter().map(|r| run_words(r.label)).collect();
    let refs: Vec<&str> = titles.iter().map(String::as_str).collect();
    let fit = super::panels_that_fit(layout, grid, &refs, X, &legend);
    let shown = capstan_engine::analysis::closed_loop::evenly(runs.len(), fit);
    let panels: Vec<Panel> = shown
        .iter()
        .map(|&k| (k, &runs[k]))
        .map(|(k, r)| {
            let t = &r.trace;
            let target: Vec<(f64, f64)> = (0..t.len()).map(|i| (t.t_s[i], t.target_n[i])).collect();
            let measured: Vec<(f64, f64)> =
                (0..t.len()).map(|i| (t.t_s[i], t.measured_n[i])).collect();
            Panel {
                title: run_words(r.label),
                x_label: X.into(),
                y_label: "T2 (N)".into(),
                series: vec![
                    Series::Line(thin(measured), measured_style(k)),
                    Series::Line(thin(target), target_style()),
                ],
                ..Panel::default()
            }
        })
        .collect();
    let chart = figure(&panels, grid.0, grid.1, grid.2)?;
    Ok(Figure {
        id: "tracking",
        legend,
        chart,
        caption: format!("The T2 target (dashed) and the T2 the rig measured (solid, the firmware's raw log at 100 Hz), over each run. Between the segments the target jumps (steps), moves linearly (a ramp) or swings about its mean (a sine sweep, one frequency per segment).{}", super::selection_note(shown.len(), runs.len(), "runs")),
    })
}

/// Decade ticks of log10(f) over the points' range (1, 2, 5 × 10^k).
fn log_ticks(lo: f64, hi: f64) -> Vec<(f64, String)> {
    let mut ticks = Vec::new();
    for e in (lo.floor() as i32)..=(hi.ceil() as i32) {
        for m in [1.0, 2.0, 5.0] {
            let f: f64 = m * 10f64.powi(e);
            let x = f.log10();
            if x >= lo - 1e-9 && x <= hi + 1e-9 {
                let label = if f >= 1.0 {
                    format!("{f:.0}")
                } else {
                    format!("{f}")
                };
                ticks.push((x, label));
            }
        }
    }
    ticks
}

fn point_marker(k: usize) -> Marker {
    Marker {
        color: OKABE_ITO[k % OKABE_ITO.len()],
        radius: 4,
        hollow: false,
        opacity: 0.9,
    }
}

/// The closed loop's Bode plot: gain (dB) and phase (deg) against frequency, one series per
/// run with a sweep, and the −3 dB line. `None` when no run has a sweep.
pub fn bode_plot(runs: &[RunTrace], layout: &Layout) -> Result<Option<Figure>> {
    let swept: Vec<(usize, &RunTrace)> = runs
        .iter()
        .enumerate()
        .filter(|(_, r)| !r.bode.is_empty())
        .collect();
    if swept.is_empty() {
        return Ok(None);
    }
    let xs: Vec<f64> = swept
        .iter()
        .flat_map(|(_, r)| r.bode.iter().map(|p| p.freq_hz.log10()))
        .collect();
    let (lo, hi) = xs
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    let ticks = log_ticks(lo - 0.05, hi + 0.05);
    let mut gain = Vec::new();
    let mut phase = Vec::new();
    for &(k, r) in &swept {
        let pts = |f: fn(&BodePoint) -> f64| {
            r.bode
                .iter()
                .map(|p| (p.freq_hz.log10(), f(p)))
                .collect::<Vec<_>>()
        };
        gain.push(Series::Line(pts(|p| p.gain_db), measured_style(k)));
        gain.push(Series::Points(pts(|p| p.gain_db), point_marker(k)));
        phase.push(Series::Line(pts(|p| p.phase_deg), measured_style(k)));
        phase.push(Series::Points(pts(|p| p.phase_deg), point_marker(k)));
    }
    let three_db = LineStyle {
        color: INK,
        width: 1,
        dash: Dash::Dashed,
    };
    gain.push(Series::Line(vec![(lo, -3.0103), (hi, -3.0103)], three_db));
    let panels = vec![
        Panel {
            title: "closed-loop gain".into(),
            x_label: "frequency (Hz)".into(),
            y_label: "gain (dB)".into(),
            series: gain,
            x_ticks: Some(ticks.clone()),
            zero_line: true,
            ..Panel::default()
        },
        Panel {
            title: "closed-loop phase".into(),
            x_label: "frequency (Hz)".into(),
            y_label: "phase (°)".into(),
            series: phase,
            x_ticks: Some(ticks),
            zero_line: true,
            ..Panel::default()
        },
    ];
    let (cols, w, h) = layout.grid(2, 540, 330);
    let chart = figure(&panels, cols, w, h)?;
    let mut legend: Vec<Entry> = swept
        .iter()
        .map(|(k, r)| Entry {
            key: Key::Marker(point_marker(*k)),
            label: run_words(r.label),
        })
        .collect();
    legend.push(Entry {
        key: Key::Line(three_db),
        label: "−3 dB".into(),
    });
    Ok(Some(Figure {
        id: "bode",
        legend,
        chart,
        caption: "The closed loop from the T2 target to the measured T2, at each frequency of the stepped sine sweep: the gain (the measured T2's amplitude over the target's, in dB) and the phase (the measured sine's minus the target's), fitted by least squares over whole cycles after the first second of each frequency. Where the gain crosses the dashed line is the −3 dB bandwidth.".into(),
    }))
}

#[cfg(test)]
mod tests {
    #[test]
    fn raw_log_names_read_as_words() {
        assert_eq!(
            super::run_words("d12.7_w720_v10_run2"),
            "run 2: D = 12.7\u{a0}mm, 720°, 10\u{a0}V"
        );
        assert_eq!(super::run_words("bench log 3"), "bench log 3");
        assert_eq!(super::run_words("d12_wx_v10_run2"), "d12_wx_v10_run2");
    }
}
