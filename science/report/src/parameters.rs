//! The one parameter table: every fitted quantity once, with its unit and 95 % interval, the
//! per-cord mu included; where two models estimate the same quantity differently, both rows,
//! with the reason. `metrics.json` carries the same rows (`parameters`), and the headline quotes
//! them.

use capstan_engine::analysis::Analysis;
use capstan_engine::fit::stats::mean;
use serde::Serialize;

mod words;
use words::{cord_words, dof_count, dof_words};
pub use words::{describe, mu_words};
pub(crate) use words::{heating_note, identified};

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
    /// Its standard error (None where none is computed; for a variance component the
    /// large-sample SE of its χ² interval's method).
    pub se: Option<f64>,
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
    let names: Vec<&str> = (a.extended.values.iter())
        .map(|v| identified(&v.name).0)
        .collect();
    for v in &a.extended.values {
        let (name, scale) = identified(&v.name);
        let (unit, words) = match describe(name) {
            (unit, _) if name == "mu" => (unit, mu_words(&names)),
            (unit, words) => (unit, words.to_string()),
        };
        let (value, se) = (v.value * scale, v.jackknife_se * scale);
        let half = t_cords * se;
        out.push(Row {
            key: format!("extended.{name}"),
            quantity: words,
            source: "extended model".into(),
            value,
            se: fin(se),
            unit,
            ci95_lo: fin(value - half),
            ci95_hi: fin(value + half),
            note: if pm.folds >= 2 {
                format!("value ± t({})·SE, SE from the cord jackknife over the leave-one-cord-out refits (cords as the independent units){}", pm.folds - 1, heating_note(name, value))
            } else {
                format!("no interval: the cord jackknife needs two cords or more{}", heating_note(name, value))
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
        se: fin(bse),
        unit: "1",
        ci95_lo: fin(b - t_cords * bse),
        ci95_hi: fin(b + t_cords * bse),
        note: format!("value ± t({})·SE, SE from the cord jackknife over the leave-one-cord-out refits (cords as the independent units); differs from the extended model's mu because Euler-Eytelwein has no sensor offset or heating term: its one mu absorbs them", a.prediction_model.folds.saturating_sub(1)),
    });
}

/// A variance component's row: its value, and its interval by `method` (None: not computed,
/// and `none` says why).
fn component(
    (key, quantity, unit): (&str, &str, &'static str),
    value: f64,
    interval: Option<crate::components::Interval>,
    method: String,
    none: &str,
) -> Row {
    let i = interval.filter(|_| value.is_finite());
    Row {
        key: key.into(),
        quantity: quantity.into(),
        source: "variance component".into(),
        value,
        se: i.and_then(|i| i.se),
        unit,
        ci95_lo: i.map(|i| i.lo),
        ci95_hi: i.map(|i| i.hi),
        note: match i {
            Some(_) => method,
            None => format!("{method}; no interval: {none}"),
        },
    }
}

/// The cords at the smallest and the largest wrap: the units of the wrap-extrapolation error.
fn edge_cords(a: &Analysis) -> usize {
    let obs = &a.obs;
    let wraps = capstan_engine::fit::stats::distinct(obs.groups.iter().map(|g| g.wrap_deg));
    match (wraps.first(), wraps.last()) {
        (Some(lo), Some(hi)) => (obs.groups.iter())
            .filter(|g| g.wrap_deg == *lo || g.wrap_deg == *hi)
            .count(),
        _ => 0,
    }
}

/// The variance components of a new measurement, each with its 95 % interval
/// ([`crate::components`] says how).
fn variance_rows(a: &Analysis, out: &mut Vec<Row>) {
    use crate::components::{cord_df, excess_sd, noise_df, sd};
    let pm = &a.prediction_model;
    let s = &a.evidence.scatter;
    let obs = &a.obs;
    let cords = obs.groups.len();
    let runs_per_cord: Vec<usize> = (0..cords).map(|g| obs.runs_of_group(g).len()).collect();
    let runs = obs.runs.len();
    // A spread the data cannot show (one cord; one run per cord) is not estimable, not 0.
    let shown = |v: f64, estimable: f64| if estimable.is_finite() { v } else { f64::NAN };
    let (spread, what) = cord_spread(a);
    let spread = shown(spread, s.cord_pct);
    let df_u = cords.saturating_sub(1) as f64;
    out.push(component(
        ("scatter.cord_ln_mu_sd", "cord-to-cord SD of ln mu", "1"),
        spread,
        sd(spread, df_u),
        format!("{what}; not what capstan predict uses for a new cord; χ² interval on cords − 1 = {}, as if the cord effects were seen without error (approximate)", dof_count(df_u)),
        "one cord, or the cord effects at 0",
    ));
    let run_sd = shown((1.0 + s.run_pct / 100.0).ln(), s.run_pct);
    let df_e = runs.saturating_sub(cords) as f64;
    out.push(component(
        ("scatter.run_ln_mu_sd", "run-to-run SD of ln mu on one cord", "1"),
        run_sd,
        sd(run_sd, df_e),
        format!("evidence engine (every run its own mu); χ² interval on runs − cords = {} (exact for a balanced design under normality)", dof_count(df_e)),
        "no cord has two runs",
    ));
    let df_noise = noise_df(obs.len(), runs, s.lag1_autocorrelation);
    let noise_method = format!("χ² interval on the within-run residuals' effective degrees of freedom, (rows − runs)·(1 − ρ)/(1 + ρ): {} with ρ = {:.2} their lag-1 autocorrelation", dof_words(df_noise), s.lag1_autocorrelation);
    out.push(component(
        ("noise.abs_n", "within-run noise, absolute part", "N"),
        s.noise_abs_n,
        sd(s.noise_abs_n, df_noise),
        format!("noise SD² = a² + (r·T2)²; {noise_method}"),
        "the part is at 0",
    ));
    out.push(component(
        ("noise.rel", "within-run noise, proportional part", "1"),
        s.noise_rel,
        sd(s.noise_rel, df_noise),
        "a fraction of T2; its interval as the absolute part's above (the two move together)"
            .to_string(),
        "the part is at 0",
    ));
    // A new cord's error is predict's error model, fitted to the held-out residuals, not a
    // variance component of these data: its own source, and no interval (not computed).
    let nc = &pm.new_cord_error;
    let error_model = |r: Row| Row {
        source: "new-cord error model".into(),
        ..r
    };
    let mut error_rows = vec![error_model(component(
        ("new_cord_error.abs_n", "a new cord's error in T2, constant part a (SD² = a² + (b·T2)²)", "N"),
        nc.abs_n,
        None,
        format!("fitted to the held-out residuals of the whole procedure (every cord predicted by the causes chosen and fitted without it; {} cords) beyond the curve's own variance; in capstan predict's prediction interval", nc.cords),
        "not computed (a two-part fit to held-out residuals)",
    ))];
    error_rows.push(error_model(component(
        (
            "new_cord_error.rel",
            "a new cord's error in T2, part proportional to T2 (b)",
            "1",
        ),
        nc.rel,
        None,
        "as above: the part that grows with T2".to_string(),
        "as above",
    )));
    let we = &pm.wrap_extrapolation_error;
    let edge_cords = if we.rows > 0 { edge_cords(a) } else { 0 };
    out.push(component(
        ("wrap_extrapolation_error.sd_n", "error of extrapolating in wrap (SD)", "N"),
        we.sd_n,
        excess_sd(we.heldout_rms_n, we.accounted_rms_n, edge_cords),
        format!("what fits without the smallest or the largest wrap miss there beyond the curve's variance and a new cord's error (0: nothing more, or fewer than three wraps); in capstan predict's interval outside the fitted wraps; χ² interval on those misses' mean square ({edge_cords} cords at the end wraps), less the other components, clamped at 0"),
        "not measured (fewer than three wraps)",
    ));
    let cord_pct = s.cord_pct;
    let df_c = cord_df(s.cord_pct, s.run_pct, &runs_per_cord);
    out.push(component(
        ("scatter.cord_pct", "cord-to-cord SD of mu, % of mu", "%"),
        cord_pct,
        sd(cord_pct, df_c),
        format!("evidence engine (every run its own mu): the headline's figure; χ² interval on Satterthwaite's {} for the cord component of the runs' mu", dof_words(df_c)),
        "one cord, or the component at 0",
    ));
    // After the variance components, so each source is one group of the table.
    out.append(&mut error_rows);
}

/// The extended model's cord-to-cord SD of ln mu and what it is. Where its cord effects were
/// shrunk to the parameter budget, λ was raised until they fit it and σ_u = √(σ²/λ) follows
/// from the budget, not from the cords (the thesis: 0.0162, a third of its own cord effects'
/// SD, which are shrunk by about a tenth): then the fitted effects' sample SD is the spread.
/// Otherwise σ_u, with λ = σ²/σ_u² re-estimated, is.
fn cord_spread(a: &Analysis) -> (f64, String) {
    use capstan_engine::analysis::fits::STRICT_BUDGET;
    let e = &a.extended;
    let sigma_u = crate::cells::fx(e.sigma_u, 4);
    if e.n_fixed as f64 + e.edf_random < STRICT_BUDGET - 0.05 {
        let w = "the extended (mixed) model's σ_u, with λ = σ²/σ_u² re-estimated".to_string();
        return (e.sigma_u, w);
    }
    let u: Vec<f64> = e.cord_log_mu.iter().map(|c| c.1).collect();
    let sd = match u.len() {
        0 | 1 => f64::NAN,
        n => {
            let mean = u.iter().sum::<f64>() / n as f64;
            (u.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
        }
    };
    let w = format!("SD of the extended (mixed) model's fitted cord effects on ln mu; the model's own σ_u = {sigma_u} is set by its {STRICT_BUDGET:.0}-parameter budget, not estimated");
    (sd, w)
}

/// The evidence engine's estimate of each named cause, where the extended model has the same
/// quantity (converted to the extended model's parameter).
fn evidence_rows(a: &Analysis, out: &mut Vec<Row>) {
    for c in &a.mechanisms.causes {
        let Some(kind) = capstan_physics::EffectKind::from_name(c.name) else {
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
        // The catalogue's value is what the data identify (heating's k = h·τ, as the table
        // gives it).
        let (value, se) = (raw, se);
        let (name, _) = identified(p.name());
        let (unit, words) = describe(name);
        out.push(Row {
            key: format!("evidence.{name}"),
            quantity: words.into(),
            source: "evidence engine".into(),
            value,
            se: fin(se),
            unit,
            ci95_lo: fin(value - 1.96 * se),
            ci95_hi: fin(value + 1.96 * se),
            note: format!("value ± 1.96·SE with runs as clusters; it differs from the extended model's row because here every run has its own mu (there every cord, shrunk), and a sensor or heating term trades off against mu differently in the two{}", heating_note(name, value)),
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
            quantity: cord_words(&grp.label, grp.wrap_deg, grp.diameter_mm),
            source: "Euler-Eytelwein per cord".into(),
            value: m,
            se: fin(sd / (k as f64).sqrt()),
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
