//! `capstan analyze` on bad input: an error naming file, line and column, never a panic.

use capstan::cli::{analyze, run, Cli, Command};

fn analyze_csv(name: &str, body: &str) -> String {
    let dir = std::env::temp_dir().join(format!("capstan-bad-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, body).unwrap();
    let r = run(Cli {
        command: Command::Analyze(analyze::Args {
            input: capstan::cli::input::DataArgs { data: Some(path) },
            out: dir.join("out"),
            json: false,
            timing: capstan::cli::input::TimingArgs {
                protocol_times: false,
            },
            threads: Some(1),
            validate: false,
            seed: 0,
            figures: None,
            width_mm: 170.0,
            font_pt: 8.0,
            figure_numbers: false,
            thesis_comparison: false,
            plan: false,
        }),
    });
    let e = format!("{:#}", r.expect_err("bad input must fail"));
    // Refused data leave no output directory behind (it was made, holding only a lock file).
    assert!(!dir.join("out").exists(), "{e}");
    e
}

#[test]
fn bad_cells_and_columns_are_located() {
    let h = "capstan_diameter_mm,wrap_deg,drive_v,run,step,t1_n,t2_n\n";
    let e = analyze_csv("missing.csv", "wrap_deg,t1_n\n270,1\n");
    assert!(e.contains("missing.csv:1:") && e.contains("t2_n"), "{e}");
    let e = analyze_csv(
        "text.csv",
        &format!("{h}12.7,270,10,1,1,1.0,2.0\n12.7,270,10,1,2,abc,2.0\n"),
    );
    assert!(e.contains("text.csv:3:6") && e.contains("t1_n"), "{e}");
    let e = analyze_csv("zero.csv", &format!("{h}0,270,10,1,1,1,2.0\n"));
    assert!(
        e.contains("zero.csv:2:1") && e.contains("greater than 0"),
        "{e}"
    );
    let e = analyze_csv("huge.csv", &format!("{h}12.7,270,10,1,1,2e300,2.0\n"));
    assert!(e.contains("huge.csv:2:6") && e.contains("10000 N"), "{e}");
    let e = analyze_csv("nan.csv", &format!("{h}12.7,270,10,1,1,1.0,NaN\n"));
    assert!(e.contains("nan.csv:2:7") && e.contains("finite"), "{e}");
    let e = analyze_csv("nofile.csv", "");
    assert!(e.contains("nofile.csv"), "{e}");
}

#[test]
fn too_little_data_is_an_error_not_a_panic() {
    let e = analyze_csv("tiny.csv", "wrap_deg,t1_n,t2_n\n270,1,2\n270,2,4\n");
    assert!(e.contains("too few"), "{e}");
}
