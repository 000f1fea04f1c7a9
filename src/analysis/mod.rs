//! `capstan analyze`: the measured pairs against Euler-Eytelwein, the thesis's Table 3 and the
//! extended model; what the simulator gets wrong, why, and by how much the extension helps.
//!
//! Every number here is computed from the data by [`run`]; the only typed-in numbers are the
//! thesis's published Table 3 constants ([`thesis::TABLE3`]).

//!
//! Files: [`fits`] (every model fitted, in-sample and leave-one-cord-out), [`metrics`] (the
//! gain table), [`extended`] (the extended fit in detail), [`residuals`] (what the models get
//! wrong), [`mechanisms`] (why), [`diagnosis`] (`capstan diagnose` on the same data, quoted),
//! [`closed_loop`] (the firmware against the fitted plant),
//! [`models`] and [`thesis`] (the specs and the thesis's Table 3).

pub mod closed_loop;
pub mod diagnosis;
pub mod extended;
pub mod fits;
pub mod mechanisms;
pub mod metrics;
pub mod models;
pub mod residuals;
pub mod thesis;

use crate::data::Dataset;
use crate::fit::solve::Fit;
use crate::fit::Observations;
use serde::Serialize;
use std::time::Instant;

pub use extended::{ExtendedDetail, StrictVariant};
pub use fits::Predictions;
pub use metrics::{ln_amp, rmse_ln_amp, AngleR2, CordR2, ModelMetrics, ParamCount};

/// How to run the analysis.
#[derive(Clone, Copy, Debug)]
pub struct Options {
    /// Threads for the independent fits (LOCO folds, mechanism variants).
    pub threads: usize,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            threads: std::thread::available_parallelism().map_or(2, |n| n.get().min(4)),
        }
    }
}

/// Wall-clock times, s.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Elapsed {
    /// Baseline, per-cord and extended fits.
    pub fits_s: f64,
    /// Leave-one-cord-out refits.
    pub loco_s: f64,
    /// Mechanism variants and tests.
    pub mechanisms_s: f64,
    /// `capstan diagnose` on the same data (both calls, run alongside the mechanisms).
    pub diagnose_s: f64,
    /// Closed-loop simulation.
    pub closed_loop_s: f64,
    /// Writing the report (filled by the CLI).
    pub report_s: f64,
    /// Everything (filled by the CLI).
    pub total_s: f64,
}

/// Everything `capstan analyze` computed.
#[derive(Clone, Debug)]
pub struct Analysis {
    /// The data as fitted.
    pub obs: Observations,
    /// Where the data came from.
    pub source: String,
    /// Predictions per row.
    pub pred: Predictions,
    /// The gain table.
    pub models: Vec<ModelMetrics>,
    /// The thesis's per-angle R².
    pub thesis_per_angle_r2: Vec<AngleR2>,
    /// The extended fit in detail.
    pub extended: ExtendedDetail,
    /// Residual patterns of the baseline and the extended model.
    pub residual_patterns: Vec<residuals::Pattern>,
    /// Mechanism tests.
    pub mechanisms: mechanisms::Mechanisms,
    /// `capstan diagnose` on the same data (None if it failed).
    pub diagnosis: Option<diagnosis::DiagnoseQuote>,
    /// The fitted extended model (for the closed loop).
    pub extended_fit: Fit,
    /// The fitted baseline.
    pub baseline_fit: Fit,
    /// Timing.
    pub elapsed: Elapsed,
}

/// Fit every model to `ds` and run every test.
pub fn run(ds: &Dataset, opts: Options) -> anyhow::Result<Analysis> {
    let obs = Observations::from_dataset(ds);
    if obs.len() < 10 {
        anyhow::bail!(
            "{}: {} rows is too few to analyse (need at least 10)",
            ds.source,
            obs.len()
        );
    }
    let threads = opts.threads;
    let f = fits::fit_all(&obs, threads);
    let models = metrics::gain_table(&obs, &f);
    let extended = extended::detail(&obs, &f);
    let thesis_per_angle_r2 = metrics::thesis_per_angle(&obs);

    // The mechanisms, with `capstan diagnose` on the same data alongside.
    let t2 = Instant::now();
    let (residual_patterns, mechanisms, diagnosed) = std::thread::scope(|s| {
        let diag = s.spawn(|| {
            let t = Instant::now();
            (diagnosis::calls(ds), t.elapsed().as_secs_f64())
        });
        let residual_patterns = residuals::patterns(ds, &obs, &f.pred);
        let mechanisms = mechanisms::run(
            &obs,
            &f.baseline,
            &f.extended,
            &f.extended_loco,
            &f.cord_mu,
            threads,
        );
        // A failed diagnosis leaves the analysis without its quote, not without a report.
        (residual_patterns, mechanisms, diag.join().ok())
    });
    let mechanisms_s = t2.elapsed().as_secs_f64();
    let diagnose_s = diagnosed.as_ref().map_or(0.0, |d| d.1);
    let diagnosis = diagnosed.map(|(c, _)| diagnosis::quote(c, &mechanisms, &extended));

    Ok(Analysis {
        source: ds.source.clone(),
        obs,
        models,
        thesis_per_angle_r2,
        extended,
        residual_patterns,
        mechanisms,
        diagnosis,
        elapsed: Elapsed {
            fits_s: f.fits_s,
            loco_s: f.loco_s,
            mechanisms_s,
            diagnose_s,
            ..Elapsed::default()
        },
        pred: f.pred,
        extended_fit: f.extended,
        baseline_fit: f.baseline,
    })
}
