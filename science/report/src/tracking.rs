//! The report of a force-control session (issue 43): how the rig tracked its T2 target. Per
//! run, every step's steady-state error, overshoot, rise and settling time, and from a stepped
//! sine sweep the closed loop's gain and phase and its −3 dB bandwidth
//! (`capstan_tracking`); the figures of [`crate::figures::tracking`]. `capstan analyze` writes
//! it instead of the friction analysis when the pairs carry a T2 target.

use crate::cells::{esc, fx};
use crate::figures::tracking::{bode_plot, target_vs_measured, RunTrace};
use crate::figures::Figure;
use crate::html::{figure_html, STYLE};
use capstan_tracking::{
    bandwidth, bode, steps, Bandwidth, BodePoint, SteadyWindow, StepResponse, Trace,
};
use serde::Serialize;
use std::fmt::Write as _;

/// One run of a force session and how it tracked.
pub struct TrackedRun {
    /// Its name ("run 1", a file's).
    pub label: String,
    /// Target and measured T2 over time.
    pub trace: Trace,
    /// Every step's response.
    pub steps: Vec<StepResponse>,
    /// Every sine frequency's gain and phase.
    pub bode: Vec<BodePoint>,
    /// The −3 dB bandwidth of the sweep.
    pub bandwidth: Bandwidth,
}

impl TrackedRun {
    /// The tracking of `trace`, steady states over `window`.
    pub fn new(label: String, trace: Trace, window: SteadyWindow) -> TrackedRun {
        let st = steps(&trace, window);
        let bd = bode(&trace);
        TrackedRun {
            label,
            bandwidth: bandwidth(&bd),
            trace,
            steps: st,
            bode: bd,
        }
    }
}

fn opt(v: Option<f64>) -> String {
    v.map_or("–".into(), |x| fx(x, 2))
}

/// The sentence of a bandwidth.
pub fn bandwidth_words(b: &Bandwidth) -> String {
    match b {
        Bandwidth::Within { freq_hz, phase_deg } => format!(
            "the closed loop's gain falls to −3 dB at {} Hz, where its phase is {}°",
            fx(*freq_hz, 2),
            fx(*phase_deg, 0)
        ),
        Bandwidth::Above { freq_hz } => format!(
            "the gain stays above −3 dB up to the sweep's last frequency, {} Hz: the bandwidth is above it",
            fx(*freq_hz, 2)
        ),
        Bandwidth::Below { freq_hz } => format!(
            "the gain is below −3 dB already at the sweep's first frequency, {} Hz",
            fx(*freq_hz, 2)
        ),
        Bandwidth::None => "no sine sweep in this run".into(),
    }
}

fn steps_table(h: &mut String, st: &[StepResponse]) {
    h.push_str("<table class=\"tracking\"><tr><th>step at (s)</th><th>from (N)</th><th>target (N)</th><th>steady T2 (N)</th><th>steady-state error</th><th>overshoot (% of the step)</th><th>rise 10–90 % (s)</th><th>settling (s)</th><th>band (N)</th></tr>");
    for s in st {
        let _ = write!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{} ± {}</td><td>{} N ({} %)</td><td>{}</td><td>{}</td><td>{}</td><td>± {}</td></tr>",
            fx(s.t_s, 2),
            fx(s.from_target_n, 1),
            fx(s.target_n, 1),
            fx(s.steady_n, 3),
            fx(s.steady_sd_n, 3),
            fx(s.ss_error_n, 3),
            fx(s.ss_error_pct, 2),
            fx(s.overshoot_pct, 1),
            opt(s.rise_s),
            opt(s.settling_s),
            fx(s.band_n, 2)
        );
    }
    h.push_str("</table>");
}

fn bode_table(h: &mut String, bd: &[BodePoint]) {
    h.push_str("<table class=\"bode\"><tr><th>frequency (Hz)</th><th>cycles fitted</th><th>target amplitude (N)</th><th>measured amplitude (N)</th><th>gain</th><th>gain (dB)</th><th>phase (°)</th><th>residual (% of amplitude)</th></tr>");
    for p in bd {
        let _ = write!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            fx(p.freq_hz, 2),
            p.cycles,
            fx(p.target_amp_n, 2),
            fx(p.measured_amp_n, 2),
            fx(p.gain, 3),
            fx(p.gain_db, 2),
            fx(p.phase_deg, 1),
            fx(p.residual_pct, 1)
        );
    }
    h.push_str("</table>");
}

/// The worst |steady-state error| (% of target) and overshoot (% of step) over the runs' steps.
pub fn worst(runs: &[TrackedRun]) -> (f64, f64) {
    runs.iter()
        .flat_map(|r| r.steps.iter())
        .fold((0.0f64, 0.0f64), |(a, b), s| {
            (a.max(s.ss_error_pct.abs()), b.max(s.overshoot_pct))
        })
}

/// The page and its figures.
pub fn tracking_html(
    runs: &[TrackedRun],
    source: &str,
    window: SteadyWindow,
    ctx: &crate::Context,
) -> crate::error::Result<(String, Vec<Figure>)> {
    let layout = ctx.figures.layout();
    let traces: Vec<RunTrace> = runs
        .iter()
        .map(|r| RunTrace {
            label: &r.label,
            trace: &r.trace,
            bode: &r.bode,
        })
        .collect();
    let mut figs = vec![target_vs_measured(&traces, &layout)?];
    if let Some(b) = bode_plot(&traces, &layout)? {
        figs.push(b);
    }
    let mut h = String::new();
    let _ = write!(h, "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>Capstan force control</title><style>{STYLE}</style></head><body>");
    let n_steps: usize = runs.iter().map(|r| r.steps.len()).sum();
    let (ss, os) = worst(runs);
    let _ = write!(h, "<h1>Force control: how the rig held its T2 target</h1><p>Data: {} ({} runs, their raw logs). The rig ran in force mode: the servo held T2 at a target, through a feedforward of the fitted capstan law and feedback on the measured T2. This page says how well, from the firmware's raw log (T2 and its target at 100 Hz). The capstan law itself is analysed from protocol runs (<code>capstan analyze</code> on a session without a target).</p>", esc(source), runs.len());
    let _ = write!(h, "<h2>Headline</h2><p class=\"headline\">Over {} steps, the largest steady-state error was {} % of the target and the largest overshoot {} % of the step. {}.</p>",
        n_steps, fx(ss, 2), fx(os, 1),
        runs.iter().find(|r| !r.bode.is_empty()).map_or("No run swept a sine: the bandwidth is not measured (set force_profile sine)".to_string(), |r| format!("From the sine sweep of {}: {}", r.label, bandwidth_words(&r.bandwidth))));
    let _ = write!(h, "<h2>Definitions</h2><ul><li><b>Step</b>: a jump of the target (by 0.2 N and 2 % of the new target or more) held for a second or longer.</li><li><b>Steady state</b>: the mean measured T2 from {} s after the jump to {} s before the next change (the firmware's conditioning window; the last half of a shorter hold), ± its standard deviation; its error from the target in N and in % of the target.</li><li><b>Overshoot</b>: how far the measured T2, smoothed over 50 ms, goes beyond the steady mean in the step's direction within 3 s of the jump, in % of the step commanded (the target − the mean over the 0.5 s before the jump).</li><li><b>Rise time</b>: from 10 % to 90 % of the step, on the smoothed T2. <b>Settling time</b>: from the jump to the last time the smoothed T2 is outside the band (± 2 % of the target, or three times its own scatter in the steady window if larger) about the steady mean.</li><li><b>Bandwidth</b>: each sine frequency's gain and phase by least squares on whole cycles after the first second (target and measured T2 each fitted with a + b·sin + c·cos); the −3 dB frequency interpolated in log-frequency between the swept frequencies, and the phase there.</li></ul>",
        fx(window.after_s, 1), fx(window.before_s, 1));
    h.push_str("<h2>Tracking</h2>");
    figure_html(&mut h, &figs, "tracking");
    for r in runs {
        let _ = write!(h, "<h3>{}</h3>", esc(&r.label));
        if r.steps.is_empty() {
            h.push_str("<p>No step of the target in this run.</p>");
        } else {
            steps_table(&mut h, &r.steps);
        }
        if !r.bode.is_empty() {
            let _ = write!(
                h,
                "<p>Sine sweep: {}.</p>",
                esc(&bandwidth_words(&r.bandwidth))
            );
            bode_table(&mut h, &r.bode);
        }
    }
    h.push_str("<h2>The closed loop's frequency response</h2>");
    if figs.iter().any(|f| f.id == "bode") {
        figure_html(&mut h, &figs, "bode");
    } else {
        h.push_str("<p class=\"note\">No run of this session swept a sine (force_profile sine), so there is no Bode plot and no bandwidth.</p>");
    }
    let _ = write!(h, "<h2>Reproducing</h2><p><code>metrics.json</code> holds every number of this page (<code>tracking</code>). Made by {}.</p></body></html>", esc(&ctx.provenance.line()));
    Ok((h, figs))
}

/// `metrics.json` of a force session.
#[derive(Serialize)]
pub struct TrackingMetrics<'a> {
    /// `force_control`: what kind of session this file is of.
    pub kind: &'static str,
    /// How the rig tracked its target.
    pub tracking: Tracking<'a>,
    /// Program, commit, input hash, command line.
    pub provenance: &'a capstan_data::Provenance,
    /// Wall time of the command, s (`None`: not measured yet).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub elapsed_s: Option<f64>,
}

/// The `tracking` object: the steady window, the worst step and every run.
#[derive(Serialize)]
pub struct Tracking<'a> {
    /// Where each step's steady state is taken.
    pub window: SteadyWindow,
    /// The worst |steady-state error|, % of the target.
    pub worst_ss_error_pct: f64,
    /// The worst overshoot, % of the step.
    pub worst_overshoot_pct: f64,
    /// Every run.
    pub runs: Vec<RunTracking<'a>>,
}

/// One run's tracking in `metrics.json` (its trace is the report's figure, not the file's).
#[derive(Serialize)]
pub struct RunTracking<'a> {
    /// Its name.
    pub label: &'a str,
    /// Samples in its trace.
    pub samples: usize,
    /// Every step's response.
    pub steps: &'a [StepResponse],
    /// Every sine frequency's gain and phase.
    pub bode: &'a [BodePoint],
    /// The sweep's −3 dB bandwidth.
    pub bandwidth: &'a Bandwidth,
}

/// `metrics.json` of a force session.
pub fn tracking_metrics<'a>(
    runs: &'a [TrackedRun],
    window: SteadyWindow,
    ctx: &'a crate::Context,
) -> TrackingMetrics<'a> {
    let (ss, os) = worst(runs);
    TrackingMetrics {
        kind: "force_control",
        tracking: Tracking {
            window,
            worst_ss_error_pct: ss,
            worst_overshoot_pct: os,
            runs: (runs.iter())
                .map(|r| RunTracking {
                    label: &r.label,
                    samples: r.trace.len(),
                    steps: &r.steps,
                    bode: &r.bode,
                    bandwidth: &r.bandwidth,
                })
                .collect(),
        },
        provenance: &ctx.provenance,
        elapsed_s: None,
    }
}
