//! The fitted model as the board's law (`capstan rig load-model --from metrics.json`, and
//! `capstan simulate --mode force --model-from`): `metrics.json`'s prediction model at the rig's
//! wrap, diameter and drive voltage, reduced to the four numbers the board holds
//! (`capstan_sim::force::board_law`, checked to follow the model within 1 % or 0.05 N), refused if
//! the rig is outside what the model was fitted on: a force controller must not extrapolate
//! the law its feedforward goes through.

use anyhow::bail;
use capstan_engine::analysis::prediction::PredictionModel;
use capstan_engine::fit::Param;
use capstan_physics::{Model, Operating};
use capstan_rig::command::Key;
use capstan_rig::BoardLaw;
use std::path::Path;

/// Where the rig works: what the board's settings say.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigPoint {
    /// Wrap, deg.
    pub wrap_deg: f64,
    /// Capstan diameter, mm.
    pub diameter_mm: f64,
    /// Drive voltage, V.
    pub drive_v: f64,
    /// The largest T2 target, N.
    pub max_target_n: f64,
}

/// The law, and what it was made from.
#[derive(Clone, Debug)]
pub struct Loaded {
    /// The board's law.
    pub law: BoardLaw,
    /// The fitted model at its population values.
    pub model: Model,
    /// The one-mu Euler-Eytelwein fit of the same analysis (`models`' baseline), if it has one.
    pub euler_eytelwein_mu: Option<f64>,
    /// The T1 the largest target needs, N.
    pub t1_max_n: f64,
}

impl Loaded {
    /// The `set` lines that put the law on the board.
    pub fn set_lines(&self) -> Vec<String> {
        let l = &self.law;
        [
            (Key::ModelMu, l.mu),
            (Key::ModelHeatPerN, l.heat_per_n),
            (Key::ModelT2OffsetN, l.t2_offset_n),
            (Key::ModelExponent, l.exponent),
        ]
        .iter()
        .map(|(k, v)| format!("set {} {v}", k.name()))
        .collect()
    }
}

/// The model at the prediction model's population values.
pub fn model_of(pm: &PredictionModel) -> Model {
    let mut m = Model::euler_eytelwein(0.0);
    for p in Param::ALL {
        if let Some(v) = pm.values.get(p.name()) {
            p.set(&mut m, *v);
        }
    }
    m
}

/// The board's law for the model in `path` (a `metrics.json`) at `rig`.
pub fn load(path: &Path, rig: &RigPoint) -> anyhow::Result<Loaded> {
    let read = capstan_report::read_and_validate(path)?;
    let mut loaded = reduce(&read.prediction_model, rig)
        .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    loaded.euler_eytelwein_mu = read.euler_eytelwein_mu;
    Ok(loaded)
}

/// The board's law for `pm` at `rig`, refused where the rig is outside the fitted data.
pub fn reduce(pm: &PredictionModel, rig: &RigPoint) -> anyhow::Result<Loaded> {
    let r = &pm.fitted_range;
    if rig.wrap_deg.is_nan() || rig.wrap_deg <= 0.0 {
        bail!("the rig's wrap is not set: set wrap_deg first (the law's wrap)");
    }
    if rig.diameter_mm.is_nan() || rig.diameter_mm <= 0.0 {
        bail!("the rig's capstan diameter is not set: set diameter_mm first");
    }
    for (what, v, span, unit) in [
        ("wrap", rig.wrap_deg, r.wrap_deg, "°"),
        ("capstan diameter", rig.diameter_mm, r.diameter_mm, " mm"),
        ("drive voltage", rig.drive_v, r.drive_v, " V"),
    ] {
        if !span.contains(v) {
            bail!(
                "out of the model's range: the rig's {what} is {v}{unit}, the model was fitted on \
                 {}{unit} to {}{unit}; a force controller must not extrapolate its law (fit the \
                 model on data that cover the rig)",
                span.min,
                span.max
            );
        }
    }
    let model = model_of(pm);
    let op = Operating {
        diameter_mm: rig.diameter_mm,
        drive_v: rig.drive_v,
        ..Operating::from_wrap_deg(rig.wrap_deg)
    };
    // The T1 the largest target needs, by the model itself (settled heating).
    let t1_needed = bisect_t1(&model, &op, rig.max_target_n);
    if !r.t1_n.contains(t1_needed) {
        bail!(
            "out of the model's range: the largest target, {} N at {}°, needs T1 = {t1_needed:.2} \
             N by the model, outside the T1 it was fitted on ({:.2} to {:.2} N)",
            rig.max_target_n,
            rig.wrap_deg,
            r.t1_n.min,
            r.t1_n.max
        );
    }
    let t1_max_n = (1.2 * t1_needed).min(r.t1_n.max);
    let law = capstan_sim::force::board_law(&model, &op, t1_max_n)?;
    Ok(Loaded {
        law,
        model,
        euler_eytelwein_mu: None,
        t1_max_n: t1_needed,
    })
}

/// The T1 reading the model needs for a T2 reading of `t2_n` (bisection on its settled law).
pub fn bisect_t1(model: &Model, op: &Operating, t2_n: f64) -> f64 {
    let (mut lo, mut hi) = (0.0f64, t2_n.max(1.0) * 2.0);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if capstan_sim::force::settled_t2_n(model, mid, op) < t2_n {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}
