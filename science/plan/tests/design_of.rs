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

/// Data that are not a full crossing of their wraps and diameters are planned as the crossing,
/// and say so; no "as before" where the planned design is not the data's (adversarial read
/// s35, D3).
#[test]
fn an_unbalanced_design_is_planned_as_the_crossing_and_says_so() {
    let mut lines = capstan_data::THESIS_CSV.lines();
    let mut text = format!("{}\n", lines.next().unwrap());
    for line in lines {
        let f: Vec<&str> = line.split(',').collect();
        let keep = (f[0] == "25.4" && ["270", "360", "450"].contains(&f[1]))
            || (f[0] == "12.7" && ["630", "720"].contains(&f[1]));
        if keep {
            text += &format!("{line}\n");
        }
    }
    let data = capstan_data::read_pairs(text.as_bytes(), "unbalanced.csv").unwrap();
    let open = capstan_plan::open(&data);
    let said = open.assumed.join("\n");
    assert!(
        said.contains("the data hold 5 cords, not every combination")
            && said.contains("(30 in all, the data's 30)"),
        "{said}"
    );
    let d = capstan_engine::diagnose::diagnose(&data);
    let mut assumed = Vec::new();
    let current = capstan_plan::candidates::Design::of(&d, &mut assumed);
    assert!(!current.is_the_datas(&d));
    let c = capstan_plan::candidates::candidates(&current, &[], false);
    assert!(
        !c[0].procedure[0].contains("as before"),
        "{}",
        c[0].procedure[0]
    );
    // The thesis data are their own design.
    let thesis = capstan_engine::diagnose::diagnose(&capstan_data::thesis_dataset());
    let current = capstan_plan::candidates::Design::of(&thesis, &mut assumed);
    assert!(current.is_the_datas(&thesis));
}
