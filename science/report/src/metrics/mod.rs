//! `metrics.json`: every number of the report, as one typed object ([`Metrics`]) with its
//! layout's version ([`METRICS_SCHEMA`]), written here ([`Metrics::to_json`]) and read back
//! here ([`read_and_validate`]: what `capstan predict` and `capstan rig model` use, the
//! prediction model, checked). The writer borrows from the analysis; the reader refuses a
//! layout version other than [`METRICS_SCHEMA`], then takes only what other commands rely on.

mod read;

use crate::discovered::Discovered;
use crate::headline::Headline;
use crate::next::NextExperiment;
use crate::parameters::Row;
use capstan_data::structure::StructureSummary;
use capstan_data::Provenance;
use capstan_engine::analysis::closed_loop::Outcome;
use capstan_engine::analysis::prediction::PredictionModel;
use capstan_engine::analysis::ModelMetrics;
use capstan_engine::analysis::{gain::Gain, uncertainty::HeldOut};
use capstan_engine::analysis::{residuals, Analysis, AngleR2, Elapsed, ExtendedDetail};
use capstan_engine::diagnose::Diagnosis;
use capstan_engine::fit::obs::TimingSource;
use capstan_engine::verdict::{Cause, Mechanism, Unexplained};
use serde::Serialize;

pub use read::{check, read_and_validate, MetricsError, MetricsRead, ModelProblem};

/// Version of `metrics.json`'s layout: 2 added `schema_version`, `provenance`,
/// `thesis_comparison`, `headline`, `parameters` and `prediction_model` (what `capstan predict`
/// reads).
pub const METRICS_SCHEMA: u32 = 2;

/// How the steps are timed without a `time_s` column.
const TIMING_NOTE: &str = "Without a time_s column, step k of the thesis protocol starts 10k + 0.5 s after the trigger, its conditioning window (2 s after the change to 1 s before the next) is centred at 10k + 6 s, and it ends at 10k + 10.5 s; the load memory starts at zero at the first kept step of each run.";

/// What the parameter counts mean.
const PARAMETER_COUNT_NOTE: &str = "Every model's count is its fixed values plus the effective degrees of freedom of its cord effects (Σ J_g/(J_g + λ)); AIC and BIC in `models` treat rows as independent and are shown for comparison with the thesis only: the causes are judged by the evidence engine (`evidence`), which does not.";

/// The contents of `metrics.json` of an analysis (the law's; a force-control session writes
/// [`crate::tracking::TrackingMetrics`] instead).
#[derive(Serialize)]
pub struct Metrics<'a> {
    /// [`METRICS_SCHEMA`].
    pub schema_version: u32,
    /// Program, commit, input hash, command line.
    pub provenance: &'a Provenance,
    /// Whether the thesis's Table 3 is compared, and why.
    pub thesis_comparison: ThesisShown<'a>,
    /// The plain headline.
    pub headline: Headline,
    /// The one parameter table.
    pub parameters: Vec<Row>,
    /// What `capstan predict` reads.
    pub prediction_model: &'a PredictionModel,
    /// The data set read.
    pub data: DataSection<'a>,
    /// Every model's fit.
    pub models: &'a [ModelMetrics],
    /// The held-out gain of the extended model over Euler-Eytelwein.
    pub gain: GainSection<'a>,
    /// Each cord held out.
    pub held_out: &'a [HeldOut],
    /// ln(T2/T1) residuals by step.
    pub ln_amp_by_step: &'a Option<Vec<residuals::StepResidual>>,
    /// What the models' parameter counts mean.
    pub parameter_count_note: &'static str,
    /// The causes named.
    pub causes: &'a [Cause],
    /// What is left unexplained.
    pub unexplained: &'a Unexplained,
    /// Every mechanism's test.
    pub mechanisms: &'a [Mechanism],
    /// The order the causes came in, with their ΔBIC.
    pub selection_path: &'a [(&'static str, f64)],
    /// The evidence engine's diagnosis.
    pub evidence: &'a Diagnosis,
    /// Patterns in the residuals.
    pub residual_patterns: &'a [residuals::Pattern],
    /// What the extended model's residual trends say, read as one family (Holm): the report's
    /// sentence under "What is left".
    pub residual_trends: String,
    /// The thesis's per-angle R².
    pub thesis_per_angle_r2: &'a [AngleR2],
    /// The extended model in detail.
    pub extended_fit: &'a ExtendedDetail,
    /// What the protocol cannot test.
    pub protocol_limits: &'a [String],
    /// Fits that did not converge.
    pub fits_not_converged: &'a [String],
    /// The firmware in the loop with the extended model (`null`: not run).
    pub closed_loop: Option<&'a Outcome>,
    /// Wall times, s.
    pub elapsed_s: &'a Elapsed,
    /// Beyond the catalogue (`capstan discover`), when it ran.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub discovered: Option<Discovered<'a>>,
    /// The next experiment, when it was asked for.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub next_experiment: Option<&'a NextExperiment>,
}

/// `thesis_comparison`: shown or not, and why.
#[derive(Serialize)]
pub struct ThesisShown<'a> {
    /// Shown in the report, `metrics.json` and the figures.
    pub shown: bool,
    /// Why.
    pub why: &'a str,
}

/// `data`: the data set read and how its steps are timed.
#[derive(Serialize)]
pub struct DataSection<'a> {
    /// Where it came from.
    pub source: &'a str,
    /// Rows.
    pub rows: usize,
    /// Cords.
    pub cords: usize,
    /// Runs.
    pub runs: usize,
    /// Its structure, and how each level was found.
    pub structure: &'a StructureSummary,
    /// Where the step times come from.
    pub timing_source: TimingSource,
    /// How the steps are timed without a `time_s` column.
    pub timing_note: &'static str,
    /// What the data checks warned about (`None`: not checked here).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub warnings: Option<&'a [String]>,
}

/// `gain`: the held-out RMSE ratio and the cords behind it.
#[derive(Serialize)]
pub struct GainSection<'a> {
    /// The extended model's leave-one-cord-out RMSE over Euler-Eytelwein's.
    pub loco_rmse_ratio_extended_over_baseline: &'a Gain,
    /// Cords the extended model predicts better held out.
    pub cords_predicted_better: usize,
    /// Cords held out.
    pub cords: usize,
}

impl<'a> Metrics<'a> {
    /// The metrics of `a`, with the closed loop's outcome (`None`: not run) and the report's
    /// context; without the discovered and next-experiment sections (see the `with_`
    /// methods).
    pub fn new(a: &'a Analysis, closed_loop: Option<&'a Outcome>, ctx: &'a crate::Context) -> Self {
        Metrics {
            schema_version: METRICS_SCHEMA,
            provenance: &ctx.provenance,
            thesis_comparison: ThesisShown {
                shown: ctx.thesis.shown,
                why: &ctx.thesis.why,
            },
            headline: crate::headline::headline(a),
            parameters: crate::parameters::rows(a),
            prediction_model: &a.prediction_model,
            data: DataSection {
                source: &a.source,
                rows: a.obs.len(),
                cords: a.obs.groups.len(),
                runs: a.obs.runs.len(),
                structure: &a.evidence.data.structure,
                timing_source: a.obs.timing,
                timing_note: TIMING_NOTE,
                warnings: None,
            },
            models: &a.models,
            gain: GainSection {
                loco_rmse_ratio_extended_over_baseline: &a.gain,
                cords_predicted_better: a.held_out.iter().filter(|c| c.extended_better).count(),
                cords: a.held_out.len(),
            },
            held_out: &a.held_out,
            ln_amp_by_step: &a.ln_amp_by_step,
            parameter_count_note: PARAMETER_COUNT_NOTE,
            causes: &a.mechanisms.causes,
            unexplained: &a.mechanisms.unexplained,
            mechanisms: &a.mechanisms.tests,
            selection_path: &a.mechanisms.selection_path,
            evidence: &a.evidence,
            residual_patterns: &a.residual_patterns,
            residual_trends: crate::trends::extended_trends(a),
            thesis_per_angle_r2: &a.thesis_per_angle_r2,
            extended_fit: &a.extended,
            protocol_limits: &a.mechanisms.protocol_limits,
            fits_not_converged: &a.fit_notes,
            closed_loop,
            elapsed_s: &a.elapsed,
            discovered: None,
            next_experiment: None,
        }
    }

    /// With what `capstan discover` found beyond the catalogue.
    pub fn with_discovered(mut self, d: Discovered<'a>) -> Self {
        self.discovered = Some(d);
        self
    }

    /// With the "Next experiment" object.
    pub fn with_next(mut self, n: &'a NextExperiment) -> Self {
        self.next_experiment = Some(n);
        self
    }

    /// With the data checks' warnings.
    pub fn with_data_warnings(mut self, w: &'a [String]) -> Self {
        self.data.warnings = Some(w);
        self
    }

    /// The file's text: pretty JSON, keys sorted at every level.
    pub fn to_json(&self) -> serde_json::Result<String> {
        to_sorted_json(self)
    }
}

/// `v` as pretty JSON with the keys of every object sorted (as `metrics.json` has always been
/// written: through serde_json's map, sorted without its `preserve_order` feature), so the
/// file's layout does not follow the declaration order of the types inside.
pub fn to_sorted_json(v: &impl Serialize) -> serde_json::Result<String> {
    serde_json::to_string_pretty(&serde_json::to_value(v)?)
}
