//! The current design the planner rebuilds from a data set, without simulating (`open`).

/// The thesis data with every run copied `copies` times under new run numbers.
fn thesis_with_runs_copied(copies: usize) -> capstan_data::Dataset {
    let mut lines = capstan_data::THESIS_CSV.lines();
    let mut text = format!("{}\n", lines.next().unwrap());
    let rows: Vec<&str> = lines.collect();
    for k in 0..copies {
        for line in &rows {
            let f: Vec<&str> = line.split(',').collect();
            let run: usize = f[3].parse().unwrap();
            let run = run + 6 * k;
            text += &format!("{},{},{},{run},{}\n", f[0], f[1], f[2], f[4..].join(","));
        }
    }
    capstan_data::read_pairs(text.as_bytes(), "copied.csv").expect("the copied thesis data")
}

/// A data set with more runs per cord than the planner simulates is planned at the cap, and
/// says so (adversarial pass 2, defect 7: a million-row file made one simulated campaign of
/// ~83,000 runs, and the plan ran for minutes without a word).
#[test]
fn a_design_with_many_runs_per_cord_is_planned_at_the_cap_and_says_so() {
    use capstan_plan::candidates::MAX_RUNS_PER_CORD;
    let many = capstan_plan::open(&thesis_with_runs_copied(5));
    let said = many.assumed.join("\n");
    assert!(
        said.contains(&format!(
            "the data's 30 runs per cord are planned as {MAX_RUNS_PER_CORD}"
        )),
        "{said}"
    );
    // At the thesis's own 6 runs per cord nothing is capped.
    let thesis = capstan_plan::open(&thesis_with_runs_copied(1));
    assert!(
        !thesis.assumed.iter().any(|a| a.contains("planned as")),
        "{:?}",
        thesis.assumed
    );
}
