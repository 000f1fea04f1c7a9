//! The tables as files for a paper, from the thesis analysis: `parameters.csv` holds every row
//! of the report's parameter table at full precision (value, SE, 95 % interval, unit, how the
//! interval is computed), every variance component with an interval that holds its value;
//! `parameters.tex` and `models.tex` are booktabs tabulars that compile (with pdflatex when it
//! is installed; a structural check of the LaTeX always).

use capstan_engine::analysis::Analysis;
use capstan_report::table_files::{models_csv, models_tex, parameters_csv, parameters_tex};
use std::process::Command;
use std::sync::OnceLock;

fn thesis() -> &'static Analysis {
    static A: OnceLock<Analysis> = OnceLock::new();
    A.get_or_init(|| {
        capstan_engine::analysis::run(&capstan_data::thesis_dataset(), Default::default()).unwrap()
    })
}

/// A CSV's rows as cells (quoted cells with commas and doubled quotes).
fn cells(text: &str) -> Vec<Vec<String>> {
    let mut rows = Vec::new();
    for line in text.lines() {
        let (mut row, mut cell, mut quoted) = (Vec::new(), String::new(), false);
        let mut chars = line.chars().peekable();
        while let Some(c) = chars.next() {
            match c {
                '"' if quoted && chars.peek() == Some(&'"') => {
                    cell.push('"');
                    chars.next();
                }
                '"' => quoted = !quoted,
                ',' if !quoted => row.push(std::mem::take(&mut cell)),
                c => cell.push(c),
            }
        }
        row.push(cell);
        rows.push(row);
    }
    rows
}

#[test]
fn parameters_csv_holds_every_row_with_its_interval() {
    let a = thesis();
    let rows = capstan_report::parameters::rows(a);
    let csv = cells(&parameters_csv(&rows));
    assert_eq!(
        csv[0][..5],
        ["key", "quantity", "estimate_of", "value", "se"]
    );
    assert_eq!(csv.len(), rows.len() + 1);
    let num = |s: &str| s.parse::<f64>().ok();
    for (r, c) in rows.iter().zip(&csv[1..]) {
        assert_eq!(c.len(), 9, "{c:?}");
        assert_eq!(c[0], r.key);
        assert_eq!(num(&c[3]), Some(r.value), "{}", r.key);
        let (lo, hi) = (num(&c[5]), num(&c[6]));
        if let (Some(lo), Some(hi)) = (lo, hi) {
            assert!(
                lo <= r.value && r.value <= hi,
                "{}: {lo} {} {hi}",
                r.key,
                r.value
            );
        }
        assert!(!c[8].is_empty(), "{}: no method", r.key);
    }
    // Every variance component has its interval and says how it was computed.
    let components: Vec<&Vec<String>> = csv[1..]
        .iter()
        .filter(|c| c[2] == "variance component")
        .collect();
    assert_eq!(components.len(), 6);
    for c in components {
        assert!(num(&c[5]).is_some() && num(&c[6]).is_some(), "{c:?}");
        assert!(c[8].contains("interval"), "{c:?}");
    }
    // The run-to-run SD on runs − cords = 50 degrees of freedom: its interval is the
    // textbook one, s·√(50/χ²₀.₉₇₅(50)) to s·√(50/χ²₀.₀₂₅(50)) (χ² quantiles 71.42, 32.36).
    let run = rows
        .iter()
        .find(|r| r.key == "scatter.run_ln_mu_sd")
        .unwrap();
    let s = run.value;
    assert!((run.ci95_lo.unwrap() - s * (50.0f64 / 71.420).sqrt()).abs() < 1e-4 * s);
    assert!((run.ci95_hi.unwrap() - s * (50.0f64 / 32.357).sqrt()).abs() < 1e-4 * s);
}

/// A structural check of a LaTeX tabular: ASCII, balanced braces and environments, and every
/// row of the tabular with its columns' number of cells.
fn check_tex(tex: &str, columns: usize) {
    assert!(tex.is_ascii(), "not ASCII");
    let body: String = tex
        .lines()
        .filter(|l| !l.starts_with('%'))
        .collect::<Vec<_>>()
        .join("\n");
    let unescaped = |c: char| {
        let mut n = 0i64;
        let mut prev = ' ';
        for ch in body.chars() {
            if ch == c && prev != '\\' {
                n += 1;
            }
            prev = if prev == '\\' && ch == '\\' { ' ' } else { ch };
        }
        n
    };
    assert_eq!(unescaped('{'), unescaped('}'), "braces");
    assert_eq!(unescaped('$') % 2, 0, "math shifts");
    assert_eq!(unescaped('%'), 0, "an unescaped % in the body");
    assert_eq!(
        body.matches("\\begin{").count(),
        body.matches("\\end{").count()
    );
    let start = body.find("\\midrule").unwrap();
    let end = body.find("\\bottomrule").unwrap();
    for row in body[start + 8..end]
        .lines()
        .filter(|l| !l.trim().is_empty())
    {
        let amps = row.matches('&').count() - row.matches("\\&").count();
        assert_eq!(amps, columns - 1, "{row}");
        assert!(row.trim_end().ends_with("\\\\"), "{row}");
    }
}

/// pdflatex on the tables in a small document: None when pdflatex is not installed.
fn pdflatex(tables: &[(&str, String)]) -> Option<(bool, String)> {
    let ok = Command::new("pdflatex")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok {
        return None;
    }
    let dir = std::env::temp_dir().join(format!("capstan-tables-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut doc = String::from("\\documentclass{article}\n\\usepackage[margin=1.5cm]{geometry}\n\\usepackage{booktabs}\n\\begin{document}\n");
    for (name, text) in tables {
        std::fs::write(dir.join(format!("{name}.tex")), text).unwrap();
        doc.push_str(&format!("\\noindent\\input{{{name}}}\n\\clearpage\n"));
    }
    doc.push_str("\\end{document}\n");
    std::fs::write(dir.join("doc.tex"), doc).unwrap();
    let out = Command::new("pdflatex")
        .args(["-interaction=nonstopmode", "-halt-on-error", "doc.tex"])
        .current_dir(&dir)
        .output()
        .unwrap();
    let log = String::from_utf8_lossy(&out.stdout).to_string();
    Some((out.status.success() && dir.join("doc.pdf").exists(), log))
}

#[test]
fn the_latex_tables_are_well_formed_and_compile() {
    let a = thesis();
    let rows = capstan_report::parameters::rows(a);
    let params = parameters_tex(&rows, "a test");
    let models = models_tex(a, "a test");
    check_tex(&params, 5);
    check_tex(&models, 6);
    assert!(params.contains("\\toprule") && params.contains("$\\pm$ SE"));
    assert_eq!(
        params.matches("\\\\\n").count(),
        rows.len() + 1,
        "a row per quantity and the header"
    );
    // The extended model's mu with its SE's precision, and the note that says how.
    assert!(params.contains("extended model & $0.145"), "{params}");
    assert!(params.contains("\\textsuperscript{a}~value $\\pm$ t(9)"));
    let csv = models_csv(a);
    assert_eq!(csv.lines().count(), a.models.len() + 1);
    assert!(csv.contains("thesis Table 3,thesis,") && models.contains("not refittable"));
    match pdflatex(&[("parameters", params), ("models", models)]) {
        Some((ok, log)) => assert!(ok, "pdflatex failed:\n{log}"),
        None => eprintln!("pdflatex not installed: the tables were checked for structure only"),
    }
}
