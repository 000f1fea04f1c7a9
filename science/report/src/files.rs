//! `predictions.csv`: the input rows with every model's predictions (`metrics.json`, every
//! number of the report, is [`crate::metrics`]).

use capstan_data::Dataset;
use capstan_engine::analysis::Analysis;

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
