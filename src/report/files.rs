//! `metrics.json` (every number of the report) and `predictions.csv` (the input rows with
//! every model's predictions).

use crate::analysis::Analysis;
use crate::data::Dataset;
use serde_json::{json, Value};
use std::fmt::Write as _;

/// The contents of `metrics.json`.
pub fn metrics_json(a: &Analysis, closed_loop: &Value) -> Value {
    let ext = a.models.iter().find(|m| m.name == "extended");
    json!({
        "data": {
            "source": a.source,
            "rows": a.obs.len(),
            "cords": a.obs.groups.len(),
            "runs": a.obs.runs.len(),
            "timing_source": a.obs.timing,
            "timing_note": "Without a time_s column, step k of the thesis protocol starts 10k + 0.5 s after the trigger, its conditioning window (2 s after the change to 1 s before the next) is centred at 10k + 6 s, and it ends at 10k + 10.5 s; the load memory starts at zero at the first kept step of each run.",
        },
        "models": a.models,
        "n_params_note": ext.map(|m| format!(
            "n_params of the extended model counts fixed effects + variance components ({} + {} = {}), the standard mixed-model convention that the ≤ 12 budget uses: the per-cord effects are predicted from one fitted variance, not free. Counted strictly by their effective degrees of freedom ({:.2}), the model uses {:.2}; with the cord effects shrunk until fixed + edf = 12 its in-sample RMSE is {:.3} N.",
            m.n_params_detail.fixed, m.n_params_detail.variance_components, m.n_params, m.n_params_detail.edf_random, m.n_params_strict, a.extended.strict12.rmse_t2_n)),
        "causes": a.mechanisms.causes,
        "mechanisms": a.mechanisms.tests,
        "variants": a.mechanisms.variants,
        "tau_profile": a.mechanisms.tau_profile,
        "low_tension_by_cord": a.mechanisms.low_tension_by_cord,
        "intercept_vs_slope": a.mechanisms.intercept_vs_slope,
        "cord_lines": a.mechanisms.cord_lines,
        "residual_patterns": a.residual_patterns,
        "thesis_per_angle_r2": a.thesis_per_angle_r2,
        "extended_fit": a.extended,
        "protocol_limits": a.mechanisms.protocol_limits,
        "diagnose": a.diagnosis,
        "closed_loop": closed_loop,
        "elapsed_s": a.elapsed,
    })
}

fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v}")
    } else {
        String::new()
    }
}

/// `predictions.csv`: the input rows (columns as read) plus the cord, the step timing used, and
/// every model's prediction.
pub fn predictions_csv(ds: &Dataset, a: &Analysis) -> String {
    let mut s = String::new();
    let mut header: Vec<String> = ds.header.clone();
    header.extend(
        [
            "cord",
            "window_centre_s",
            "t2_baseline_n",
            "t2_baseline_per_cord_n",
            "t2_thesis_n",
            "t2_extended_n",
            "t2_extended_population_n",
            "t2_baseline_loco_n",
            "t2_baseline_per_cord_loco_n",
            "t2_extended_loco_n",
            "h_extended_ns",
        ]
        .map(String::from),
    );
    let _ = writeln!(s, "{}", header.join(","));
    let p = &a.pred;
    for (i, pair) in ds.pairs.iter().enumerate() {
        let mut cells: Vec<String> = ds
            .header
            .iter()
            .map(|h| match h.as_str() {
                "capstan_diameter_mm" => pair.capstan_diameter_mm.map_or(String::new(), num),
                "wrap_deg" => num(pair.wrap_deg),
                "drive_v" => pair.drive_v.map_or(String::new(), num),
                "run" => pair.run.map_or(String::new(), num),
                "step" => pair.step.map_or(String::new(), num),
                "time_s" => pair.time_s.map_or(String::new(), num),
                "t1_n" => num(pair.t1_n),
                "t2_n" => num(pair.t2_n),
                other => ds
                    .extra_columns
                    .iter()
                    .position(|c| c == other)
                    .map_or(String::new(), |k| num(pair.extra[k])),
            })
            .collect();
        let row = &a.obs.rows[i];
        cells.push(a.obs.groups[row.group].label.clone());
        cells.push(num(row.timing.centre_s));
        for v in [
            p.baseline[i],
            p.baseline_per_cord[i],
            p.thesis[i],
            p.extended[i],
            p.extended_population[i],
            p.baseline_loco[i],
            p.baseline_per_cord_loco[i],
            p.extended_loco[i],
            p.extended_load_memory_ns[i],
        ] {
            cells.push(num(v));
        }
        let _ = writeln!(s, "{}", cells.join(","));
    }
    s
}
