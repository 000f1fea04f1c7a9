//! The report renders in headless Chromium with every figure drawn (`scripts/check-report`),
//! and the check fails on a report whose figure shows only its axes, or empty data layers. The
//! figure files for a journal column (85 mm, 8 pt) and a page (170 mm, 9 pt) keep every text
//! inside its canvas and off other text as Chromium lays it out, with this machine's fonts and
//! with DejaVu alone; a file with a text moved onto another, or out of the canvas, fails.
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

/// False (and why) when Chromium is missing; a failure with CI=true.
fn have_chromium() -> bool {
    if chromium().is_some() {
        return true;
    }
    if std::env::var("CI").is_ok_and(|v| v == "true") {
        panic!("CI=true but chromium is missing (apt-get install -y chromium)");
    }
    eprintln!("SKIPPED: chromium not installed (apt-get install -y chromium); the report was not rendered");
    false
}

/// `capstan analyze` on the thesis data into `dir`, with figure files when `figures` is given.
fn analyze_thesis(dir: &Path, figures: Option<&str>, width_mm: f64, font_pt: f64) {
    run(Cli {
        command: Command::Analyze(analyze::Args {
            input: capstan::cli::input::DataArgs { data: None },
            out: dir.to_path_buf(),
            json: false,
            timing: capstan::cli::input::TimingArgs {
                protocol_times: false,
            },
            threads: None,
            validate: false,
            seed: 0,
            figures: figures.map(String::from),
            width_mm,
            font_pt,
            figure_numbers: false,
            thesis_comparison: false,
            plan: false,
        }),
    })
    .unwrap();
}

#[test]
fn figure_files_keep_their_text_apart_in_headless_chromium() {
    if !have_chromium() {
        return;
    }
    let fonts = if Path::new("/usr/share/fonts/truetype/dejavu").is_dir() {
        2
    } else {
        1
    };
    for (mm, pt) in [(85.0, 8.0), (170.0, 9.0)] {
        let dir = std::env::temp_dir().join(format!("capstan-files-{mm}-{}", std::process::id()));
        analyze_thesis(&dir, Some("svg"), mm, pt);
        let (ok, text) = check_report(&dir.join("report.html"));
        assert!(ok, "check-report failed at {mm} mm:\n{text}");
        assert_eq!(
            text.matches("6 figure files").count(),
            fonts,
            "the files checked with every set of fonts:\n{text}"
        );
        assert_eq!(
            text.matches("texts inside their canvas, none on another")
                .count(),
            2 * fonts
        );
        if mm == 85.0 {
            // One text twice (on itself), another moved out of the canvas: both are caught.
            let path = dir.join("figures/figure-1-gain.svg");
            let svg = std::fs::read_to_string(&path).unwrap();
            let first = svg.find("<text ").unwrap();
            let end = first + svg[first..].find("</text>").unwrap() + "</text>".len();
            let twice = format!("{}{}{}", &svg[..end], &svg[first..end], &svg[end..]);
            let last = twice.rfind("<text x=\"").unwrap() + "<text x=\"".len();
            let outside = format!("{}-400{}", &twice[..last], &twice[last..]);
            std::fs::write(&path, outside).unwrap();
            let (ok, text) = check_report(&dir.join("report.html"));
            assert!(!ok, "{text}");
            assert!(
                text.contains("TEXTBOX figure-1-gain.svg") && text.contains(" on "),
                "{text}"
            );
            assert!(text.contains("outside the canvas"), "{text}");
        }
    }
}

#[test]
fn report_renders_in_headless_chromium() {
    if !have_chromium() {
        return;
    }
    let dir = std::env::temp_dir().join(format!("capstan-render-{}", std::process::id()));
    analyze_thesis(&dir, None, 170.0, 8.0);
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
