//! `metrics.json` (every number of the report) and `predictions.csv` (the input rows with
//! every model's predictions).

use capstan_data::Dataset;
use capstan_engine::analysis::Analysis;
use serde_json::{json, Value};

/// Version of `metrics.json`'s layout: 2 added `schema_version`, `provenance`,
/// `thesis_comparison`, `headline`, `parameters` and `prediction_model` (what `capstan predict`
/// reads).
pub const METRICS_SCHEMA: u32 = 2;

/// The contents of `metrics.json`.
pub fn metrics_json(a: &Analysis, closed_loop: &Value, ctx: &crate::Context) -> Value {
    json!({
        "schema_version": METRICS_SCHEMA,
        "provenance": ctx.provenance,
        "thesis_comparison": {"shown": ctx.thesis.shown, "why": ctx.thesis.why},
        "headline": crate::headline::headline(a),
        "parameters": crate::parameters::rows(a),
        "prediction_model": a.prediction_model,
        "data": {
            "source": a.source,
            "rows": a.obs.len(),
            "cords": a.obs.groups.len(),
            "runs": a.obs.runs.len(),
            "structure": a.evidence.data.structure,
            "timing_source": a.obs.timing,
            "timing_note": "Without a time_s column, step k of the thesis protocol starts 10k + 0.5 s after the trigger, its conditioning window (2 s after the change to 1 s before the next) is centred at 10k + 6 s, and it ends at 10k + 10.5 s; the load memory starts at zero at the first kept step of each run.",
        },
        "models": a.models,
        "gain": {
            "loco_rmse_ratio_extended_over_baseline": a.gain,
            "cords_predicted_better": a.held_out.iter().filter(|c| c.extended_better).count(),
            "cords": a.held_out.len(),
        },
        "held_out": a.held_out,
        "ln_amp_by_step": a.ln_amp_by_step,
        "parameter_count_note": "Every model's count is its fixed values plus the effective degrees of freedom of its cord effects (Σ J_g/(J_g + λ)); AIC and BIC in `models` treat rows as independent and are shown for comparison with the thesis only: the causes are judged by the evidence engine (`evidence`), which does not.",
        "causes": a.mechanisms.causes,
        "unexplained": a.mechanisms.unexplained,
        "mechanisms": a.mechanisms.tests,
        "selection_path": a.mechanisms.selection_path,
        "evidence": a.evidence,
        "residual_patterns": a.residual_patterns,
        "thesis_per_angle_r2": a.thesis_per_angle_r2,
        "extended_fit": a.extended,
        "protocol_limits": a.mechanisms.protocol_limits,
        "fits_not_converged": a.fit_notes,
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

/// `predictions.csv`: the input rows (columns as read) plus the cord and run of the data set's
/// structure (`run_id`: 1, 2, ... in the order the runs first appear), the step timing used, and
/// every model's prediction, written row by row (a million rows are ~230 MB: not held).
pub fn write_predictions_csv(
    s: &mut impl std::io::Write,
    ds: &Dataset,
    a: &Analysis,
) -> std::io::Result<()> {
    let mut header: Vec<String> = ds.header.clone();
    header.extend(
        [
            "cord",
            "run_id",
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
    writeln!(s, "{}", header.join(","))?;
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
                other => match ds.label_columns.iter().position(|c| c.name == other) {
                    Some(k) => capstan_data::text_cell(&pair.labels[k]),
                    None => ds
                        .extra_columns
                        .iter()
                        .position(|c| c == other)
                        .map_or(String::new(), |k| num(pair.extra[k])),
                },
            })
            .collect();
        let row = &a.obs.rows[i];
        cells.push(capstan_data::text_cell(&a.obs.groups[row.group].label));
        cells.push((row.run + 1).to_string());
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
        writeln!(s, "{}", cells.join(","))?;
    }
    Ok(())
}
