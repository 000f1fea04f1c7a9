//! Pairs CSVs the reader must refuse at the right place with a message that leads somewhere,
//! or accept with the right structure.

use super::checked;
use capstan_data::{check_capstan_data, read_pairs, thesis_dataset, Basis, Dataset, THESIS_CSV};

const H: &str = "capstan_diameter_mm,wrap_deg,drive_v,run,step,time_s,t1_n,t2_n";
const ROW: [&str; 8] = ["12.7", "270", "10", "1", "1", "16", "1.5", "3.2"];

fn read(text: &str) -> Result<Dataset, String> {
    read_pairs(text.as_bytes(), "x.csv").map_err(|e| e.to_string())
}

/// `text` is refused with a message starting with `at` and containing every `words`.
fn refused(text: &str, at: &str, words: &[&str]) {
    let e = read(text)
        .and_then(|d| check_capstan_data(&d).map_err(|e| e.to_string()))
        .expect_err(at);
    assert!(e.starts_with(at), "want {at}: {e}");
    for w in words {
        assert!(e.contains(w), "want `{w}`: {e}");
    }
    // Bounded and on one line, whatever the input.
    assert!(e.len() < 700 && !e.contains('\n'), "{e}");
    checked();
}

/// `text` is accepted as `rows` rows in `cords` cords and `runs` runs.
fn accepted(text: &str, rows: usize, cords: usize, runs: usize) -> Dataset {
    let d = read(text).unwrap_or_else(|e| panic!("{e}"));
    check_capstan_data(&d).unwrap();
    let s = &d.structure;
    assert_eq!(
        (d.pairs.len(), s.cords.len(), s.run_cord.len()),
        (rows, cords, runs),
        "{}",
        s.describe()
    );
    checked();
    d
}

fn rows(n: usize, sep: &str) -> String {
    let mut s = format!("{H}{sep}");
    for k in 1..=n {
        let t1 = 1.0 + k as f64;
        s += &format!("12.7,270,10,1,{k},{},{t1},{}{sep}", 6 + 10 * k, 2.0 * t1);
    }
    s
}

#[test]
fn every_column_refuses_what_it_cannot_hold_at_its_line_and_column() {
    let bad: [(&str, &str); 7] = [
        ("", "empty cell"),
        ("abc", "not a number"),
        ("NaN", "not a finite number"),
        ("inf", "not a finite number"),
        ("-inf", "not a finite number"),
        ("1e400", "not a finite number"),
        ("1,5", "write decimals with a point"),
    ];
    for col in 0..8 {
        for (cell, why) in bad {
            let mut r = ROW;
            let quoted = format!("\"{cell}\"");
            r[col] = if cell.contains(',') { &quoted } else { cell };
            let text = format!("{H}\n{}\n{}\n", ROW.join(","), r.join(","));
            refused(&text, &format!("x.csv:3:{}: column `", col + 1), &[why]);
        }
    }
    // Beyond each column's physical range, with the range said.
    let beyond: [(usize, &str, &str); 12] = [
        (0, "0", "greater than 0 and at most 1000 mm"),
        (0, "1001", "at most 1000 mm"),
        (1, "0", "greater than 0 and at most 3600 deg"),
        (1, "-90", "greater than 0"),
        (1, "1e9", "at most 3600 deg"),
        (2, "1000.5", "within ±1000 V"),
        (3, "1e10", "within ±1e9"),
        (4, "-2e9", "within ±1e9"),
        (5, "1e11", "within ±1e10 s"),
        (6, "10000.01", "within ±10000 N"),
        (7, "-1e5", "within ±10000 N"),
        (7, "1e154", "within ±10000 N"),
    ];
    for (col, cell, why) in beyond {
        let mut r = ROW;
        r[col] = cell;
        let text = format!("{H}\n{}\n", r.join(","));
        refused(&text, &format!("x.csv:2:{}: column `", col + 1), &[why]);
    }
}

#[test]
fn positions_are_exact_for_every_line_ending_blank_lines_and_long_lines() {
    for sep in ["\n", "\r\n", "\r"] {
        for bad_at in [2usize, 5, 40] {
            // Rows 2.. are good up to the bad one, with a blank line after the header.
            let good = rows(bad_at - 2, sep);
            let good = good.replacen(sep, &format!("{sep}{sep}"), 1);
            let text = format!("{good}12.7,270,10,1,99,16,x,3{sep}");
            refused(
                &text,
                &format!("x.csv:{}:7:", bad_at + 1),
                &["not a number"],
            );
            // Too few cells, at its line.
            let text = format!("{good}12.7,270{sep}");
            refused(
                &text,
                &format!("x.csv:{}:", bad_at + 1),
                &["2 cells where the header has 8"],
            );
        }
        // A line longer than any pairs CSV line, on line 301.
        let mut text = rows(299, sep);
        text += &"7".repeat(capstan_data::MAX_LINE_BYTES + 1);
        refused(&text, "x.csv:301:1:", &["a line longer than"]);
        // Good files read the same whatever the line ending.
        accepted(&rows(12, sep), 12, 1, 1);
    }
}

#[test]
fn quoting_encodings_and_separators_are_refused_with_what_to_do() {
    let cases: Vec<(String, &str, Vec<&str>)> = vec![
        (String::new(), "x.csv: the file is empty", vec![]),
        ("\n\n\r\n".into(), "x.csv: the file is empty", vec![]),
        (format!("{H}\n"), "x.csv: no data rows", vec![]),
        (
            "wrap_deg,t1_n\n270,1\n".into(),
            "x.csv:1: missing required column `t2_n`",
            vec![],
        ),
        (
            "t1_n,t2_n\n1,2\n".into(),
            "x.csv:1: missing required column `wrap_deg`",
            vec![],
        ),
        (
            "wrap_deg,t2_n\n270,2\n".into(),
            "x.csv:1: missing required column `t1_n`",
            vec![],
        ),
        (
            "wrap_deg,t1_n,t2_n,t1_n\n".into(),
            "x.csv:1:4: column `t1_n` appears twice",
            vec!["column 2"],
        ),
        (
            "wrap_deg,t1_n,t2_n,\n270,1,2,\n".into(),
            "x.csv:1:4: header column 4 has no name",
            vec!["trailing comma"],
        ),
        (
            "# logged 2026-06-01\nwrap_deg,t1_n,t2_n\n270,1,2\n".into(),
            "x.csv:1: a comment line",
            vec!["grep -v '^#'"],
        ),
        (
            "wrap_deg;t1_n;t2_n\n270;1.5;3\n".into(),
            "x.csv:1: the header",
            vec!["separated by `;`", "tr ';' ','"],
        ),
        (
            "wrap_deg;t1_n;t2_n\n270;1,5;3,25\n".into(),
            "x.csv:1: the header",
            vec!["decimals are written with commas", "s/,/./g"],
        ),
        (
            "wrap_deg\tt1_n\tt2_n\n270\t1\t2\n".into(),
            "x.csv:1: the header",
            vec!["separated by tabs"],
        ),
        (
            "wrap_deg|t1_n|t2_n\n270|1|2\n".into(),
            "x.csv:1: the header",
            vec!["separated by `|`"],
        ),
        (
            "wrap_deg,t1_n,t2_n\n270,1,\"2\n".into(),
            "x.csv:2:3: a quoted cell opened here is never closed",
            vec![],
        ),
        (
            "wrap_deg,t1_n,t2_n\n#270,1,2\n".into(),
            "x.csv:2:1: column `wrap_deg`",
            vec!["comment line"],
        ),
        (
            "wrap_deg,t1_n,t2_n,humidity\n270,1,2,wet\n".into(),
            "x.csv:2:4: column `humidity`",
            vec!["label name", "material", "session"],
        ),
        (
            "wrap_deg,t1_n,t2_n\n270,1,2,4\n".into(),
            "x.csv:2: 4 cells where the header has 3",
            vec![],
        ),
        (
            "wrap_deg,t1_n,t2_n\n,,\n".into(),
            "x.csv:2:1: column `wrap_deg`: empty cell",
            vec![],
        ),
    ];
    for (text, at, words) in &cases {
        refused(text, at, words);
    }
    // A quoted cell across lines: its error is at the line it starts on, quoted short.
    let big = format!(
        "wrap_deg,t1_n,t2_n\n270,1,2\n270,1,\"{}\"\n",
        "9\n".repeat(300_000)
    );
    refused(
        &big,
        "x.csv:3:3: column `t2_n`: not a number",
        &["(600000 characters)"],
    );
    // One quoted cell larger than a line may be: refused where it starts, in bounded memory.
    let huge = format!("wrap_deg,t1_n,t2_n\n270,1,\"{}\"\n", "x".repeat(3 << 20));
    refused(
        &huge,
        "x.csv:2:3: a quoted cell that runs over",
        &["never closed?"],
    );
    // Another encoding (Latin-1 "°"), at its cell.
    let e = read_pairs(
        &b"wrap_deg,t1_n,t2_n\r\n270,1,2\r\n270\xb0,1,2\r\n"[..],
        "x.csv",
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.starts_with("x.csv:3:1: not UTF-8 text") && e.contains("save it as UTF-8"),
        "{e}"
    );
    checked();
    // Binary input.
    let zeros = String::from_utf8(vec![0u8; 2 << 20]).unwrap();
    refused(&zeros, "x.csv:1:1: a line longer than", &["binary"]);
}

#[test]
fn data_that_cannot_be_capstan_pairs_are_refused_with_the_likely_cause() {
    let t = thesis_dataset();
    let swapped = THESIS_CSV.replacen("t1_n,t2_n", "t2_n,t1_n", 1);
    refused(
        &swapped,
        "x.csv: T2 is below T1 in 705 of 720 rows",
        &["swapped", "swap the two names"],
    );
    let mut negated = String::from(H);
    negated.push('\n');
    for p in t.pairs.iter().take(40) {
        negated += &format!(
            "12.7,270,10,{},{},16,{},{}\n",
            p.run.unwrap(),
            p.step.unwrap(),
            -p.t1_n,
            -p.t2_n
        );
    }
    refused(
        &negated,
        "x.csv: only 0 of 40 rows have both tensions above zero",
        &["negated", "line 2"],
    );
    refused(
        "wrap_deg,t1_n,t2_n\n360,1,1\n360,2,2\n360,3,3\n",
        "x.csv: T2 is at most T1 in all 3 rows",
        &["swapped, or the drive off"],
    );
    refused(
        "wrap_deg,t1_n,t2_n\n360,1,0\n360,2,0\n360,3,7\n",
        "x.csv: only 1 of 3 rows",
        &[],
    );
    // A few rows at or below zero, or with T2 < T1, are data (a zero offset, a slack cord).
    accepted(
        "wrap_deg,t1_n,t2_n\n360,0.1,-0.05\n360,1,2\n360,2,4.1\n360,3,6.3\n",
        4,
        1,
        1,
    );
}

#[test]
fn the_structure_is_read_inferred_or_assumed_and_said() {
    // The thesis: 10 cords and 60 runs from columns.
    let d = accepted(THESIS_CSV, 720, 10, 60);
    assert!(d.structure.all_from_columns());
    // Case 5: only wrap_deg,t1_n,t2_n: 5 cords, 5 runs, both assumed, and said.
    let three: String = THESIS_CSV
        .lines()
        .map(|l| {
            let c: Vec<&str> = l.trim_end().split(',').collect();
            format!("{},{},{}\n", c[1], c[5], c[6])
        })
        .collect();
    let d = accepted(&three, 720, 5, 5);
    assert_eq!(d.structure.cord_level.from, Basis::Assumed);
    assert_eq!(d.structure.run_level.from, Basis::Assumed);
    assert!(d.structure.describe().contains("ASSUMED"));
    // With step: the runs come back, inferred from step restarting.
    let steps: String = THESIS_CSV
        .lines()
        .map(|l| {
            let c: Vec<&str> = l.trim_end().split(',').collect();
            format!("{},{},{},{},{}\n", c[0], c[1], c[4], c[5], c[6])
        })
        .collect();
    let d = accepted(&steps, 720, 10, 60);
    assert_eq!(d.structure.run_level.from, Basis::Inferred);
    // Two sessions concatenated with the same run numbers: refused with both lines ...
    let header = THESIS_CSV.lines().next().unwrap().trim_end();
    let body: String = THESIS_CSV
        .lines()
        .skip(1)
        .take(24)
        .map(|l| format!("{}\n", l.trim_end()))
        .collect();
    let twice = format!("{header}\n{body}{body}");
    refused(
        &twice,
        "x.csv:26: cord D12.7/270deg run 1 step 1 again (first on line 2)",
        &["session"],
    );
    // ... or kept apart by a session column (text, quoted or not), reported on line 2 if bad.
    let mut labelled =
        String::from("capstan_diameter_mm,wrap_deg,drive_v,run,step,t1_n,t2_n,session\n");
    for (k, l) in body.lines().chain(body.lines()).enumerate() {
        // (The second session's T2 a little different: a run equal to another to the last
        // digit is a copy, which the checks name.)
        labelled += &if k < 24 {
            format!("{l},\"2026-06-01, a\"\n")
        } else {
            format!("{l}1,b\n")
        };
    }
    let d = accepted(&labelled, 48, 1, 4);
    assert_eq!(d.structure.run_level.columns, ["run", "session"]);
    // Text columns are labels under their names: material separates cords.
    for (name, cords, runs) in [
        ("material", 2, 4),
        ("cord", 2, 4),
        ("date", 1, 4),
        ("note", 1, 2),
        ("comment", 1, 2),
    ] {
        let mut t = format!("capstan_diameter_mm,wrap_deg,drive_v,run,step,t1_n,t2_n,{name}\n");
        for (k, l) in body.lines().chain(body.lines()).enumerate() {
            t += &if k < 24 {
                format!("{l},nylon\n")
            } else {
                format!("{l}1,PE\n")
            };
        }
        if name == "note" || name == "comment" {
            refused(&t, "x.csv:26: cord D12.7/270deg run 1 step 1 again", &[]);
            continue;
        }
        accepted(&t, 48, cords, runs);
    }
    // Rows of one run scattered through the file are still one run.
    accepted(
        "wrap_deg,run,t1_n,t2_n\n270,1,1,2\n270,2,1,2.1\n270,1,2,4\n270,2,2,4.1\n",
        4,
        1,
        2,
    );
    // Without run and step, time_s restarting separates runs.
    accepted(
        "wrap_deg,time_s,t1_n,t2_n\n270,16,1,2\n270,26,2,4\n270,16,1,2.1\n270,26,2,4.1\n",
        4,
        1,
        2,
    );
}
