//! The report as a researcher publishes from it: every figure file opens (SVG parses, PNG
//! decodes, PDF has its page) at its physical size without a burned-in "Figure N", the tables
//! are written as CSV and LaTeX, every number of the headline is the value `metrics.json` holds,
//! the provenance names the input by its SHA-256, and the thesis's Table 3 is compared only on
//! the thesis data.

use capstan::cli::{analyze, run, Cli, Command};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

fn analyze_into(dir: &Path, data: Option<PathBuf>, figures: Option<&str>, width_mm: f64) {
    run(Cli {
        command: Command::Analyze(analyze::Args {
            input: capstan::cli::input::DataArgs { data },
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
            font_pt: 8.0,
            figure_numbers: false,
            thesis_comparison: false,
            plan: false,
        }),
    })
    .unwrap();
}

/// The thesis data analysed once, with every figure format at one journal column.
fn thesis_out() -> &'static PathBuf {
    static OUT: OnceLock<PathBuf> = OnceLock::new();
    OUT.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("capstan-publish-{}", std::process::id()));
        analyze_into(&dir, None, Some("svg,png,pdf"), 85.0);
        dir
    })
}

fn metrics(dir: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("metrics.json")).unwrap()).unwrap()
}

#[test]
fn every_figure_file_opens_and_is_numbered_as_in_the_report() {
    let dir = thesis_out();
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    let ids: Vec<&str> = html
        .split("data-figure=\"")
        .skip(1)
        .map(|s| s.split('"').next().unwrap())
        .collect();
    assert!(ids.len() >= 5, "{ids:?}");
    for (k, id) in ids.iter().enumerate() {
        let n = k + 1;
        assert!(
            html.contains(&format!("<b>Figure {n}.</b>")),
            "figure {n} caption"
        );
        let stem = dir.join("figures").join(format!("figure-{n}-{id}"));
        let svg = std::fs::read_to_string(stem.with_extension("svg")).unwrap();
        capstan_report::export::svg_parses(&svg).unwrap();
        // Legend inside the file, sized for a journal column; no number unless asked for
        // (--figure-numbers): the journal's caption numbers it.
        assert!(
            svg.contains("class=\"legend\"") && svg.contains("width=\"85mm\""),
            "{id}"
        );
        assert!(!svg.contains(">Figure "), "{id}");
        let png = std::fs::read(stem.with_extension("png")).unwrap();
        let (w, h) = capstan_report::export::png_decodes(&png).unwrap();
        // 85 mm at 300 dpi, and the file says so (11811 px/m).
        assert_eq!(w, 1004, "{id}");
        assert!(h > 100, "{id}: {h}");
        let info = capstan_report::check::png_info(&png).unwrap();
        assert_eq!(info.per_metre, Some((11811, 11811)), "{id}");
        let pdf = std::fs::read(stem.with_extension("pdf")).unwrap();
        let (pages, framed) = capstan_report::export::pdf_pages(&pdf);
        assert_eq!((pages, framed), (1, true), "{id}");
        // The page is 85 mm (240.9 pt) wide.
        let (pw, _) = capstan_report::check::pdf_page_pt(&pdf).unwrap();
        assert!((pw - 240.945).abs() < 0.01, "{id}: {pw} pt");
    }
}

/// The numbers in a sentence (digits, a decimal point, a leading minus), except inside a word
/// such as "T2".
fn numbers_in(s: &str) -> Vec<String> {
    let c: Vec<char> = s.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < c.len() {
        let starts = c[i].is_ascii_digit() && (i == 0 || !c[i - 1].is_alphanumeric());
        if !starts {
            i += 1;
            continue;
        }
        let mut j = i;
        while j < c.len()
            && (c[j].is_ascii_digit()
                || (c[j] == '.' && j + 1 < c.len() && c[j + 1].is_ascii_digit()))
        {
            j += 1;
        }
        let neg = i > 0 && c[i - 1] == '-';
        let text: String = c[i..j].iter().collect();
        out.push(if neg { format!("-{text}") } else { text });
        i = j;
    }
    out
}

#[test]
fn the_tables_are_written_as_csv_and_latex() {
    let dir = thesis_out();
    let m = metrics(dir);
    let csv = std::fs::read_to_string(dir.join("tables/parameters.csv")).unwrap();
    let rows = m["parameters"].as_array().unwrap();
    assert_eq!(csv.lines().count(), rows.len() + 1);
    // The same rows as metrics.json, in order, with the same values.
    for (line, r) in csv.lines().skip(1).zip(rows) {
        let key = r["key"].as_str().unwrap();
        assert!(line.starts_with(&format!("{key},")), "{line}");
        assert!(
            line.contains(&format!(",{},", r["value"].as_f64().unwrap())),
            "{line}"
        );
    }
    for f in [
        "tables/parameters.tex",
        "tables/models.tex",
        "tables/models.csv",
    ] {
        let text = std::fs::read_to_string(dir.join(f)).unwrap();
        assert!(text.is_ascii() || f.ends_with(".csv"), "{f}");
        assert!(
            text.contains(&capstan_data::provenance::thesis_sha256()) || f.ends_with(".csv"),
            "{f}"
        );
    }
}

#[test]
fn every_number_in_the_headline_is_its_value_in_metrics_json() {
    let m = metrics(thesis_out());
    let h = &m["headline"];
    let sentences: Vec<&str> = h["sentences"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap())
        .collect();
    assert!((3..=5).contains(&sentences.len()), "{sentences:?}");
    let quoted = h["numbers"].as_array().unwrap();
    let mut texts = Vec::new();
    for n in quoted {
        let text = n["text"].as_str().unwrap();
        let d = n["decimals"].as_u64().unwrap() as usize;
        let v = m
            .pointer(n["pointer"].as_str().unwrap())
            .and_then(Value::as_f64);
        let v = v.unwrap_or_else(|| panic!("{} is not a number in metrics.json", n["pointer"]));
        assert_eq!(format!("{v:.d$}"), text, "{}", n["pointer"]);
        texts.push(text.to_string());
    }
    // "95 %" (the interval's level) and the "1" of "includes 1" are wording, not results.
    for s in &sentences {
        for num in numbers_in(s) {
            assert!(
                texts.contains(&num) || num == "95" || num == "1",
                "{num} in {s:?} is not one of the quoted metrics {texts:?}"
            );
        }
        assert!(
            !s.contains("LOCO") && !s.contains("BIC") && !s.contains("edf") && !s.contains("SE "),
            "{s}"
        );
    }
    // No number quoted twice differently; every quoted number appears.
    let all = sentences.join(" ");
    for t in &texts {
        assert!(all.contains(t.as_str()), "{t}");
    }
}

#[test]
fn provenance_names_the_input_and_the_thesis_is_recognised_by_content() {
    let m = metrics(thesis_out());
    let p = &m["provenance"];
    assert_eq!(m["schema_version"], 2);
    assert_eq!(
        p["input_sha256"].as_str().unwrap(),
        capstan_data::provenance::thesis_sha256()
    );
    assert!(p["program"].as_str().unwrap().starts_with("capstan "));
    assert!(!p["commit"].as_str().unwrap().is_empty());
    assert_eq!(m["thesis_comparison"]["shown"], true);
    assert!(m["models"]
        .as_array()
        .unwrap()
        .iter()
        .any(|x| x["name"] == "thesis"));
    let html = std::fs::read_to_string(thesis_out().join("report.html")).unwrap();
    assert!(html.contains(p["input_sha256"].as_str().unwrap()));
    assert!(html.contains("thesis's R² of amplification"));
}

#[test]
fn other_data_get_no_thesis_comparison() {
    // The thesis data without their last row: other bytes, so not the thesis data set.
    let text = capstan_data::THESIS_CSV.trim_end();
    let cut = &text[..text.rfind('\n').unwrap()];
    let dir = std::env::temp_dir().join(format!("capstan-publish-other-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("mine.csv");
    std::fs::write(&csv, format!("{cut}\n")).unwrap();
    let out = dir.join("out");
    analyze_into(&out, Some(csv.clone()), None, 170.0);
    let m = metrics(&out);
    assert_eq!(m["thesis_comparison"]["shown"], false);
    assert!(!m["models"]
        .as_array()
        .unwrap()
        .iter()
        .any(|x| x["name"] == "thesis"));
    assert_eq!(m["thesis_per_angle_r2"].as_array().unwrap().len(), 0);
    assert_eq!(
        m["provenance"]["input_sha256"].as_str().unwrap(),
        capstan_data::provenance::sha256_file(&csv).unwrap()
    );
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(!html.contains("Table 3 applied per angle") && !html.contains("thesis Table 3"));
    assert!(!out.join("figures").exists(), "no --figures, no files");
}

#[test]
fn the_next_experiment_section_is_rendered_from_its_metrics_object() {
    let dir = thesis_out();
    let m = metrics(dir);
    let next = &m["next_experiment"];
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    // The object and the section come from one typed value: the planner's open hypotheses
    // of these data (no --plan), as the command builds it.
    let typed = capstan_report::next::next_experiment(
        &capstan_plan::open(&capstan_data::thesis_dataset()),
        None,
        "capstan plan",
    );
    assert_eq!(next, &serde_json::to_value(&typed).unwrap());
    let section = capstan_report::html::typeset(&capstan_report::next::next_html(&typed));
    assert!(
        html.contains(&section),
        "the section is not the metrics' object rendered"
    );
    // Without --plan: what is open (the thesis data name a T2 offset and heating at one drive
    // voltage, so a speed effect is open too) and the command that plans it.
    assert_eq!(next["planned"], false);
    assert_eq!(next["command"], "capstan plan");
    let open: Vec<&str> = (next["open"].as_array().unwrap().iter())
        .map(|h| h["label"].as_str().unwrap())
        .collect();
    assert!(
        open.contains(&"t2_offset+contact_heating")
            && open.iter().any(|l| l.contains("speed_dependence")),
        "{open:?}"
    );
    assert!(section.contains("<code>capstan plan</code>"));
}

/// Every figure file says where it came from (program, commit, input's SHA-256, command
/// line), as metrics.json does: SVG in a metadata element, PNG in an iTXt chunk, PDF in the
/// document information dictionary its newest trailer names; each still opens.
#[test]
fn figure_files_carry_the_provenance() {
    let dir = thesis_out().join("figures");
    let commit = capstan::provenance::COMMIT;
    let sha = capstan_data::provenance::thesis_sha256();
    let (mut svgs, mut pngs, mut pdfs) = (0, 0, 0);
    for e in std::fs::read_dir(&dir).unwrap().flatten() {
        let name = e.file_name().to_string_lossy().to_string();
        let bytes = std::fs::read(e.path()).unwrap();
        if name.ends_with(".svg") {
            let text = String::from_utf8(bytes).unwrap();
            assert!(
                text.contains("<metadata id=\"capstan-provenance\">capstan ")
                    && text.contains(commit),
                "{name}"
            );
            capstan_report::export::svg_parses(&text).unwrap();
            svgs += 1;
        } else if name.ends_with(".png") {
            let text = String::from_utf8_lossy(&bytes).to_string();
            assert!(
                text.contains("iTXtComment") && text.contains(commit),
                "{name}"
            );
            capstan_report::export::png_decodes(&bytes).unwrap();
            pngs += 1;
        } else if name.ends_with(".pdf") {
            let info = capstan_report::stamp::pdf::document_info(&bytes)
                .unwrap_or_else(|| panic!("{name}: no document information dictionary"));
            assert!(
                info.contains(&format!("commit {commit}"))
                    && info.contains(&format!("input SHA-256 {sha}"))
                    && info.contains("command: "),
                "{name}: {info}"
            );
            let (pages, framed) = capstan_report::export::pdf_pages(&bytes);
            assert!(pages == 1 && framed, "{name}");
            capstan_report::check::pdf_page_pt(&bytes).unwrap();
            pdfs += 1;
        }
    }
    assert!(
        svgs > 0 && svgs == pngs && svgs == pdfs,
        "{svgs} SVG, {pngs} PNG, {pdfs} PDF"
    );
}
