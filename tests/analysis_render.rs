//! The report renders in headless Chromium with every figure drawn (`scripts/check-report`),
//! and the check fails on a report whose figure shows only its axes, or empty data layers.
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

/// `scripts/check-report` on `report`: (passed, its output).
fn check_report(report: &Path) -> (bool, String) {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/check-report");
    let out = Proc::new("bash").arg(&script).arg(report).output().unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    (out.status.success(), text)
}

/// `html` with every data layer (`<g class="mark…">…</g>`) of figure `id` passed through
/// `keep`, which gets the layer's opening tag and returns what stays (plotters' documents
/// inside a layer have no `<g>` of their own).
fn edit_layers(html: &str, id: &str, keep: impl Fn(&str) -> String) -> String {
    let start = html.find(&format!("data-figure=\"{id}\"")).unwrap();
    let end = start + html[start..].find("</figure>").unwrap();
    let mut fig = String::new();
    let mut rest = &html[start..end];
    while let Some(i) = rest.find("<g class=\"mark") {
        let open = i + rest[i..].find('>').unwrap() + 1;
        let close = open + rest[open..].find("</g>").unwrap();
        fig.push_str(&rest[..i]);
        fig.push_str(&keep(&rest[i..open]));
        rest = &rest[close + "</g>".len()..];
    }
    fig.push_str(rest);
    format!("{}{}{}", &html[..start], fig, &html[end..])
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
    let (ok, text) = check_report(&dir.join("report.html"));
    assert!(ok, "check-report failed:\n{text}");
    assert!(
        text.contains("all") && text.contains("figures rendered"),
        "{text}"
    );

    // A figure with only its axes (no data layers), and one whose data layers are empty, fail.
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    for (id, keep_open_tag) in [("residuals", false), ("gain", true)] {
        let broken = edit_layers(&html, id, |open| {
            if keep_open_tag {
                format!("{open}</g>")
            } else {
                String::new()
            }
        });
        assert_ne!(broken, html, "{id}: nothing removed");
        let path = dir.join(format!("broken-{id}.html"));
        std::fs::write(&path, broken).unwrap();
        let (ok, text) = check_report(&path);
        assert!(
            !ok,
            "check-report passed a figure without data ({id}):\n{text}"
        );
        assert!(
            text.contains(&format!("figure {id} is not drawn")),
            "{id}: {text}"
        );
        // The other figures still pass.
        assert_eq!(text.matches("is not drawn").count(), 1, "{text}");
    }
}
