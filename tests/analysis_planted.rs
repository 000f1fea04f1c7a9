//! `capstan analyze` on data where the truth was planted (simulated end to end, firmware in the
//! loop, the thesis rig's noise): the causes it names, and its report's sentences against its
//! `metrics.json`.
//!
//! `cargo test` runs a fixed slice of the validation (every 4th of its 40 data sets);
//! `capstan analyze --validate` runs all 40 and asserts the targets (`.ci/run` does this).

use capstan::cli::{analyze, run, Cli, Command};
use capstan_data::write_pairs;
use capstan_validation::cases::{draw_case, Class};
use capstan_validation::validate;

mod analysis_support;

/// The seed `capstan analyze --validate` uses by default.
const SEED: u64 = 31_415_926;

#[test]
fn the_causes_named_are_the_causes_planted() {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let v = validate::validate(SEED, 4, threads).unwrap();
    for o in &v.outcomes {
        println!(
            "{} {} -> named {:?}, unexplained {}",
            if o.correct { "ok  " } else { "MISS" },
            o.case,
            o.named,
            o.unexplained
        );
    }
    let right = v.outcomes.iter().filter(|o| o.correct).count();
    assert!(
        right as f64 >= 0.8 * v.outcomes.len() as f64,
        "{right}/{} right (slice)",
        v.outcomes.len()
    );
    assert_eq!(v.clean_alarms.0, 0, "a cause named on a clean set");
}

/// The report of a planted data set: every verdict sentence is its verdict's.
#[test]
fn the_report_on_planted_data_says_what_its_verdicts_say() {
    // A pressure-dependent friction planted (single case 0), and the thesis's two mechanisms
    // (pair case 0): the report's sentences are made from their verdicts.
    for case in [
        draw_case(SEED, Class::Single, 0),
        draw_case(SEED, Class::Pair, 0),
    ] {
        let (data, _) = case.generate().unwrap();
        let dir = std::env::temp_dir().join(format!(
            "capstan-planted-{}-{}",
            std::process::id(),
            case.seed
        ));
        std::fs::create_dir_all(&dir).unwrap();
        let csv = dir.join("pairs.csv");
        write_pairs(&csv, &data.pairs).unwrap();
        run(Cli {
            command: Command::Analyze(analyze::Args {
                input: capstan::cli::input::DataArgs { data: Some(csv) },
                out: dir.clone(),
                json: false,
                timing: capstan::cli::input::TimingArgs {
                    protocol_times: false,
                },
                threads: Some(2),
                validate: false,
                seed: 0,
                figures: None,
                width_mm: 170.0,
                font_pt: 8.0,
                figure_numbers: false,
                thesis_comparison: false,
                plan: false,
            }),
        })
        .unwrap();
        let metrics: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("metrics.json")).unwrap())
                .unwrap();
        let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
        analysis_support::check(&metrics, &html);
    }
}
