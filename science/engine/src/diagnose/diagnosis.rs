//! What `capstan diagnose` answers (`Diagnosis`, serialised as its `--json` object).

use crate::evidence::{Adequacy, Columns, Evidence, NotTestable, Rival, RowsUsed, Scatter};
pub use crate::verdict::Found;
use capstan_data::structure::StructureSummary;
use capstan_physics::{Effect, EffectKind};
use serde::Serialize;
use std::collections::BTreeMap;

/// A step of the forward selection.
#[derive(Clone, Debug, Serialize)]
pub struct PathStep {
    /// The effect that came in.
    pub effect: &'static str,
    /// Its ΔBIC when it came in (given those before it).
    pub delta_bic: f64,
}

/// Plain Euler-Eytelwein with one mu.
#[derive(Clone, Debug, Serialize)]
pub struct Baseline {
    /// Least-squares mu (T2 residuals, all rows).
    pub mu: f64,
    /// RMSE of T2 with that mu, N.
    pub rmse_t2_n: f64,
    /// RMSE of T2 with every run's own mu, N (the null of the within-run comparisons).
    pub rmse_t2_run_mu_n: f64,
}

/// The found effects' population model: one mu refitted to all rows with the effects at the
/// sizes found.
#[derive(Clone, Debug, Serialize)]
pub struct Extended {
    /// RMSE of T2, N.
    pub rmse_t2_n: f64,
    /// RMSE of T2 with every run's own mu and the within-run effects, N.
    pub rmse_t2_run_mu_n: f64,
}

/// What the data set is made of.
#[derive(Clone, Debug, Serialize)]
pub struct DesignSummary {
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
    pub columns: Columns,
    /// Both rising and falling steps inside runs.
    pub both_directions: bool,
    /// Cord × step cells with at least two runs (the pure error's replicates).
    pub replicated_cells: usize,
}

/// ΔBIC thresholds below which a candidate is named.
#[derive(Clone, Debug, Serialize)]
pub struct Thresholds {
    /// For within-run (shape) candidates.
    pub within_run: f64,
    /// For between-run and between-cord candidates.
    pub between: f64,
}

/// The data set read: where from, and how its rows map to cords and runs.
#[derive(Clone, Debug, Serialize)]
pub struct DataInfo {
    /// Where it came from.
    pub source: String,
    /// Its structure, and how each level was found (from columns, inferred, assumed).
    pub structure: StructureSummary,
    /// What the data checks warned about, as the command that read the data gives them
    /// (`None`: not given, and not in the JSON).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub warnings: Option<Vec<String>>,
}

/// The answer.
#[derive(Clone, Debug, Serialize)]
pub struct Diagnosis {
    /// The data set and its structure.
    pub data: DataInfo,
    /// The strongest effect found (`none` if nothing is supported).
    pub effect: &'static str,
    /// Its parameter (empty for `none`).
    pub parameters: BTreeMap<&'static str, f64>,
    /// Every effect found, strongest first, each with its evidence given the others.
    pub effects: Vec<Found>,
    /// Structure is left that no catalogue effect explains (see `adequacy`).
    pub unexplained: bool,
    /// The pattern that remains, if any (`step_direction`, `t1_shape`, `time`, `wrap`,
    /// `diameter`, `cells`).
    pub residual_pattern: Option<&'static str>,
    /// Candidates that, in place of a found effect, explain the data almost as well: the data
    /// cannot rule them out (with why, where the design says so).
    pub rivals: Vec<Rival>,
    /// The answer in plain words, generated from the decision.
    pub verdict: String,
    /// The tests of what is left.
    pub adequacy: Adequacy,
    /// Every testable candidate's evidence given the found effects, found ones first.
    pub candidates: Vec<Evidence>,
    /// The order in which within-run effects came in.
    pub selection_path: Vec<PathStep>,
    /// Plain Euler-Eytelwein.
    pub baseline: Baseline,
    /// With the found effects.
    pub extended: Extended,
    /// Wall time of the diagnosis, s.
    pub elapsed_s: f64,
    /// Effects that could not be tested, and why.
    pub not_testable: Vec<NotTestable>,
    /// The data set's design.
    pub design: DesignSummary,
    /// Scatter of mu and the noise the found model leaves.
    pub scatter: Scatter,
    /// How many rows each part used.
    pub rows_used: RowsUsed,
    /// The decision rule: thresholds on ΔBIC per level.
    pub thresholds: Thresholds,
    /// Where the answer came from (program, commit, the input's SHA-256, the command line),
    /// as the command that prints it gives it (`None`: not given, and not in the JSON).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub provenance: Option<capstan_data::Provenance>,
    /// The strongest effect found.
    #[serde(skip)]
    pub kind: EffectKind,
    /// Its catalogue value (the neutral value for `none`).
    #[serde(skip)]
    pub value: f64,
}

impl Diagnosis {
    /// The candidate for `kind`, if it was tested.
    pub fn candidate(&self, kind: EffectKind) -> Option<&Evidence> {
        self.candidates.iter().find(|c| c.kind == kind)
    }

    /// The strongest found effect as a catalogue [`Effect`].
    pub fn found(&self) -> Effect {
        Effect {
            kind: self.kind,
            value: self.value,
        }
    }

    /// Every found effect as a catalogue [`Effect`], strongest first.
    pub fn found_effects(&self) -> Vec<Effect> {
        self.candidates
            .iter()
            .filter(|c| c.selected)
            .map(|c| Effect {
                kind: c.kind,
                value: c.value,
            })
            .collect()
    }

    /// The JSON object of `capstan diagnose --json`: pretty, the keys of every object sorted
    /// (as it has always been written), whatever the order of the fields here.
    pub fn to_json(&self) -> String {
        serde_json::to_value(self)
            .and_then(|v| serde_json::to_string_pretty(&v))
            .expect("a diagnosis serialises")
    }
}
