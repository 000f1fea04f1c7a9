//! The one parameter table: every fitted quantity once, with its unit and 95 % interval, the
//! per-cord mu included; where two models estimate the same quantity differently, both rows,
//! with the reason. `metrics.json` carries the same rows (`parameters`), and the headline quotes
//! them.

use capstan_engine::analysis::Analysis;
use capstan_engine::fit::stats::mean;
use serde::Serialize;

/// One row of the table.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    /// Stable key (`extended.mu`, `cord.D12.7/270deg.mu`, ...).
    pub key: String,
    /// The quantity in words.
    pub quantity: String,
    /// Which model or estimate.
    pub source: String,
    /// Value.
    pub value: f64,
    /// Unit ("1" for a pure number).
    pub unit: &'static str,
    /// 95 % interval, lower end (NaN → null when none is computed).
    pub ci95_lo: Option<f64>,
    /// 95 % interval, upper end.
    pub ci95_hi: Option<f64>,
    /// How the interval was computed, or why two estimates differ.
    pub note: String,
}

/// Two-sided 95 % Student t quantile.
fn t95(dof: usize) -> f64 {
    use statrs::distribution::{ContinuousCDF, StudentsT};
    if dof == 0 {
        return f64::NAN;
    }
    StudentsT::new(0.0, 1.0, dof as f64).map_or(1.96, |t| t.inverse_cdf(0.975))
}

fn fin(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

/// Unit and words of a model parameter.
pub fn describe(name: &str) -> (&'static str, &'static str) {
    match name {
        "mu" => (
            "1",
            "friction coefficient mu (population, at 1 N, run 1, time 0)",
        ),
        "n" => ("1", "tension exponent n of dT/dθ = k·Tⁿ"),
        "b_nm2" => ("N m²", "bending stiffness of the cord"),
        "mu_change_per_100s" => ("1/(100 s)", "fractional drift of mu per 100 s"),
        "mu_change_per_run" => ("1/run", "fractional change of mu per repeat run"),
        "mu_change_per_mm" => ("1/mm", "fractional change of mu per mm of diameter"),
        "mu_change_per_v" => ("1/V", "fractional change of mu per volt of drive"),
        "mu_log_slope_per_rad" => ("1/rad", "change of ln mu per radian of wrap"),
        "heat_per_ns" => (
            "1/(N s)",
            "contact heating h: mu falls by exp(−h·H), H the friction load remembered (N s)",
        ),
        "heat_tau_s" => ("s", "memory time of the friction load"),
        "t1_offset_n" => ("N", "zero offset (or path loss) of the T1 reading"),
        "t2_offset_n" => ("N", "zero offset of the T2 reading"),
        "t2_gain" => ("1", "gain of the T2 reading relative to T1"),
        _ => ("?", "model parameter"),
    }
}

/// Every row, in table order: the extended model, the evidence engine's estimates of the same
/// quantities, Euler-Eytelwein's mu, the variance components, then each cord's mu.
pub fn rows(a: &Analysis) -> Vec<Row> {
    let mut out = Vec::new();
    extended_rows(a, &mut out);
    evidence_rows(a, &mut out);
    baseline_row(a, &mut out);
    variance_rows(a, &mut out);
    cord_rows(a, &mut out);
    out
}

/// Each extended-model value, ± t(folds − 1) times its cord-jackknife SE.
fn extended_rows(a: &Analysis, out: &mut Vec<Row>) {
    let pm = &a.prediction_model;
    let t_cords = t95(pm.folds.saturating_sub(1));
    for v in &a.extended.values {
        let (unit, words) = describe(&v.name);
        let half = t_cords * v.jackknife_se;
        out.push(Row {
            key: format!("extended.{}", v.name),
            quantity: words.into(),
            source: "extended model".into(),
            value: v.value,
            unit,
            ci95_lo: fin(v.value - half),
            ci95_hi: fin(v.value + half),
            note: if pm.folds >= 2 {
                format!("value ± t({})·SE, SE from the cord jackknife over the leave-one-cord-out refits (cords as the independent units)", pm.folds - 1)
            } else {
                "no interval: the cord jackknife needs two cords or more".to_string()
            },
        });
    }
}

/// Euler-Eytelwein's one mu, ± t(folds − 1) times its SE.
fn baseline_row(a: &Analysis, out: &mut Vec<Row>) {
    let t_cords = t95(a.prediction_model.folds.saturating_sub(1));
    let b = a.baseline_fit.model(None).law.mu;
    let bse = a.baseline_mu_se;
    out.push(Row {
        key: "baseline.mu".into(),
        quantity: "friction coefficient mu".into(),
        source: "Euler-Eytelwein, one mu".into(),
        value: b,
        unit: "1",
        ci95_lo: fin(b - t_cords * bse),
        ci95_hi: fin(b + t_cords * bse),
        note: "differs from the extended model's mu because Euler-Eytelwein has no sensor offset or heating term: its one mu absorbs them".into(),
    });
}

/// The variance components of a new measurement (no intervals computed).
fn variance_rows(a: &Analysis, out: &mut Vec<Row>) {
    let pm = &a.prediction_model;
    let s = &a.evidence.scatter;
    // A spread the data cannot show (one cord; one run per cord) is not estimable, not 0.
    let shown = |v: f64, estimable: f64| if estimable.is_finite() { v } else { f64::NAN };
    for (key, q, v, unit, note) in [
        (
            "scatter.cord_ln_mu_sd",
            "cord-to-cord SD of ln mu",
            shown(a.extended.sigma_u, s.cord_pct),
            "1",
            "the extended (mixed) model's σ_u, its cord effects shrunk to the parameter budget; not what capstan predict uses for a new cord; no interval computed",
        ),
        (
            "scatter.run_ln_mu_sd",
            "run-to-run SD of ln mu on one cord",
            shown((1.0 + s.run_pct / 100.0).ln(), s.run_pct),
            "1",
            "evidence engine (every run its own mu); no interval computed",
        ),
        (
            "noise.abs_n",
            "within-run noise, absolute part",
            s.noise_abs_n,
            "N",
            "noise SD² = a² + (r·T2)²; no interval computed",
        ),
        (
            "noise.rel",
            "within-run noise, proportional part",
            s.noise_rel,
            "1",
            "fraction of T2; no interval computed",
        ),
        (
            "new_cord_error.abs_n",
            "a new cord's error in T2, constant part a (SD² = a² + (b·T2)²)",
            pm.new_cord_error.abs_n,
            "N",
            "fitted to the held-out residuals of the whole procedure (every cord predicted by the causes chosen and fitted without it) beyond the curve's own variance; in capstan predict's prediction interval; no interval computed",
        ),
        (
            "new_cord_error.rel",
            "a new cord's error in T2, part proportional to T2 (b)",
            pm.new_cord_error.rel,
            "1",
            "as above: the part that grows with T2; no interval computed",
        ),
        (
            "wrap_extrapolation_error.sd_n",
            "error of extrapolating in wrap (SD)",
            pm.wrap_extrapolation_error.sd_n,
            "N",
            "what fits without the smallest or the largest wrap miss there beyond the curve's variance and a new cord's error (0 when nothing more, or with fewer than three wraps); in capstan predict's prediction interval at wraps outside the fitted ones; no interval computed",
        ),
    ] {
        out.push(Row {
            key: key.into(),
            quantity: q.into(),
            source: "variance component".into(),
            value: v,
            unit,
            ci95_lo: None,
            ci95_hi: None,
            note: note.into(),
        });
    }
    out.push(Row {
        key: "scatter.cord_pct".into(),
        quantity: "cord-to-cord SD of mu, % of mu".into(),
        source: "variance component".into(),
        value: s.cord_pct,
        unit: "%",
        ci95_lo: None,
        ci95_hi: None,
        note: "evidence engine (every run its own mu): the headline's figure; larger than the extended model's σ_u above, which explains part of the cord differences by the named causes and shrinks the rest; no interval computed".into(),
    });
}

/// The evidence engine's estimate of each named cause, where the extended model has the same
/// quantity (converted to the extended model's parameter).
fn evidence_rows(a: &Analysis, out: &mut Vec<Row>) {
    for c in &a.mechanisms.causes {
        let Some(kind) = capstan_friction::EffectKind::from_name(c.name) else {
            continue;
        };
        let Some(p) = capstan_engine::fit::Param::from_effect(kind) else {
            continue;
        };
        let ev = &c.evidence;
        let Some((_, raw)) = ev["parameters"].as_object().and_then(|m| m.iter().next()) else {
            continue;
        };
        let (Some(raw), se) = (
            raw.as_f64(),
            ev["parameter_se"].as_f64().unwrap_or(f64::NAN),
        ) else {
            continue;
        };
        // The catalogue's heating value is h·τ; the model's is h.
        let scale = if kind == capstan_friction::EffectKind::ContactHeating {
            1.0 / capstan_friction::HEAT_TAU_S
        } else {
            1.0
        };
        let (value, se) = (raw * scale, se * scale);
        let (unit, words) = describe(p.name());
        out.push(Row {
            key: format!("evidence.{}", p.name()),
            quantity: words.into(),
            source: "evidence engine".into(),
            value,
            unit,
            ci95_lo: fin(value - 1.96 * se),
            ci95_hi: fin(value + 1.96 * se),
            note: format!("value ± 1.96·SE with runs as clusters; it differs from the extended model's row because the evidence engine gives every run its own mu (the extended model one mu per cord, shrunk), and a sensor or heating term trades off against mu differently in the two{}", if scale != 1.0 { format!("; the catalogue value {} = h·τ (τ = {} s) is shown as h", crate::cells::fx(raw, 5), capstan_friction::HEAT_TAU_S) } else { String::new() }),
        });
    }
}

/// Each cord's Euler-Eytelwein mu: every run's mean ln(T2/T1)/β, the cord's mean over its runs,
/// the interval from the runs as replicates.
fn cord_rows(a: &Analysis, out: &mut Vec<Row>) {
    let obs = &a.obs;
    for (g, grp) in obs.groups.iter().enumerate() {
        let mut runs: Vec<f64> = Vec::new();
        for r in obs.runs_of_group(g) {
            let mus: Vec<f64> = obs.runs[r]
                .iter()
                .map(|&i| &obs.rows[i])
                .filter(|row| row.t1_n > 0.0 && row.t2_n > 0.0)
                .map(|row| (row.t2_n / row.t1_n).ln() / row.op.wrap_rad)
                .collect();
            if !mus.is_empty() {
                runs.push(mean(&mus));
            }
        }
        let m = mean(&runs);
        let k = runs.len();
        let sd = if k > 1 {
            (runs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (k - 1) as f64).sqrt()
        } else {
            f64::NAN
        };
        let half = t95(k.saturating_sub(1)) * sd / (k as f64).sqrt();
        out.push(Row {
            key: format!("cord.{}.mu", grp.label),
            quantity: format!(
                "mu of cord {} ({:.0}°, D = {} mm)",
                grp.label, grp.wrap_deg, grp.diameter_mm
            ),
            source: "Euler-Eytelwein per cord".into(),
            value: m,
            unit: "1",
            ci95_lo: fin(m - half),
            ci95_hi: fin(m + half),
            note: format!(
                "mean over its {k} runs of each run's mean ln(T2/T1)/β; interval t({})·SD/√runs",
                k.saturating_sub(1)
            ),
        });
    }
}
