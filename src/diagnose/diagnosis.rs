//! What `capstan diagnose` answers (`Diagnosis`, serialised as its `--json` object) and the
//! options of the decision rule.

use super::{prep, BETWEEN_THRESHOLD, WITHIN_THRESHOLD};
use capstan_friction::{Effect, EffectKind};
use serde::Serialize;
use std::collections::BTreeMap;

/// Options of [`diagnose_with`].
#[derive(Clone, Copy, Debug)]
pub struct Options {
    /// A within-run (shape) candidate is supported when its ΔBIC < −this.
    pub within_threshold: f64,
    /// A between-run or between-cord candidate is supported when its ΔBIC < −this.
    pub between_threshold: f64,
    /// Without `time_s`, take the window times from `step` with the thesis protocol
    /// (10 s steps): makes `thermal_drift` testable on the thesis data.
    pub protocol_times: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            within_threshold: WITHIN_THRESHOLD,
            between_threshold: BETWEEN_THRESHOLD,
            protocol_times: false,
        }
    }
}

/// At which level of the data a candidate is judged.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Level {
    /// Shape inside runs (run mu free).
    WithinRun,
    /// Runs' mu against a covariate that varies between cords (cord scatter as error).
    BetweenCord,
    /// Runs' mu against the run number within cords (run scatter as error).
    BetweenRun,
}

/// One candidate effect, fitted.
#[derive(Clone, Debug, Serialize)]
pub struct Candidate {
    /// Catalogue name.
    pub effect: &'static str,
    /// BIC of the model with this effect minus BIC of `none` (negative: supported).
    pub delta_bic: f64,
    /// The fitted catalogue parameter.
    pub parameters: BTreeMap<&'static str, f64>,
    /// Its standard error.
    pub parameter_se: f64,
    /// Where the evidence comes from.
    pub level: Level,
    /// The parameter is outside the region of practical equivalence with `none` (see
    /// [`practically_relevant`]).
    pub relevant: bool,
    /// ΔBIC is below the threshold of its level and the size is relevant.
    pub supported: bool,
    /// The effect.
    #[serde(skip)]
    pub kind: EffectKind,
    /// The fitted catalogue value.
    #[serde(skip)]
    pub value: f64,
}

/// An effect that could not be tested on this data set.
#[derive(Clone, Debug, Serialize)]
pub struct NotTestable {
    /// Catalogue name.
    pub effect: &'static str,
    /// Why.
    pub reason: String,
}

/// Plain Euler-Eytelwein with one mu.
#[derive(Clone, Debug, Serialize)]
pub struct Baseline {
    /// Least-squares mu (T2 residuals, all rows).
    pub mu: f64,
    /// RMSE of T2 with that mu, N.
    pub rmse_t2_n: f64,
    /// RMSE of T2 with every run's own mu, N (the within-run noise of the comparison).
    pub rmse_t2_run_mu_n: f64,
}

/// The chosen effect's population model (one mu and the effect) refitted to all rows.
#[derive(Clone, Debug, Serialize)]
pub struct Extended {
    /// RMSE of T2, N.
    pub rmse_t2_n: f64,
    /// RMSE of T2 with every run's own mu and the effect, N (within-run effects only).
    pub rmse_t2_run_mu_n: f64,
}

/// What the data set is made of.
#[derive(Clone, Debug, Serialize)]
pub struct Design {
    /// Rows.
    pub rows: usize,
    /// Cords: (diameter, voltage, wrap) combinations.
    pub cords: usize,
    /// Runs (or cords, without a `run` column).
    pub runs: usize,
    /// Distinct wraps, deg.
    pub wraps_deg: Vec<f64>,
    /// Distinct diameters, mm.
    pub diameters_mm: Vec<f64>,
    /// Distinct drive voltages, V.
    pub drive_v: Vec<f64>,
    /// Optional columns present.
    pub columns: prep::Columns,
}

/// Scatter and noise the models found.
#[derive(Clone, Debug, Serialize)]
pub struct Scatter {
    /// Cord-to-cord standard deviation of mu, % of mu.
    pub cord_pct: f64,
    /// Run-to-run standard deviation of mu within cords, % of mu.
    pub run_pct: f64,
    /// Residual standard deviation of T2 with run-level mu (Euler-Eytelwein), N.
    pub within_run_sd_n: f64,
    /// Overdispersion ĉ of the within-run likelihood ratios (clustering of residuals in runs).
    pub overdispersion: f64,
}

/// ΔBIC thresholds below which a candidate is supported.
#[derive(Clone, Debug, Serialize)]
pub struct Thresholds {
    /// For within-run (shape) candidates.
    pub within_run: f64,
    /// For between-run and between-cord candidates.
    pub between: f64,
}

/// The answer.
#[derive(Clone, Debug, Serialize)]
pub struct Diagnosis {
    /// The effect found (`none` if nothing is supported).
    pub effect: &'static str,
    /// Its parameter (empty for `none`).
    pub parameters: BTreeMap<&'static str, f64>,
    /// Every testable effect, best (lowest ΔBIC) first.
    pub candidates: Vec<Candidate>,
    /// Plain Euler-Eytelwein.
    pub baseline: Baseline,
    /// With the chosen effect.
    pub extended: Extended,
    /// Wall time of the diagnosis, s.
    pub elapsed_s: f64,
    /// Effects that could not be tested, and why.
    pub not_testable: Vec<NotTestable>,
    /// The data set's design.
    pub design: Design,
    /// Scatter of mu and within-run noise.
    pub scatter: Scatter,
    /// The decision rule: thresholds on ΔBIC per level.
    pub thresholds: Thresholds,
    /// The effect found.
    #[serde(skip)]
    pub kind: EffectKind,
    /// Its catalogue value (the neutral value for `none`).
    #[serde(skip)]
    pub value: f64,
}

impl Diagnosis {
    /// The candidate for `kind`, if it was tested.
    pub fn candidate(&self, kind: EffectKind) -> Option<&Candidate> {
        self.candidates.iter().find(|c| c.kind == kind)
    }

    /// The found effect as a catalogue [`Effect`].
    pub fn found(&self) -> Effect {
        Effect {
            kind: self.kind,
            value: self.value,
        }
    }

    /// The JSON object of `capstan diagnose --json`.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a diagnosis serialises")
    }
}
