//! The tables as files for a paper, from the thesis analysis: `parameters.csv` holds every row
//! of the report's parameter table at full precision (value, SE, 95 % interval, unit, how the
//! interval is computed), every variance component with an interval that holds its value;
//! `parameters.tex` and `models.tex` are booktabs tabulars that compile (with pdflatex when it
//! is installed; a structural check of the LaTeX always).

use capstan_engine::analysis::Analysis;
use capstan_report::table_files::{
    cord_parameters_tex, models_csv, models_tex, parameters_csv, parameters_tex,
};
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

/// The cells of a LaTeX row, split at the `&`s outside braces (`\&` is text).
fn split_cells(row: &str) -> Vec<String> {
    let row = row.trim().trim_end_matches("\\\\").trim_end();
    let (mut cells, mut cell, mut depth, mut prev) = (Vec::new(), String::new(), 0i32, ' ');
    for c in row.chars() {
        match c {
            '{' if prev != '\\' => depth += 1,
            '}' if prev != '\\' => depth -= 1,
            '&' if depth == 0 && prev != '\\' => {
                cells.push(std::mem::take(&mut cell).trim().to_string());
                prev = c;
                continue;
            }
            _ => {}
        }
        cell.push(c);
        prev = if prev == '\\' && c == '\\' { ' ' } else { c };
    }
    cells.push(cell.trim().to_string());
    cells
}

/// The two arguments of `\Capstan{name}{a}{b}` when `cell` is one.
fn capstan_args<'a>(cell: &'a str, name: &str) -> Option<(&'a str, &'a str)> {
    let rest = cell.strip_prefix(&format!("\\Capstan{name}{{"))?;
    let mut depth = 1;
    for (i, c) in rest.char_indices() {
        depth += match c {
            '{' => 1,
            '}' => -1,
            _ => 0,
        };
        if depth == 0 {
            let b = rest[i + 1..].strip_prefix('{')?.strip_suffix('}')?;
            return Some((&rest[..i], b));
        }
    }
    None
}

/// A cell as the layout sets it: the lines of each of its columns. Narrow: a pair or an
/// "over" is one column of two lines; wide: a pair is two columns, an "over" one line.
fn laid_out(cell: &str, wide: bool) -> Vec<Vec<String>> {
    if let Some((a, b)) = capstan_args(cell, "Pair") {
        return if wide {
            vec![vec![a.into()], vec![b.into()]]
        } else {
            vec![vec![a.into(), b.into()]]
        };
    }
    if let Some((a, b)) = capstan_args(cell, "Over") {
        return if wide {
            vec![vec![format!("{a} {b}")]]
        } else {
            vec![vec![a.into(), b.into()]]
        };
    }
    vec![vec![cell.to_string()]]
}

/// The table's rows (header and body) as cells.
fn table_rows(tex: &str) -> Vec<Vec<String>> {
    let start = tex.find("\\toprule").unwrap() + 8;
    let end = tex.find("\\bottomrule").unwrap();
    tex[start..end]
        .lines()
        .map(str::trim)
        .filter(|l| {
            !l.is_empty() && !l.starts_with("\\midrule") && !l.starts_with("\\addlinespace")
        })
        .map(split_cells)
        .collect()
}

/// A structural check of a LaTeX table file: ASCII, balanced braces and environments, and
/// every row of the table with at most its columns' number of cells in both layouts (a
/// group's title is a row of one cell), the body's rows with all of them.
fn check_tex(tex: &str, narrow: usize, wide: usize) {
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
    // The layout's comments after `\ifdim` and `\else` are the only unescaped %.
    assert_eq!(
        unescaped('%') as usize,
        body.matches("%\n").count() + 2,
        "an unescaped % in the body"
    );
    assert_eq!(
        body.matches("\\begin{").count(),
        body.matches("\\end{").count()
    );
    for row in table_rows(&body) {
        let cells = |wide| row.iter().map(|c| laid_out(c, wide).len()).sum::<usize>();
        let group = row.len() == 1 && row[0].starts_with("\\textit");
        assert!(cells(false) == narrow || group, "{row:?}");
        assert!(cells(true) == wide || group, "{row:?}");
    }
}

/// The page of a two-column article whose column is 85 mm (178 mm of text, 8 mm between
/// the columns), and of a one-column one 170 mm wide.
const COLUMN_85_MM: &str = "\\documentclass[twocolumn]{article}\n\\usepackage[a4paper,textwidth=178mm,columnsep=8mm,textheight=250mm]{geometry}\n";
const FULL_170_MM: &str =
    "\\documentclass{article}\n\\usepackage[a4paper,textwidth=170mm,textheight=250mm]{geometry}\n";

/// pdflatex on the tables, each in a table float of a small document opening with `page`:
/// whether it compiled and its log; None when pdflatex is not installed.
fn pdflatex(page: &str, tables: &[(&str, String)]) -> Option<(bool, String)> {
    let ok = Command::new("pdflatex")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok {
        return None;
    }
    let dir = std::env::temp_dir().join(format!(
        "capstan-tables-{}-{}",
        std::process::id(),
        page.len()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    let mut doc = format!("{page}\\usepackage{{booktabs,tabularx}}\n\\begin{{document}}\n");
    for (name, text) in tables {
        std::fs::write(dir.join(format!("{name}.tex")), text).unwrap();
        doc.push_str(&format!(
            "\\begin{{table}}[p]\\caption{{{name}}}\\input{{{name}}}\\end{{table}}\n\\clearpage\n"
        ));
    }
    doc.push_str("\\end{document}\n");
    std::fs::write(dir.join("doc.tex"), doc).unwrap();
    let out = Command::new("pdflatex")
        .args(["-interaction=nonstopmode", "-halt-on-error", "doc.tex"])
        .current_dir(&dir)
        .output()
        .unwrap();
    let log = std::fs::read_to_string(dir.join("doc.log")).unwrap_or_default();
    let ok = out.status.success() && dir.join("doc.pdf").exists();
    let _ = std::fs::remove_dir_all(&dir);
    Some((ok, log))
}

#[test]
fn the_latex_tables_are_well_formed_and_compile() {
    let a = thesis();
    let rows = capstan_report::parameters::rows(a);
    let params = parameters_tex(&rows, "a test");
    let cords = cord_parameters_tex(&rows, "a test");
    let models = models_tex(a, "a test");
    check_tex(&params, 3, 4);
    check_tex(&cords, 3, 4);
    check_tex(&models, 5, 6);
    assert!(params.contains("\\toprule") && params.contains("$\\pm$ SE"));
    // Every row once between the two files: the ten cords' own mu in parameters-cords.tex.
    let lines = |t: &str| t.matches("\\\\\n").count() - t.matches("\\textit{").count() - 1;
    let per_cord = rows.iter().filter(|r| r.key.starts_with("cord.")).count();
    assert_eq!(per_cord, 10);
    assert_eq!(lines(&params), rows.len() - per_cord, "{params}");
    assert_eq!(lines(&cords), per_cord, "{cords}");
    let cord = "mu, 720$^\\circ$, D = 25.4 mm";
    assert!(!params.contains(cord) && cords.contains(cord), "{cords}");
    // Each cord named once: its wrap and diameter, not its label beside them again.
    assert!(!cords.contains("D25.4/720deg"), "{cords}");
    // Each source one group, in the rows' order: the extended model, the evidence engine,
    // Euler-Eytelwein's one mu, the variance components, the new-cord error model.
    let groups: Vec<&str> = (params.split("\\textit{").skip(1))
        .filter_map(|g| g.split('}').next())
        .collect();
    assert_eq!(
        groups,
        [
            "extended model",
            "evidence engine",
            "Euler-Eytelwein, one mu",
            "variance component",
            "new-cord error model"
        ]
    );
    // A note that repeats another and adds to it is marked with both letters, the repeat
    // printed once: the extended model's heating row, its interval method (a) and h = k/τ (b).
    assert!(
        params.contains("(T2 $-$ T1))\\textsuperscript{a,b}"),
        "{params}"
    );
    assert_eq!(
        params
            .matches("cord jackknife over the leave-one-cord-out")
            .count(),
        1
    );
    // The extended model's mu with its SE's precision, and the note that says how.
    assert!(
        params.contains("\\textit{extended model} \\\\\nfriction coefficient mu"),
        "{params}"
    );
    assert!(params.contains("\\CapstanPair{$0.1453 \\pm 0.0045$}{$0.1350$ to $0.1555$}"));
    assert!(params.contains("\\textsuperscript{a}~value $\\pm$ t(9)"));
    let csv = models_csv(a);
    assert_eq!(csv.lines().count(), a.models.len() + 1);
    assert!(csv.contains("thesis Table 3,thesis,") && models.contains("not refittable"));
    let tables = [("parameters", params), ("cords", cords), ("models", models)];
    for page in [COLUMN_85_MM, FULL_170_MM] {
        match pdflatex(page, &tables) {
            Some((ok, log)) => {
                assert!(ok, "pdflatex failed:\n{log}");
                // Nothing sticks out of the 85 mm column or the 170 mm page, and each table
                // with its notes fits one column (250 mm of text): a `table` float, not `table*`.
                assert!(!log.contains("Overfull \\hbox"), "{page}\n{log}");
                assert!(!log.contains("Float too large"), "{page}\n{log}");
            }
            None => eprintln!("pdflatex not installed: the tables were checked for structure only"),
        }
    }
}

/// A conservative width of LaTeX text at `\footnotesize` (Computer Modern 8 pt), in pt: a
/// digit or lower-case letter 4.6 (the widest are 4.6-4.7), f, i, j, l, r, t or a bracket 3.3 (2.4-3.3),
/// m or w 7.1, `.` or `,` 2.4, a capital 6.6, a space 2.8 (in math: the room around a ± or ×),
/// a minus, ±, × or % 7.1, a superscript 3; commands that print nothing count 0.
fn width_pt(tex: &str) -> f64 {
    let (mut w, mut math, mut chars) = (0.0, false, tex.chars().peekable());
    while let Some(c) = chars.next() {
        w += match c {
            '$' => {
                math = !math;
                0.0
            }
            '{' | '}' => 0.0,
            ' ' => 2.8,
            '.' | ',' => 2.4,
            'f' | 'i' | 'j' | 'l' | 'r' | 't' | '(' | ')' | '[' | ']' => 3.3,
            'm' | 'w' => 7.1,
            '-' if math => 7.1,
            '\\' => {
                let mut name = String::new();
                while let Some(&n) = chars.peek() {
                    if !n.is_ascii_alphabetic() && !name.is_empty() || name == "," || name == "%" {
                        break;
                    }
                    name.push(n);
                    chars.next();
                    if !n.is_ascii_alphabetic() {
                        break;
                    }
                }
                match name.as_str() {
                    "pm" | "times" | "%" => 7.1,
                    "," => 1.7,
                    "textsuperscript" => {
                        while chars.next().is_some_and(|n| n != '}') {}
                        3.0
                    }
                    _ => 0.0,
                }
            }
            c if c.is_ascii_uppercase() => 6.6,
            _ => 4.6,
        };
    }
    w
}

/// The columns a `tabularx` column specification (or a `\newcolumntype`'s body) lists: a
/// `p{N em}` as Some(N), an `l`, `r` or `c` as None; `>{...}` and `@{...}` skipped.
fn columns(spec: &str) -> Vec<Option<f64>> {
    let (mut out, mut rest) = (Vec::new(), spec);
    let braced = |s: &str| -> (String, usize) {
        let mut depth = 0;
        for (i, c) in s.char_indices() {
            depth += match c {
                '{' => 1,
                '}' => -1,
                _ => 0,
            };
            if depth == 0 {
                return (s[1..i].to_string(), i + 1);
            }
        }
        panic!("unbalanced {s}")
    };
    while let Some(c) = rest.chars().next() {
        rest = &rest[1..];
        match c {
            '>' | '@' => rest = &rest[braced(rest).1..],
            'p' => {
                let (w, n) = braced(rest);
                out.push(Some(w.strip_suffix("em").unwrap().parse().unwrap()));
                rest = &rest[n..];
            }
            'l' | 'r' | 'c' => out.push(None),
            c => panic!("column type {c} in {spec}"),
        }
    }
    out
}

/// The width the fixed columns of a table file take in its narrow (`wide` false) or wide
/// layout, gaps included, after checking that every line of a `p` column fits its width (a
/// value or interval unbroken; a header may wrap between words).
fn fixed_width_pt(tex: &str, wide: bool) -> f64 {
    use capstan_report::tex_layout::TEX_TABCOLSEP_PT;
    const EM_PT: f64 = 8.5; // \footnotesize's em (cmr8's quad)
    let spec = tex
        .lines()
        .filter_map(|l| l.strip_prefix("\\newcolumntype{Q}{"))
        .nth(usize::from(wide))
        .unwrap()
        .trim_end_matches("}%");
    let cols = columns(spec);
    let mut widest = vec![0.0f64; cols.len()];
    for (i, row) in table_rows(tex).iter().enumerate() {
        let laid: Vec<Vec<String>> = row.iter().flat_map(|c| laid_out(c, wide)).collect();
        // The first cell is the wrapping column's; a group's title has no others.
        for (k, lines) in laid.iter().skip(1).enumerate() {
            for line in lines {
                let words = if i == 0 && cols[k].is_some() {
                    line.split(' ').map(String::from).collect()
                } else {
                    vec![line.clone()]
                };
                for word in words {
                    let w = width_pt(&word);
                    if let Some(em) = cols[k] {
                        assert!(w <= em * EM_PT, "{word:?} ({w} pt) in a {em} em column");
                    }
                    widest[k] = widest[k].max(w);
                }
            }
        }
    }
    let fixed: f64 = cols
        .iter()
        .zip(&widest)
        .map(|(c, w)| c.map_or(*w, |em| em * EM_PT))
        .sum();
    fixed + 2.0 * TEX_TABCOLSEP_PT * cols.len() as f64
}

#[test]
fn the_latex_tables_fit_an_85_mm_column_and_the_170_mm_page() {
    use capstan_report::tex_layout::{TEX_MIN_WRAP_PT, TEX_TARGET_WIDTH_PT, TEX_WIDE_FROM_PT};
    let a = thesis();
    let rows = capstan_report::parameters::rows(a);
    for tex in [parameters_tex(&rows, "a test"), models_tex(a, "a test")] {
        // As wide as the line, its first column wrapping; the layout chosen by that width.
        assert!(
            tex.contains(
                "\\begin{tabularx}{\\linewidth}{@{}>{\\raggedright\\arraybackslash}XQ@{}}"
            ),
            "{tex}"
        );
        assert!(tex.contains(&format!("\\ifdim\\linewidth<{TEX_WIDE_FROM_PT}pt")));
        // In an 85 mm column the wrapping column keeps its least width; at the width from
        // which the values stand beside their intervals, too.
        let narrow = fixed_width_pt(&tex, false);
        let wide = fixed_width_pt(&tex, true);
        assert!(
            TEX_TARGET_WIDTH_PT - narrow >= TEX_MIN_WRAP_PT,
            "narrow: {narrow} pt fixed of {TEX_TARGET_WIDTH_PT}\n{tex}"
        );
        assert!(
            TEX_WIDE_FROM_PT - wide >= TEX_MIN_WRAP_PT,
            "wide: {wide} pt fixed of {TEX_WIDE_FROM_PT}\n{tex}"
        );
        eprintln!("fixed columns: {narrow:.1} pt narrow, {wide:.1} pt wide");
    }
}
