//! `metrics.json` read back: the prediction model `capstan analyze` wrote, its schema checked
//! before its fields, then its numbers checked against what an analysis can write (an edited
//! or damaged file fails here rather than giving intervals that mean nothing).

use capstan_data::ranges::shown;
use capstan_engine::analysis::prediction::{self, PredictionModel};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// Why `metrics.json` gives no usable prediction model; every message names the file.
#[derive(Debug, thiserror::Error)]
pub enum MetricsError {
    /// The file cannot be read.
    #[error("cannot read {}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The file is not JSON.
    #[error("{}:{line}:{column}: not JSON: {cause}", path.display())]
    NotJson {
        /// The file.
        path: PathBuf,
        /// Line of the error, from 1.
        line: usize,
        /// Column of the error, from 1.
        column: usize,
        /// What the JSON parser says.
        cause: serde_json::Error,
    },
    /// The file's layout version (the top-level `schema_version`) is not the one this program
    /// writes ([`super::METRICS_SCHEMA`]).
    #[error("{}: {}", path.display(), version_said(found.as_deref(), *reads))]
    SchemaVersion {
        /// The file.
        path: PathBuf,
        /// What stands there, as JSON (`None`: no `schema_version`).
        found: Option<String>,
        /// The version this program writes and reads.
        reads: u32,
    },
    /// No `prediction_model` (a file of metrics schema 1, or not an analysis's).
    #[error("{}: no prediction_model (written by capstan analyze from metrics schema 2 on; run capstan analyze again)", path.display())]
    NoPredictionModel {
        /// The file.
        path: PathBuf,
    },
    /// The model's schema is newer than this program reads.
    #[error("{}: prediction_model schema {found} is newer than this capstan reads ({reads}): use the capstan that wrote it, or a newer one", path.display())]
    SchemaNewer {
        /// The file.
        path: PathBuf,
        /// Its schema.
        found: u64,
        /// The schema this program reads.
        reads: u64,
    },
    /// The model's schema is older than this program reads.
    #[error("{}: prediction_model schema {found}, this capstan reads schema {reads} (run capstan analyze again)", path.display())]
    SchemaOlder {
        /// The file.
        path: PathBuf,
        /// Its schema.
        found: u64,
        /// The schema this program reads.
        reads: u64,
    },
    /// The model's schema is not a number.
    #[error("{}: prediction_model schema {found} is not a schema number (this capstan reads {reads})", path.display())]
    SchemaNotNumber {
        /// The file.
        path: PathBuf,
        /// What stands there, as JSON.
        found: String,
        /// The schema this program reads.
        reads: u64,
    },
    /// The model has no schema.
    #[error("{}: prediction_model has no schema (this capstan reads {reads}; run capstan analyze again)", path.display())]
    NoSchema {
        /// The file.
        path: PathBuf,
        /// The schema this program reads.
        reads: u64,
    },
    /// The analysis had fewer than two cords to leave out: no interval.
    #[error("{}: the analysis had fewer than two cords to leave out, so its model has no interval; analyse data with at least two cords", path.display())]
    TooFewCords {
        /// The file.
        path: PathBuf,
    },
    /// The model's fields are not the model's.
    #[error("{}: prediction_model is malformed: {cause}{}", path.display(), at.as_ref().map_or(String::new(), |f| format!(" (at {f})")))]
    Malformed {
        /// The file.
        path: PathBuf,
        /// What the JSON reader says.
        cause: serde_json::Error,
        /// The first field holding `null` where a number was expected, as a path.
        at: Option<String>,
    },
    /// The model's numbers are not ones an analysis writes.
    #[error("{}: prediction_model: {problem}", path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        problem: ModelProblem,
    },
}

/// What a [`MetricsError::SchemaVersion`] says after the file's name: what stands there, what
/// this program reads, and what to do (a newer file needs a newer capstan; any other, a new
/// analysis).
fn version_said(found: Option<&str>, reads: u32) -> String {
    match found {
        None => {
            format!("no schema_version (this capstan reads {reads}; run capstan analyze again)")
        }
        Some(f) if f.parse::<u64>().is_ok_and(|n| n > u64::from(reads)) => format!(
            "schema_version is {f}, newer than this capstan reads ({reads}): use the capstan \
             that wrote it, or a newer one"
        ),
        Some(f) => {
            format!("schema_version is {f}; this capstan reads {reads} (run capstan analyze again)")
        }
    }
}

/// What is wrong with a prediction model's numbers: which field, which value, and what an
/// analysis writes instead.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModelProblem {
    /// mu outside (0, 2].
    #[error("mu {} is not a friction coefficient above 0 and up to 2", shown(*.mu))]
    Mu {
        /// The value found.
        mu: f64,
    },
    /// A parameter value that is not a finite number.
    #[error("{name} = {} is not a number", shown(*.value))]
    NotANumber {
        /// The parameter.
        name: String,
        /// The value found.
        value: f64,
    },
    /// No free parameters.
    #[error("no free parameters (an analysis fits mu at least)")]
    NoFreeParameters,
    /// A free parameter without a value.
    #[error("free parameter {name} has no value")]
    FreeWithoutValue {
        /// The parameter.
        name: String,
    },
    /// The covariance is not n × n for n free parameters.
    #[error("the covariance is not {n} × {n} (one row per free parameter)")]
    CovarianceNotSquare {
        /// Free parameters.
        n: usize,
    },
    /// A covariance row not finite, or its variance negative.
    #[error("covariance row {row} is not finite or has a negative variance")]
    CovarianceRow {
        /// The row, from 1.
        row: usize,
    },
    /// An error's part that is negative or not a number.
    #[error("{field} = {} must be 0 or more", shown(*.value))]
    Negative {
        /// The field (`new_cord_error.abs_n`).
        field: String,
        /// The value found.
        value: f64,
    },
    /// An SD larger than its held-out and accounted RMS allow.
    #[error("{name}.sd_n {} exceeds what its held-out RMS {} and accounted RMS {} give ({})", shown(*.sd_n), shown(*.heldout_rms_n), shown(*.accounted_rms_n), shown(*.most))]
    SdExceeds {
        /// The error (`wrap_extrapolation_error`).
        name: String,
        /// Its SD, N.
        sd_n: f64,
        /// Its held-out RMS, N.
        heldout_rms_n: f64,
        /// Its accounted RMS, N.
        accounted_rms_n: f64,
        /// The most SD they give, N.
        most: f64,
    },
    /// A new cord's error with no held-out rows of two cords behind it.
    #[error("new_cord_error has no held-out rows of two cords or more behind it (no cord had a held-out prediction)")]
    NoHeldOutRows,
    /// Degrees of freedom that the cords cannot have.
    #[error("new_cord_error.dof = {dof} is not a number of degrees of freedom for {cords} cords")]
    DegreesOfFreedom {
        /// The degrees of freedom found.
        dof: usize,
        /// The cords behind the error.
        cords: usize,
    },
    /// An extrapolation SD without held-out rows.
    #[error("wrap_extrapolation_error has an SD but no held-out rows behind it")]
    SdWithoutRows,
    /// An extrapolation distance that is not one.
    #[error("wrap_extrapolation_step_deg = {step} is not the distance the error was measured at")]
    ExtrapolationStep {
        /// The distance found, deg.
        step: f64,
    },
    /// A fitted range whose ends are not a range.
    #[error("fitted_range.{name} {min} to {max} is not a range")]
    NotARange {
        /// The quantity.
        name: &'static str,
        /// Its lower end.
        min: f64,
        /// Its upper end.
        max: f64,
    },
}

/// What other commands read back from `metrics.json`.
#[derive(Clone, Debug)]
pub struct MetricsRead {
    /// The prediction model, checked.
    pub prediction_model: PredictionModel,
    /// The one-mu Euler-Eytelwein fit (`models[name = baseline].values.mu`), if the file
    /// holds it (what `capstan rig model` shows beside the fitted law).
    pub euler_eytelwein_mu: Option<f64>,
}

/// Read the prediction model of the `metrics.json` at `path`, and check it: the file's layout
/// version (`schema_version`, after the model's presence, so that a file of layout 1 is named
/// as one without a model), the model's schema, that it has an interval, its fields, and its
/// numbers ([`check`]).
pub fn read_and_validate(path: &Path) -> Result<MetricsRead, MetricsError> {
    let p = || path.to_path_buf();
    let text =
        std::fs::read_to_string(path).map_err(|source| MetricsError::Read { path: p(), source })?;
    let v: Value = serde_json::from_str(&text).map_err(|cause| MetricsError::NotJson {
        path: p(),
        line: cause.line(),
        column: cause.column(),
        cause,
    })?;
    let Some(pm) = v.get("prediction_model") else {
        return Err(MetricsError::NoPredictionModel { path: p() });
    };
    let layout = v.get("schema_version");
    if layout.and_then(Value::as_u64) != Some(u64::from(super::METRICS_SCHEMA)) {
        return Err(MetricsError::SchemaVersion {
            path: p(),
            found: layout.map(Value::to_string),
            reads: super::METRICS_SCHEMA,
        });
    }
    let reads = u64::from(prediction::SCHEMA);
    match pm.get("schema").map(|s| (s, s.as_u64())) {
        Some((_, Some(s))) if s == reads => {}
        Some((_, Some(found))) if found > reads => {
            return Err(MetricsError::SchemaNewer {
                path: p(),
                found,
                reads,
            })
        }
        Some((_, Some(found))) => {
            return Err(MetricsError::SchemaOlder {
                path: p(),
                found,
                reads,
            })
        }
        Some((v, None)) => {
            return Err(MetricsError::SchemaNotNumber {
                path: p(),
                found: v.to_string(),
                reads,
            })
        }
        None => return Err(MetricsError::NoSchema { path: p(), reads }),
    }
    if (pm.get("folds").and_then(Value::as_u64)).is_some_and(|k| k < 2) {
        return Err(MetricsError::TooFewCords { path: p() });
    }
    let model: PredictionModel =
        serde_json::from_value(pm.clone()).map_err(|cause| MetricsError::Malformed {
            path: p(),
            cause,
            at: null_field(pm),
        })?;
    check(&model).map_err(|problem| MetricsError::Invalid { path: p(), problem })?;
    Ok(MetricsRead {
        prediction_model: model,
        euler_eytelwein_mu: euler_eytelwein_mu(&v),
    })
}

/// The one-mu Euler-Eytelwein fit in `metrics.json` (`models[name = baseline].values.mu`,
/// the values being `[name, value]` pairs).
fn euler_eytelwein_mu(v: &Value) -> Option<f64> {
    let base = (v.get("models")?.as_array()?.iter())
        .find(|m| m.get("name").and_then(|n| n.as_str()) == Some("baseline"))?;
    (base.get("values")?.as_array()?.iter())
        .find(|p| p.get(0).and_then(|n| n.as_str()) == Some("mu"))?
        .get(1)?
        .as_f64()
}

/// The first field of `v` holding a `null` (where a number was expected), as a path.
fn null_field(v: &Value) -> Option<String> {
    let joined = |head: String, rest: String| {
        if rest.is_empty() {
            head
        } else {
            format!("{head}.{rest}")
        }
    };
    match v {
        Value::Null => Some(String::new()),
        Value::Object(m) => {
            (m.iter()).find_map(|(k, x)| null_field(x).map(|r| joined(k.clone(), r)))
        }
        Value::Array(a) => (a.iter().enumerate())
            .find_map(|(i, x)| null_field(x).map(|r| joined(format!("[{i}]"), r))),
        _ => None,
    }
}

/// A model error's numbers: finite, not negative, and an SD its held-out and accounted RMS
/// can give (sd² = max(0, held-out² − accounted²); more was edited).
fn check_error(name: &str, e: &prediction::ModelError) -> Result<(), ModelProblem> {
    for (part, v) in [
        ("sd_n", e.sd_n),
        ("heldout_rms_n", e.heldout_rms_n),
        ("accounted_rms_n", e.accounted_rms_n),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(ModelProblem::Negative {
                field: format!("{name}.{part}"),
                value: v,
            });
        }
    }
    let most = (e.heldout_rms_n.powi(2) - e.accounted_rms_n.powi(2))
        .max(0.0)
        .sqrt();
    if e.sd_n > most * (1.0 + 1e-9) + 1e-12 {
        return Err(ModelProblem::SdExceeds {
            name: name.to_string(),
            sd_n: e.sd_n,
            heldout_rms_n: e.heldout_rms_n,
            accounted_rms_n: e.accounted_rms_n,
            most,
        });
    }
    Ok(())
}

/// What `capstan analyze` writes and a prediction relies on: a finite mu in the catalogue's
/// range, a square covariance of the free parameters with a non-negative diagonal, a new
/// cord's error at or above 0 from the held-out rows of two cords or more, an extrapolation
/// error no more than its held-out residuals leave, known free parameters, and ranges that are
/// ranges.
pub fn check(pm: &PredictionModel) -> Result<(), ModelProblem> {
    let mu = pm.values.get("mu").copied().unwrap_or(f64::NAN);
    if !(mu.is_finite() && mu > 0.0 && mu <= 2.0) {
        return Err(ModelProblem::Mu { mu });
    }
    if let Some((k, v)) = pm.values.iter().find(|(_, v)| !v.is_finite()) {
        return Err(ModelProblem::NotANumber {
            name: k.clone(),
            value: *v,
        });
    }
    if pm.free.is_empty() {
        return Err(ModelProblem::NoFreeParameters);
    }
    if let Some(name) = pm.free.iter().find(|n| !pm.values.contains_key(n.as_str())) {
        return Err(ModelProblem::FreeWithoutValue { name: name.clone() });
    }
    check_covariance(pm)?;
    check_new_cord_error(&pm.new_cord_error)?;
    // Without three wraps there is nothing to extrapolate from: no rows, and then no error.
    let w = &pm.wrap_extrapolation_error;
    check_error("wrap_extrapolation_error", w)?;
    if w.rows == 0 && w.sd_n != 0.0 {
        return Err(ModelProblem::SdWithoutRows);
    }
    let step = pm.wrap_extrapolation_step_deg;
    if !(step.is_finite() && step >= 0.0) || (w.rows > 0 && step == 0.0) {
        return Err(ModelProblem::ExtrapolationStep { step });
    }
    let r = &pm.fitted_range;
    for (name, s) in [
        ("wrap_deg", r.wrap_deg),
        ("diameter_mm", r.diameter_mm),
        ("t1_n", r.t1_n),
        ("drive_v", r.drive_v),
    ] {
        if !(s.min.is_finite() && s.max.is_finite() && s.min <= s.max) {
            return Err(ModelProblem::NotARange {
                name,
                min: s.min,
                max: s.max,
            });
        }
    }
    Ok(())
}

/// A square covariance of the free parameters with a finite, non-negative diagonal.
fn check_covariance(pm: &PredictionModel) -> Result<(), ModelProblem> {
    let n = pm.free.len();
    let square = pm.covariance.len() == n && pm.covariance.iter().all(|r| r.len() == n);
    if !square {
        return Err(ModelProblem::CovarianceNotSquare { n });
    }
    for (i, row) in pm.covariance.iter().enumerate() {
        if row.iter().any(|c| !c.is_finite()) || row[i] < 0.0 {
            return Err(ModelProblem::CovarianceRow { row: i + 1 });
        }
    }
    Ok(())
}

/// A new cord's error at or above 0 from the held-out rows of two cords or more.
fn check_new_cord_error(e: &prediction::NewCordError) -> Result<(), ModelProblem> {
    for (name, v) in [
        ("abs_n", e.abs_n),
        ("rel", e.rel),
        ("heldout_rms_n", e.heldout_rms_n),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(ModelProblem::Negative {
                field: format!("new_cord_error.{name}"),
                value: v,
            });
        }
    }
    if e.rows == 0 || e.cords < 2 {
        return Err(ModelProblem::NoHeldOutRows);
    }
    if e.dof == 0 || e.dof > e.cords {
        return Err(ModelProblem::DegreesOfFreedom {
            dof: e.dof,
            cords: e.cords,
        });
    }
    Ok(())
}
