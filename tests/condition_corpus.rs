//! `capstan condition` on the exports labs really make, each written from the project's own
//! simulated raw series as another lab's logger would see it: 30 Hz for 140 s from before the
//! trigger (a lead-in of its own), the logger's noise (0.05 N) and zero offsets, in its units
//! and layout. Every export must give, for every run it holds and every level, a pair within
//! 2 % of the means of the logged series over the firmware's windows (2 s after each change
//! to 1 s before the next), and `capstan analyze` must read the pairs with the right runs.
//!
//! The corpus: Logger Pro's text export (two data sets), Logger Pro's "Export as CSV" (two
//! runs side by side, the second shorter), a LabVIEW measurement file (header block,
//! `***End_of_Header***`, X_Value, lbf, an empty Comment column), a DAQ CSV with a six-line
//! metadata block, grams and a run column, a PicoLog-style CSV (kN, time in ms, columns given
//! by number) and an Excel-saved CSV (byte-order mark, semicolons, decimal commas, CRLF, kg).

mod condition_support;

use condition_support::{capstan, condition_at, csv_rows, simulate_runs, tmp, Noise, Raw};
use std::path::Path;

const HZ: f64 = 30.0;
const LOGGED_S: f64 = 140.0;
const NOISE_N: f64 = 0.05;
const G0: f64 = 9.806_65;
const LBF: f64 = 4.448_221_615_260_5;

/// A logger's samples of one run: its own clock (s), T1 and T2 in N as it read them (zero
/// offsets and noise included), and the time since the trigger of each.
struct Logged {
    t: Vec<f64>,
    t1: Vec<f64>,
    t2: Vec<f64>,
    since: Vec<f64>,
}

/// One run as a logger sees it: from `lead_s` before the trigger, every 1/30 s for `span_s`,
/// the raw sample nearest before (the rig at rest after the run), plus `offsets` and noise.
fn logged(raw: &Raw, lead_s: f64, span_s: f64, offsets: (f64, f64), seed: u64) -> Logged {
    let mut noise = Noise(seed);
    let rest = raw[..20]
        .iter()
        .fold((0.0, 0.0), |a, r| (a.0 + r.1 / 20.0, a.1 + r.2 / 20.0));
    let mut l = Logged {
        t: Vec::new(),
        t1: Vec::new(),
        t2: Vec::new(),
        since: Vec::new(),
    };
    let mut j = 0;
    for i in 0..(span_s * HZ) as usize {
        let t = i as f64 / HZ;
        let since = t - lead_s;
        while j + 1 < raw.len() && raw[j + 1].0 <= since {
            j += 1;
        }
        let (a, b) = if since >= raw[0].0 && since <= raw[raw.len() - 1].0 {
            (raw[j].1, raw[j].2)
        } else {
            rest
        };
        l.t.push(t);
        l.t1.push(a + offsets.0 + NOISE_N * noise.normal());
        l.t2.push(b + offsets.1 + NOISE_N * noise.normal());
        l.since.push(since);
    }
    l
}

/// The means of the logged T1 and T2 over each of the firmware's 12 windows.
fn window_means(l: &Logged) -> Vec<(f64, f64)> {
    (0..12)
        .map(|k| {
            let (a, b) = (12.5 + 10.0 * k as f64, 19.5 + 10.0 * k as f64);
            let idx: Vec<usize> = (0..l.t.len())
                .filter(|&i| l.since[i] >= a && l.since[i] < b)
                .collect();
            let n = idx.len() as f64;
            (
                idx.iter().map(|&i| l.t1[i]).sum::<f64>() / n,
                idx.iter().map(|&i| l.t2[i]).sum::<f64>() / n,
            )
        })
        .collect()
}

/// One export: its file name, text, the `condition` options it needs, and the runs it holds
/// (run number, the logged run).
struct Export<'a> {
    name: &'static str,
    text: String,
    args: Vec<&'static str>,
    runs: Vec<(u32, &'a Logged)>,
}

fn logger_pro_text(runs: &[&Logged]) -> String {
    let mut s = String::new();
    for (k, l) in runs.iter().enumerate() {
        s += &format!(
            "Vernier Format 2\ncapstan.cmbl 11/27/2026 10:00:00 .\nRun {}\nTime\tForce\tForce 2\n\
             t\tF\tF2\ns\tN\tN\n\n",
            k + 1
        );
        for i in 0..l.t.len() {
            s += &format!("{:.4}\t{:.4}\t{:.4}\n", l.t[i], l.t1[i], l.t2[i]);
        }
    }
    s
}

fn logger_pro_csv(a: &Logged, b: &Logged) -> String {
    let mut s = String::from(
        "\"Run 1: Time (s)\",\"Run 1: Force (N)\",\"Run 1: Force 2 (N)\",\"Run 2: Time (s)\",\
         \"Run 2: Force (N)\",\"Run 2: Force 2 (N)\"\n",
    );
    for i in 0..a.t.len().max(b.t.len()) {
        let cell = |l: &Logged| match l.t.get(i) {
            Some(t) => format!("{t:.4},{:.4},{:.4}", l.t1[i], l.t2[i]),
            None => ",,".into(),
        };
        s += &format!("{},{}\n", cell(a), cell(b));
    }
    s
}

fn labview(l: &Logged) -> String {
    let mut s = String::from(
        "LabVIEW Measurement\t\nWriter_Version\t2\nReader_Version\t2\nSeparator\tTab\n\
         Decimal_Separator\t.\nMulti_Headings\tNo\nX_Columns\tOne\nTime_Pref\tRelative\n\
         Operator\tlab\nDate\t2026/11/27\nTime\t10:00:00.000\n***End_of_Header***\t\n\t\n\
         Channels\t2\t\nSamples\t4200\t4200\t\nDate\t2026/11/27\t2026/11/27\t\n\
         X_Dimension\tTime\tTime\t\nX0\t0.0000000000000000E+0\t0.0000000000000000E+0\t\n\
         Delta_X\t0.033333\t0.033333\t\n***End_of_Header***\t\t\t\n\
         X_Value\tForce T1 (lbf)\tForce T2 (lbf)\tComment\n",
    );
    for i in 0..l.t.len() {
        s += &format!(
            "{:.6}\t{:.6}\t{:.6}\t\n",
            l.t[i],
            l.t1[i] / LBF,
            l.t2[i] / LBF
        );
    }
    s
}

fn daq(runs: &[&Logged]) -> String {
    let mut s = String::from(
        "Logger,ACME DAQ-8\nSerial,A1234\nStarted,2026-11-27 10:00:00\nRate,30 Hz\n\
         Channels,2\n\nRun,Time (s),Force 1 (g),Force 2 (g)\n",
    );
    for (k, l) in runs.iter().enumerate() {
        for i in 0..l.t.len() {
            s += &format!(
                "{},{:.4},{:.2},{:.2}\n",
                k + 1,
                l.t[i],
                l.t1[i] / G0 * 1e3,
                l.t2[i] / G0 * 1e3
            );
        }
    }
    s
}

fn picolog(l: &Logged) -> String {
    let mut s = String::from("Time (ms),T1 Last (kN),T2 Last (kN)\n");
    for i in 0..l.t.len() {
        s += &format!(
            "{:.1},{:.8},{:.8}\n",
            l.t[i] * 1e3,
            l.t1[i] / 1e3,
            l.t2[i] / 1e3
        );
    }
    s
}

fn excel(l: &Logged) -> String {
    let mut s = String::from("\u{feff}Time (s);T1 (kg);T2 (kg)\r\n");
    for i in 0..l.t.len() {
        s +=
            &format!("{:.4};{:.6};{:.6}\r\n", l.t[i], l.t1[i] / G0, l.t2[i] / G0).replace('.', ",");
    }
    s
}

/// (run, step, T1, T2) of levels.csv, every level found.
fn levels(dir: &Path) -> Vec<(u32, u32, f64, f64)> {
    csv_rows(&dir.join("levels.csv"))
        .iter()
        .map(|r| {
            assert_eq!(r[11], "ok", "{r:?}");
            (
                r[0].parse().unwrap(),
                r[1].parse().unwrap(),
                r[7].parse().unwrap(),
                r[9].parse().unwrap(),
            )
        })
        .collect()
}

fn check(dir: &Path, e: &Export) {
    let file = dir.join(e.name);
    std::fs::write(&file, &e.text).unwrap();
    let out = dir.join(format!("{}-pairs", e.name));
    let mut more = vec!["--diameter-mm", "12.7", "--drive-v", "10"];
    more.extend(&e.args);
    let o = condition_at(&file, &out, &more);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{}: {stderr}", e.name);
    let got = levels(&out);
    assert_eq!(got.len(), 12 * e.runs.len(), "{}: {stderr}", e.name);
    // condition.json says where the pairs came from.
    let cj: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("condition.json")).unwrap())
            .unwrap();
    assert_eq!(
        cj["provenance"]["input_sha256"].as_str().map(str::len),
        Some(64),
        "{}",
        e.name
    );
    for (run, l) in &e.runs {
        let want = window_means(l);
        let mine: Vec<_> = got.iter().filter(|g| g.0 == *run).collect();
        assert_eq!(mine.len(), 12, "{} run {run}: {stderr}", e.name);
        for (g, (w1, w2)) in mine.iter().zip(&want) {
            for (v, w, ch) in [(g.2, w1, "T1"), (g.3, w2, "T2")] {
                assert!(
                    (v - w).abs() <= 0.02 * w.abs(),
                    "{} run {run} step {} {ch}: {v} N against the window mean {w} N",
                    e.name,
                    g.1
                );
            }
        }
    }
    // The pairs are what analyze reads, with the runs the export holds.
    let report = dir.join(format!("{}-report", e.name));
    let o = capstan(&[
        "analyze",
        out.join("pairs.csv").to_str().unwrap(),
        "--out",
        report.to_str().unwrap(),
    ]);
    assert!(
        o.status.success(),
        "{}: {}",
        e.name,
        String::from_utf8_lossy(&o.stderr)
    );
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(report.join("metrics.json")).unwrap())
            .unwrap();
    assert_eq!(m["data"]["runs"], e.runs.len(), "{}", e.name);
    assert_eq!(m["data"]["cords"], 1, "{}", e.name);
}

#[test]
fn every_export_in_the_corpus_converts_and_analyses_with_its_runs() {
    let dir = tmp("corpus");
    let sim = simulate_runs(&dir, "monotone", 2, &[]);
    let (r1, r2) = (&sim[0].1, &sim[1].1);
    // Each logger starts on its own before the trigger, with its own zero offsets.
    let a = logged(r1, 1.7, LOGGED_S, (0.03, -0.02), 11);
    let b = logged(r2, 2.4, LOGGED_S - 3.0, (0.03, -0.02), 12);
    let c = logged(r1, 0.4, LOGGED_S, (-0.01, 0.04), 13);
    let corpus = [
        Export {
            name: "logger-pro.txt",
            text: logger_pro_text(&[&a, &b]),
            args: vec![],
            runs: vec![(1, &a), (2, &b)],
        },
        Export {
            name: "logger-pro.csv",
            text: logger_pro_csv(&a, &b),
            args: vec![],
            runs: vec![(1, &a), (2, &b)],
        },
        Export {
            name: "labview.lvm",
            text: labview(&c),
            args: vec![],
            runs: vec![(1, &c)],
        },
        Export {
            name: "daq.csv",
            text: daq(&[&a, &b]),
            args: vec!["--time-column", "Time"],
            runs: vec![(1, &a), (2, &b)],
        },
        Export {
            name: "picolog.csv",
            text: picolog(&c),
            args: vec!["--t1-column", "2", "--t2-column", "T2 Last"],
            runs: vec![(1, &c)],
        },
        Export {
            name: "excel.csv",
            text: excel(&b),
            args: vec!["--run", "2"],
            runs: vec![(2, &b)],
        },
    ];
    for e in &corpus {
        check(&dir, e);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// One run of a side-by-side export by its `Run N:` name; a header block given by line.
#[test]
fn one_run_of_several_and_a_header_row_on_request() {
    let dir = tmp("corpus-one");
    let sim = simulate_runs(&dir, "updown", 2, &[]);
    let a = logged(&sim[0].1, 1.0, LOGGED_S, (0.0, 0.0), 21);
    let b = logged(&sim[1].1, 1.0, LOGGED_S, (0.0, 0.0), 22);
    let csv = dir.join("lp.csv");
    std::fs::write(&csv, logger_pro_csv(&a, &b)).unwrap();
    let out = dir.join("run2");
    let o = condition_at(&csv, &out, &["--time-column", "Run 2: Time"]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(stderr.contains("only Run 2 converted"), "{stderr}");
    let got = levels(&out);
    assert!(got.len() == 12 && got.iter().all(|g| g.0 == 2), "{got:?}");
    // The DAQ export's metadata block, passed by --skip-rows or --header-row.
    let daq_file = dir.join("daq.csv");
    std::fs::write(&daq_file, daq(&[&a])).unwrap();
    for opt in [["--skip-rows", "6"], ["--header-row", "7"]] {
        let out = dir.join(format!("daq{}", opt[0]));
        let o = condition_at(&daq_file, &out, &[opt[0], opt[1]]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert_eq!(levels(&out).len(), 12);
    }
    // A header that is not the header: said, with the header's columns.
    let o = condition_at(&daq_file, &dir.join("bad"), &["--header-row", "2"]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}
