//! The reader: positions, refusals, labels, the structure, round trips.

use super::*;
use crate::plausible;

fn pair(wrap_deg: f64, run: Option<f64>) -> Pair {
    Pair {
        capstan_diameter_mm: Some(12.7),
        wrap_deg,
        drive_v: Some(10.0),
        run,
        step: Some(2.0),
        time_s: Some(1.65),
        t1_n: 1.5469999,
        t2_n: 3.1938002,
        extra: Vec::new(),
        labels: Vec::new(),
    }
}

#[test]
fn pairs_written_one_at_a_time_read_back_and_unknowns_are_empty_cells() {
    let mut w = PairsWriter::new(Vec::new()).unwrap();
    w.write(&pair(360.0, Some(1.0))).unwrap();
    w.write(&pair(450.0, Some(2.0))).unwrap();
    let csv = String::from_utf8(w.into_inner()).unwrap();
    let back = read_pairs(csv.as_bytes(), "test").unwrap();
    assert_eq!(back.header.join(","), PAIRS_HEADER.join(","));
    assert_eq!(back.pairs, [pair(360.0, Some(1.0)), pair(450.0, Some(2.0))]);
    let mut w = PairsWriter::new(Vec::new()).unwrap();
    w.write(&pair(f64::NAN, None)).unwrap();
    let csv = String::from_utf8(w.into_inner()).unwrap();
    assert_eq!(
        csv.lines().nth(1),
        Some("12.7,,10,,2,1.65,1.5469999,3.1938002")
    );
}

#[test]
fn bundled_thesis_data_has_720_rows_ten_cords_sixty_runs_from_columns() {
    let d = thesis_dataset();
    assert_eq!(d.pairs.len(), 720);
    assert!(!d.has_column("time_s"));
    assert_eq!(d.pairs[1].t1_n, 1.157991);
    assert_eq!(d.pairs[1].run, Some(1.0));
    let s = &d.structure;
    assert_eq!((s.cords.len(), s.run_cord.len()), (10, 60));
    assert!(s.all_from_columns(), "{}", s.describe());
    assert_eq!(
        s.describe(),
        "structure: 10 cords from columns (capstan_diameter_mm, wrap_deg, drive_v); 60 runs \
         from columns (run)"
    );
    // CRLF: the rows are on lines 2, 3, ...
    assert_eq!((d.lines[0], d.lines[719]), (2, 721));
}

fn err(csv: &str) -> String {
    read_pairs(csv.as_bytes(), "x.csv").unwrap_err().to_string()
}

#[test]
fn bad_input_names_file_line_and_column() {
    assert!(err("wrap_deg,t1_n\n270,1\n").starts_with("x.csv:1: missing required column `t2_n`"));
    assert_eq!(
        err("wrap_deg,t1_n,t2_n\n270,1,2\n270,abc,2\n"),
        "x.csv:3:2: column `t1_n`: not a number (found `abc`)"
    );
    assert_eq!(
        err("wrap_deg,t1_n,t2_n\n0,1,2\n"),
        "x.csv:2:1: column `wrap_deg`: must be greater than 0 and at most 3600 deg (ten turns) \
         (found `0`)"
    );
    assert!(err("wrap_deg,t1_n,t2_n\n270,1e154,2\n")
        .starts_with("x.csv:2:2: column `t1_n`: must be within ±10000 N"));
    // A reading at or below zero is data (a zero offset makes it real).
    let d = read_pairs(
        "wrap_deg,t1_n,t2_n\n270,0,2\n270,-0.16,0.3\n".as_bytes(),
        "x",
    )
    .unwrap();
    assert_eq!(d.pairs[1].t1_n, -0.16);
    assert_eq!(
        err("wrap_deg,t1_n,t2_n\n270,1,NaN\n"),
        "x.csv:2:3: column `t2_n`: not a finite number (found `NaN`)"
    );
    assert_eq!(
        err("wrap_deg,t1_n,t2_n\n270,1,\n"),
        "x.csv:2:3: column `t2_n`: empty cell (found ``)"
    );
    assert_eq!(
        err("wrap_deg,t1_n,t2_n\n270,1\n"),
        "x.csv:2: 2 cells where the header has 3"
    );
    assert_eq!(
        err("wrap_deg,t1_n,t2_n\n"),
        "x.csv: no data rows (a header and nothing else)"
    );
    assert!(err("wrap_deg,t1_n,t1_n,t2_n\n")
        .starts_with("x.csv:1:3: column `t1_n` appears twice (also column 2)"));
    assert!(err("wrap_deg,t1_n,t2_n,humidity\n270,1,2,wet\n")
        .starts_with("x.csv:2:4: column `humidity`: not a number; a text column is read only under a label name (cord, material, session, date, boot, note, comment) (found `wet`)"));
}

#[test]
fn lines_are_exact_for_every_line_ending_blank_lines_and_long_lines() {
    let bad = |body: &str| err(body).split(": ").next().unwrap().to_string();
    assert_eq!(bad("wrap_deg,t1_n,t2_n\r\n270,abc,2\r\n"), "x.csv:2:2");
    assert_eq!(bad("wrap_deg,t1_n,t2_n\r270,1,2\r270,abc,2\r"), "x.csv:3:2");
    assert_eq!(
        bad("wrap_deg,t1_n,t2_n\n\n270,1,2\n\r\n\n270,1,x\n"),
        "x.csv:6:3"
    );
    let mut long = String::from("wrap_deg,t1_n,t2_n\n");
    for _ in 0..299 {
        long += "270,1,2\n";
    }
    long += &"9".repeat(MAX_LINE_BYTES + 10);
    assert_eq!(bad(&long), "x.csv:301:1");
    // A quoted cell over several lines: the error is where the cell starts; the quote is
    // short and on one line.
    let e = err("wrap_deg,t1_n,t2_n\n270,1,\"2\n\n3\"\n");
    assert!(
        e.starts_with("x.csv:2:3: column `t2_n`: not a number (found `2\\n\\n3`)"),
        "{e}"
    );
    let e = err(&format!(
        "wrap_deg,t1_n,t2_n\n270,1,\"{}\"\n",
        "7\n".repeat(100_000)
    ));
    assert!(e.len() < 250 && e.contains("(200000 characters)"), "{e}");
    let e = err(&format!(
        "wrap_deg,t1_n,t2_n\n270,1,\"{}",
        "x\n".repeat(600_000)
    ));
    assert!(
        e.starts_with("x.csv:2:3: a quoted cell that runs over"),
        "{e}"
    );
}

#[test]
fn hints_lead_to_a_fix() {
    let e = err("# exported by the logger\nwrap_deg,t1_n,t2_n\n270,1,2\n");
    assert!(
        e.contains("x.csv:1: a comment line") && e.contains("grep -v '^#'"),
        "{e}"
    );
    let e = err("wrap_deg;t1_n;t2_n\n270;1,5;3,25\n");
    assert!(
        e.contains("separated by `;`") && e.contains("s/,/./g"),
        "{e}"
    );
    assert!(!e.contains("tr ';'"), "{e}");
    let e = err("wrap_deg;t1_n;t2_n\n270;1.5;3.25\n");
    assert!(e.contains("tr ';' ','"), "{e}");
    let e = err("wrap_deg,t1_n,t2_n,\n270,1,2,\n");
    assert!(
        e.starts_with("x.csv:1:4: header column 4 has no name"),
        "{e}"
    );
    let e = err("wrap_deg,t1_n,t2_n\n270,\"1,5\",2\n");
    assert!(e.contains("write decimals with a point"), "{e}");
}

#[test]
fn columns_in_any_order_extras_kept_and_round_trip() {
    let d = read_pairs(
        "t2_n,humidity,t1_n,wrap_deg\n3.5,40,1.5,360\n".as_bytes(),
        "y",
    )
    .unwrap();
    assert_eq!(d.extra_columns, ["humidity"]);
    assert_eq!(
        (d.pairs[0].t1_n, d.pairs[0].t2_n, d.pairs[0].extra[0]),
        (1.5, 3.5, 40.0)
    );
    let mut out = Vec::new();
    write_pairs_to(&mut out, &d.pairs).unwrap();
    let back = read_pairs(out.as_slice(), "z").unwrap();
    assert_eq!(back.pairs[0].t1_n, 1.5);
    assert_eq!(back.pairs[0].run, None);
}

/// The thesis data with only some of its columns (and `extra` appended to the header).
fn thesis_columns(keep: &[&str], extra: &str, cell: impl Fn(usize) -> String) -> Dataset {
    let t = thesis_dataset();
    let idx: Vec<usize> = keep
        .iter()
        .map(|k| t.header.iter().position(|h| h == k).unwrap())
        .collect();
    let mut s = keep.join(",");
    if !extra.is_empty() {
        s += &format!(",{extra}");
    }
    s.push('\n');
    for (i, line) in THESIS_CSV.lines().skip(1).enumerate() {
        let cells: Vec<&str> = line.trim_end().split(',').collect();
        let row: Vec<&str> = idx.iter().map(|&k| cells[k]).collect();
        s += &row.join(",");
        if !extra.is_empty() {
            s += &format!(",{}", cell(i));
        }
        s.push('\n');
    }
    read_pairs(s.as_bytes(), "t.csv").unwrap()
}

#[test]
fn the_structure_says_what_was_read_inferred_or_assumed() {
    let three = thesis_columns(&["wrap_deg", "t1_n", "t2_n"], "", |_| String::new());
    let s = &three.structure;
    assert_eq!((s.cords.len(), s.run_cord.len()), (5, 5));
    assert_eq!(
        (s.cord_level.from, s.run_level.from),
        (Basis::Assumed, Basis::Assumed)
    );
    assert!(s.describe().contains("5 cords ASSUMED") && s.describe().contains("5 runs ASSUMED"));
    assert_eq!(s.assumed.len(), 2);
    // Steps restarting give the runs back: 60, inferred.
    let steps = thesis_columns(
        &["capstan_diameter_mm", "wrap_deg", "step", "t1_n", "t2_n"],
        "",
        |_| String::new(),
    );
    let s = &steps.structure;
    assert_eq!((s.cords.len(), s.run_cord.len()), (10, 60));
    assert_eq!(
        (s.cord_level.from, s.run_level.from),
        (Basis::Columns, Basis::Inferred)
    );
    // A cord label separates the two capstans without the diameter column.
    let material = thesis_columns(
        &["wrap_deg", "run", "step", "t1_n", "t2_n"],
        "material",
        |i| {
            if i < 360 {
                "nylon"
            } else {
                "\"polyester, braided\""
            }
            .to_string()
        },
    );
    let s = &material.structure;
    assert_eq!((s.cords.len(), s.run_cord.len()), (10, 60));
    assert_eq!(s.cord_level.from, Basis::Columns);
    assert_eq!(material.pairs[400].labels[0], "polyester, braided");
}

#[test]
fn two_sessions_with_the_same_run_numbers_are_refused_or_kept_apart_by_a_session_column() {
    let one = "wrap_deg,run,step,t1_n,t2_n\n270,1,1,1,2\n270,1,2,2,4\n";
    let twice = format!("{one}270,1,1,1.1,2.1\n270,1,2,2.1,4.1\n");
    let e = err(&twice);
    assert!(
        e.starts_with("x.csv:4: cord D12.7/270deg run 1 step 1 again (first on line 2)")
            && e.contains("`session` column"),
        "{e}"
    );
    let labelled = "wrap_deg,run,step,t1_n,t2_n,session\n270,1,1,1,2,a\n270,1,2,2,4,a\n\
                    270,1,1,1.1,2.1,b\n270,1,2,2.1,4.1,b\n";
    let d = read_pairs(labelled.as_bytes(), "x").unwrap();
    assert_eq!(d.structure.run_cord.len(), 2);
    assert_eq!(d.structure.run_level.columns, ["run", "session"]);
}

#[test]
fn data_that_cannot_be_capstan_pairs_are_refused_with_the_likely_cause() {
    let t = thesis_dataset();
    let swapped = Dataset::from_pairs(
        "swapped.csv",
        t.pairs
            .iter()
            .map(|p| Pair {
                t1_n: p.t2_n,
                t2_n: p.t1_n,
                ..p.clone()
            })
            .collect(),
    )
    .unwrap();
    let e = check_capstan_data(&swapped).unwrap_err().to_string();
    assert!(
        e.contains("T2 is below T1 in 705 of 720 rows") && e.contains("swapped"),
        "{e}"
    );
    let negated = Dataset::from_pairs(
        "negated.csv",
        t.pairs
            .iter()
            .map(|p| Pair {
                t1_n: -p.t1_n,
                t2_n: -p.t2_n,
                ..p.clone()
            })
            .collect(),
    )
    .unwrap();
    let e = check_capstan_data(&negated).unwrap_err().to_string();
    assert!(
        e.contains("only 0 of 720 rows have both tensions above zero"),
        "{e}"
    );
    assert!(check_capstan_data(&t).is_ok());
}

/// The thesis data with `f` applied to every `every`-th row (from row `from`).
fn thesis_with(every: usize, from: usize, f: impl Fn(&mut Pair)) -> Dataset {
    let mut pairs = thesis_dataset().pairs;
    for p in pairs.iter_mut().skip(from).step_by(every) {
        f(p);
    }
    Dataset::from_pairs("edited.csv", pairs).unwrap()
}

#[test]
fn swapped_or_negated_rows_are_named_warned_about_and_refused_above_a_small_share() {
    assert_eq!(plausible::swap_margin_n(), plausible::SWAP_MARGIN_N);
    // The thesis data hold none (15 rows with T2 a little below T1 at the lowest level are a
    // zero offset's doing).
    let t = check_capstan_data(&thesis_dataset()).unwrap();
    assert_eq!((t.suspect_rows(), t.column_warnings.len()), (0, 0), "{t:?}");
    let swap = |p: &mut Pair| std::mem::swap(&mut p.t1_n, &mut p.t2_n);
    // 10 % of the rows swapped: refused, naming the kind.
    let e = check_capstan_data(&thesis_with(10, 0, swap))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("cannot be capstan data") && e.contains("T1 and T2 swapped?"),
        "{e}"
    );
    // 5 % too (every 20th row, a level from 1 to 12 in turn).
    assert!(check_capstan_data(&thesis_with(20, 3, swap)).is_err());
    // One swapped row at the top level of run 1 (line 13): a warning that names it.
    let one = thesis_with(10_000, 11, swap);
    let found = check_capstan_data(&one).unwrap();
    let w = found.warnings("edited.csv");
    assert_eq!(found.suspect_rows(), 1, "{w:?}");
    assert!(
        w[0].contains("swapped?") && w[0].contains("line 13"),
        "{w:?}"
    );
    // Some T1 negated (every 10th row): refused; the rows below -3 N are named.
    let e = check_capstan_data(&thesis_with(10, 5, |p| p.t1_n = -p.t1_n))
        .unwrap_err()
        .to_string();
    assert!(e.contains("negated?") && e.contains("lines "), "{e}");
}

#[test]
fn tensions_in_grams_or_kn_and_wraps_in_radians_name_the_unit() {
    let grams = thesis_with(1, 0, |p| {
        p.t1_n *= 101.971_621;
        p.t2_n *= 101.971_621;
    });
    let e = check_capstan_data(&grams).unwrap_err().to_string();
    assert!(
        e.contains("grams") && e.contains("no bench capstan rig"),
        "{e}"
    );
    let kn = thesis_with(1, 0, |p| {
        p.t1_n /= 1000.0;
        p.t2_n /= 1000.0;
    });
    let w = check_capstan_data(&kn).unwrap().warnings("kn.csv");
    assert!(w.iter().any(|w| w.contains("in kN")), "{w:?}");
    let radians = thesis_with(1, 0, |p| p.wrap_deg = p.wrap_deg.to_radians());
    let e = check_capstan_data(&radians).unwrap_err().to_string();
    assert!(
        e.contains("radians?") && e.contains("mu = ") && e.starts_with("edited.csv:290:2:"),
        "{e}"
    );
}

#[test]
fn time_going_back_in_a_run_and_a_copied_run_are_named() {
    // Times from the steps (10 s apart): the thesis protocol.
    let timed = |f: &dyn Fn(usize, &mut Pair)| {
        let mut pairs = thesis_dataset().pairs;
        for (i, p) in pairs.iter_mut().enumerate() {
            p.time_s = Some(10.0 * p.step.unwrap());
            f(i, p);
        }
        Dataset::from_pairs("timed.csv", pairs).unwrap()
    };
    let ok = check_capstan_data(&timed(&|_, _| {})).unwrap();
    assert_eq!(ok.suspect_rows(), 0);
    // Run 1's step 5 logged at 1 s: its time goes back (and step 6's does not follow it).
    let back = check_capstan_data(&timed(&|i, p| {
        if i == 4 {
            p.time_s = Some(1.0)
        }
    }))
    .unwrap();
    let w = back.warnings("timed.csv");
    assert!(
        w.len() == 1 && w[0].contains("time_s not after") && w[0].contains("line 6"),
        "{w:?}"
    );
    // Run 2 of the first cord pasted as a seventh run.
    let mut pairs = thesis_dataset().pairs;
    let copy: Vec<Pair> = pairs[12..24]
        .iter()
        .map(|p| Pair {
            run: Some(7.0),
            ..p.clone()
        })
        .collect();
    pairs.extend(copy);
    let copied = Dataset::from_pairs("copied.csv", pairs).unwrap();
    let found = check_capstan_data(&copied).unwrap();
    let w = found.warnings("copied.csv");
    assert_eq!(found.suspect_rows(), 12, "{w:?}");
    assert!(
        w[0].contains("run 7 (from line 722) repeats") && w[0].contains("run 2 (from line 14)"),
        "{w:?}"
    );
}

#[test]
fn a_raw_time_series_is_pointed_to_condition() {
    for raw in [
        "t_s,t1_counts,t2_counts,t1_n,t2_n\n0.01,400,391,0.1,0.2\n",
        "Time (s),Force (N),Force 2 (N)\n0,0.1,0.2\n",
        "Vernier Format 2\nx.cmbl 11/27/2026 .\nLatest\nTime\tForce\tForce 2\n",
        "Time\tForce\tForce 2\n0\t0.1\t0.2\n",
    ] {
        let e = err(raw);
        assert!(
            e.contains("raw time series") && e.contains("capstan condition x.csv --out DIR"),
            "{raw:?}: {e}"
        );
        assert!(!e.contains("tr '"), "{e}");
    }
    // A pairs CSV without a column is still told which.
    assert!(err("wrap_deg,t1_n\n270,1\n").contains("missing required column `t2_n`"));
}

#[test]
fn a_trailing_comma_or_a_stray_carriage_return_is_named() {
    let e = err("wrap_deg,t1_n,t2_n\n270,1,2,\n");
    assert_eq!(
        e,
        "x.csv:2: 4 cells where the header has 3: a trailing comma at the end of the line (an \
         empty last cell): remove it"
    );
    let e = err("wrap_deg,t1_n,t2_n\n270,1,2\n270,1\r,2\n270,1,2\n");
    assert!(
        e.starts_with(
            "x.csv:3: 2 cells where the header has 3: the line is cut by a carriage \
                       return (\\r)"
        ),
        "{e}"
    );
    // CRLF and CR-only files are not strays.
    assert!(read_pairs("wrap_deg,t1_n,t2_n\r\n270,1,2\r\n".as_bytes(), "x").is_ok());
    assert!(read_pairs("wrap_deg,t1_n,t2_n\r270,1,2\r".as_bytes(), "x").is_ok());
}
