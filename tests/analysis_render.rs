//! The report renders in headless Chromium with every figure drawn (`scripts/check-report`).
//! Runs when Chromium is installed; with CI=true a missing Chromium fails; otherwise skips.

use capstan::cli::{analyze, run, Cli, Command};
use std::path::Path;
use std::process::Command as Proc;

fn chromium() -> Option<String> {
    for b in ["chromium", "chromium-browser", "google-chrome"] {
        if Proc::new("sh")
            .arg("-c")
            .arg(format!("command -v {b}"))
            .output()
            .is_ok_and(|o| o.status.success())
        {
            return Some(b.to_string());
        }
    }
    None
}

#[test]
fn report_renders_in_headless_chromium() {
    if chromium().is_none() {
        if std::env::var("CI").is_ok_and(|v| v == "true") {
            panic!("CI=true but chromium is missing (apt-get install -y chromium)");
        }
        eprintln!("SKIPPED: chromium not installed (apt-get install -y chromium); the report was not rendered");
        return;
    }
    let dir = std::env::temp_dir().join(format!("capstan-render-{}", std::process::id()));
    run(Cli {
        command: Command::Analyze(analyze::Args {
            data: None,
            out: dir.clone(),
            json: false,
            threads: None,
        }),
    })
    .unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/check-report");
    let out = Proc::new("bash")
        .arg(&script)
        .arg(dir.join("report.html"))
        .output()
        .unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "check-report failed:\n{text}");
    assert!(
        text.contains("all") && text.contains("figures rendered"),
        "{text}"
    );
}
