//! `capstan analyze`: the measured pairs against Euler-Eytelwein, the thesis's Table 3 and the
//! extended model; what the model gets wrong, the causes, the extended model and the gain.
//!
//! The causes come from the evidence engine ([`crate::evidence`]), the same statistics as
//! `capstan diagnose` on the same data: every verdict, ΔBIC and standard error in the report is
//! computed for data clustered in cords and runs and serially correlated inside a run. The
//! extended model is Euler-Eytelwein with the named causes and per-cord random log-mu. Every
//! number is computed from the data by [`run`]; the only typed-in numbers are the thesis's
//! published Table 3 constants ([`thesis::TABLE3`]).
//!
//! Files: [`fits`] (every model fitted, in-sample and leave-one-cord-out), [`metrics`] (the
//! gain table), [`uncertainty`] (cluster-bootstrap intervals of the gain), [`extended`] (the
//! extended fit in detail), [`residuals`] (what the models get wrong), [`closed_loop`] (the
//! firmware against the fitted plant, as the report draws it), [`models`] and [`thesis`]. The
//! verdicts and their sentences are the verdict layer's ([`crate::verdict`]), which the
//! diagnosis renders too. The cause-naming on planted truths is
//! `capstan_validation::validate`; the closed loop is run by `capstan_validation::closed_loop`.

pub mod closed_loop;
pub mod coverage;
pub mod extended;
pub mod fits;
pub mod gain;
pub mod heldout;
pub mod inverse;
pub mod metrics;
pub mod models;
pub mod prediction;
pub mod residuals;
pub mod thesis;
pub mod uncertainty;

use crate::diagnose::Diagnosis;
use crate::evidence;
use crate::fit::solve::Fit;
use crate::fit::Observations;
use crate::verdict::Mechanisms;
use capstan_data::Dataset;
use serde::Serialize;
use std::time::Instant;

pub use extended::ExtendedDetail;
pub use fits::Predictions;
pub use metrics::{ln_amp, ln_amp_defined, rmse_ln_amp, AngleR2, CordR2, ModelMetrics, ParamCount};

/// How to run the analysis.
#[derive(Clone, Copy, Debug)]
pub struct Options {
    /// Threads for the independent fits (LOCO folds, mechanism variants).
    pub threads: usize,
    /// Without a `time_s` column, take the times from `step` with the thesis protocol, so
    /// that a drift in time can be tested (as `diagnose --protocol-times`).
    pub protocol_times: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            threads: std::thread::available_parallelism().map_or(2, |n| n.get().min(4)),
            protocol_times: false,
        }
    }
}

/// Wall-clock times, s.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Elapsed {
    /// The evidence engine (causes, evidence, adequacy).
    pub evidence_s: f64,
    /// Baseline, per-cord and extended fits.
    pub fits_s: f64,
    /// Leave-one-cord-out refits.
    pub loco_s: f64,
    /// Cluster-bootstrap intervals and the rest of the tables.
    pub tables_s: f64,
    /// Closed-loop simulation.
    pub closed_loop_s: f64,
    /// Writing the report (filled by the CLI).
    pub report_s: f64,
    /// Of which the figure files (SVG, PNG, PDF; filled by the CLI).
    pub figure_files_s: f64,
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
    /// The held-out gain: the extended model's leave-one-cord-out RMSE (the whole procedure)
    /// over Euler-Eytelwein's, with its sign-flip test over the cords.
    pub gain: gain::Gain,
    /// Every cord's held-out RMSE under each refittable model.
    pub held_out: Vec<uncertainty::HeldOut>,
    /// The thesis's per-angle R².
    pub thesis_per_angle_r2: Vec<AngleR2>,
    /// The extended fit in detail.
    pub extended: ExtendedDetail,
    /// Residual patterns of the baseline and the extended model.
    pub residual_patterns: Vec<residuals::Pattern>,
    /// ln-amplification residuals by step, baseline against extended.
    pub ln_amp_by_step: Option<Vec<residuals::StepResidual>>,
    /// The verdicts.
    pub mechanisms: Mechanisms,
    /// The evidence engine's answer, as `capstan diagnose --json` prints it.
    pub evidence: Diagnosis,
    /// The fitted extended model (for the closed loop).
    pub extended_fit: Fit,
    /// The fitted baseline.
    pub baseline_fit: Fit,
    /// Cord-jackknife SE of Euler-Eytelwein's one mu (over its leave-one-cord-out refits).
    pub baseline_mu_se: f64,
    /// The extended model with its uncertainty, for `capstan predict`.
    pub prediction_model: prediction::PredictionModel,
    /// Timing.
    pub elapsed: Elapsed,
    /// Fits that did not converge, in words (empty when every fit did).
    pub fit_notes: Vec<String>,
}

/// The gain of the whole procedure's held-out predictions over Euler-Eytelwein's: the cords of
/// failed folds (either model's) set apart and named, the rest tested over the cords.
fn held_out_gain(
    obs: &Observations,
    ext: &uncertainty::CordErrors,
    base: &uncertainty::CordErrors,
    whole: &heldout::WholeLoco,
    base_loco: &crate::fit::solve::Loco,
) -> gain::Gain {
    let labels: Vec<String> = obs.groups.iter().map(|g| g.label.clone()).collect();
    let mut failed: Vec<(String, String)> = Vec::new();
    for f in &whole.folds {
        if let Some(why) = &f.failed {
            for c in &f.cords {
                failed.push((c.clone(), format!("the extended model's fold: {why}")));
            }
        }
    }
    for (g, why) in &base_loco.did_not_converge {
        failed.push((labels[*g].clone(), format!("Euler-Eytelwein's fold: {why}")));
    }
    for (g, label) in labels.iter().enumerate() {
        let known = failed.iter().any(|(l, _)| l == label);
        if !known && (ext.missing[g] > 0 || base.missing[g] > 0) {
            failed.push((
                label.clone(),
                format!(
                    "{} rows without a held-out prediction",
                    ext.missing[g].max(base.missing[g])
                ),
            ));
        }
    }
    let out: Vec<usize> = (0..labels.len())
        .filter(|&g| failed.iter().any(|(l, _)| *l == labels[g]))
        .collect();
    let boot = uncertainty::ratio(&ext.without(&out), &base.without(&out), 0x6a1e);
    let mut g = gain::gain(ext, base, failed, (boot.ci95, boot.jackknife_se), &labels);
    g.folds = whole.folds.clone();
    g.selection = whole.selection.clone();
    g
}

/// The named causes in words, for the extended model's description.
fn causes_text(m: &Mechanisms) -> String {
    if m.causes.is_empty() {
        "none named".into()
    } else {
        m.causes
            .iter()
            .map(|c| c.name)
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// The fewest usable rows an analysis (and a plan built on one) works from.
pub const MIN_ROWS: usize = 10;

/// `ds` has the rows an analysis needs ([`MIN_ROWS`] usable pairs), or the error that says so.
pub fn enough_rows(ds: &Dataset) -> Result<(), AnalysisError> {
    let rows = Observations::from_dataset(ds).len();
    if rows < MIN_ROWS {
        return Err(AnalysisError::TooFewRows {
            file: ds.source.clone(),
            rows,
        });
    }
    Ok(())
}

/// Why a data set cannot be analysed.
#[derive(Debug, thiserror::Error)]
pub enum AnalysisError {
    /// Fewer than [`MIN_ROWS`] usable pairs.
    #[error("{file}: {rows} rows is too few to analyse (need at least {MIN_ROWS})")]
    TooFewRows {
        /// The data set's file, as the user named it.
        file: String,
        /// Its usable rows (finite tensions and wrap).
        rows: usize,
    },
}

/// Fit every model to `ds`, name the causes and measure the gain.
pub fn run(ds: &Dataset, opts: Options) -> Result<Analysis, AnalysisError> {
    enough_rows(ds)?;
    let obs = Observations::from_dataset(ds);
    let threads = opts.threads;
    let t0 = Instant::now();
    let eopts = evidence::Options {
        threads,
        protocol_times: opts.protocol_times,
        ..evidence::Options::default()
    };
    let assessment = evidence::assess(ds, &eopts);
    // One verdict layer: the diagnosis and the mechanisms render the same verdicts.
    let verdicts = crate::verdict::of(&assessment);
    let evidence_view = crate::diagnose::render(&assessment, &verdicts, &eopts, t0);
    let mechanisms = verdicts.mechanisms;
    let evidence_s = t0.elapsed().as_secs_f64();
    let spec = models::extended(&assessment);
    let pop_spec = models::population(&assessment);
    let f = fits::fit_all(&obs, (&spec, &pop_spec), threads);
    let tw = Instant::now();
    let whole = heldout::whole_procedure(ds, &obs, &assessment, &eopts, threads);
    let mut f = f;
    f.pred.extended_loco = whole.t2_n.clone();
    // A fold that named no cause fitted Euler-Eytelwein with one mu, the baseline itself: its
    // cords get the baseline's prediction, so the test sees no difference (two fits of one
    // model from different starts differ in the solver's last digits, which a sign-flip test
    // would read as a gain or a loss half the time).
    for fold in whole
        .folds
        .iter()
        .filter(|f| f.causes.is_empty() && f.failed.is_none())
    {
        for g in (0..obs.groups.len()).filter(|&g| fold.cords.contains(&obs.groups[g].label)) {
            for i in obs.rows_of_group(g) {
                f.pred.extended_loco[i] = f.pred.baseline_loco[i];
            }
        }
    }
    f.loco_s += tw.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let models = metrics::gain_table(&obs, &f, &causes_text(&mechanisms));
    let errors = |p: &[f64]| uncertainty::CordErrors::of(&obs, p);
    let (base_loco, ext_loco, cord_loco) = (
        errors(&f.pred.baseline_loco),
        errors(&f.pred.extended_loco),
        errors(&f.pred.baseline_per_cord_loco),
    );
    let gain = held_out_gain(&obs, &ext_loco, &base_loco, &whole, &f.baseline_loco);
    let held_out = uncertainty::held_out(
        &obs,
        &[
            ("baseline", &base_loco),
            ("baseline_per_cord", &cord_loco),
            ("extended", &ext_loco),
        ],
    );
    let extended = extended::detail(&obs, &f, &assessment);
    let thesis_per_angle_r2 = metrics::thesis_per_angle(&obs);
    let residual_patterns = residuals::patterns(ds, &obs, &f.pred);
    let ln_amp_by_step = residuals::ln_amp_by_step(&obs, &f.pred);
    let prediction_model = prediction::build(&obs, &f);
    let tables_s = t1.elapsed().as_secs_f64();
    let baseline_mu_se = f
        .baseline_loco
        .jackknife_se()
        .iter()
        .find(|x| x.0 == "mu")
        .map_or(f64::NAN, |x| x.1);
    Ok(Analysis {
        baseline_mu_se,
        prediction_model,
        source: ds.source.clone(),
        obs,
        models,
        gain,
        held_out,
        thesis_per_angle_r2,
        extended,
        residual_patterns,
        ln_amp_by_step,
        mechanisms,
        evidence: evidence_view,
        elapsed: Elapsed {
            evidence_s,
            fits_s: f.fits_s,
            loco_s: f.loco_s,
            tables_s,
            ..Elapsed::default()
        },
        fit_notes: f.notes,
        pred: f.pred,
        extended_fit: f.extended,
        baseline_fit: f.baseline,
    })
}
