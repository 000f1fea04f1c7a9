//! `capstan condition` as a user meets it: a 30 Hz logger export made from the simulated rig
//! (the thesis's LabPro rate, a logger's noise, the rig's own transients), in Logger Pro's
//! text format, conditioned into pairs that match the firmware's own pairs within their
//! noise, for monotone and up-down orders; a level that cannot be found is reported, never
//! dropped; a bad cell is named by file, line and column.

mod condition_support;

use condition_support::{capstan, condition_at, csv_rows, simulate_runs, tmp, Noise};
use std::path::Path;

/// The thesis logger: 30 Hz.
const LOGGER_HZ: f64 = 30.0;
/// A LabPro force channel's noise, N (sd).
const LOGGER_NOISE_N: f64 = 0.05;
/// The thesis logged 140 s.
const LOGGED_S: f64 = 140.0;

/// Simulate one run in `order`; its firmware pairs (step, T1, T2) and the raw samples
/// (t, T1, T2) at the raw log's 100 Hz.
/// (step, T1, T2) pairs and (t, T1, T2) samples.
type Simulated = (Vec<(u32, f64, f64)>, Vec<(f64, f64, f64)>);

fn simulate(dir: &Path, order: &str) -> Simulated {
    simulate_with(dir, order, &[])
}

/// As [`simulate`], with more `simulate` options (`--noise thesis`).
fn simulate_with(dir: &Path, order: &str, more: &[&str]) -> Simulated {
    simulate_runs(dir, order, 1, more).remove(0)
}

/// The raw samples as a LabPro would log them: from the trigger, every 1/30 s, the sample
/// nearest, plus the logger's noise; after the run, the rig at rest until 140 s. In Logger
/// Pro's text export ("Vernier Format 2").
fn logger_pro_export(raw: &[(f64, f64, f64)], seed: u64) -> String {
    let mut noise = Noise(seed);
    let rest = raw[..20]
        .iter()
        .fold((0.0, 0.0), |a, r| (a.0 + r.1 / 20.0, a.1 + r.2 / 20.0));
    let mut s = String::from(
        "Vernier Format 2\nthesis.cmbl 11/27/2026 10:00:00 .\nLatest\nTime\tForce\tForce 2\nt\tF\tF2\ns\tN\tN\n\n",
    );
    let mut j = 0;
    for i in 0..(LOGGED_S * LOGGER_HZ) as usize {
        let t = i as f64 / LOGGER_HZ;
        while j + 1 < raw.len() && raw[j + 1].0 <= t {
            j += 1;
        }
        let (t1, t2) = if t <= raw[raw.len() - 1].0 {
            (raw[j].1, raw[j].2)
        } else {
            rest
        };
        let (n1, n2) = (noise.normal(), noise.normal());
        s += &format!(
            "{t:.4}\t{:.3}\t{:.3}\n",
            t1 + LOGGER_NOISE_N * n1,
            t2 + LOGGER_NOISE_N * n2
        );
    }
    s
}

/// (step, samples, T1 mean, T1 sd, T2 mean, T2 sd, status) from levels.csv.
fn levels(dir: &Path) -> Vec<(u32, f64, f64, f64, f64, f64, String)> {
    csv_rows(&dir.join("levels.csv"))
        .iter()
        .map(|r| {
            let f = |i: usize| r[i].parse::<f64>().unwrap_or(f64::NAN);
            (
                r[1].parse().unwrap(),
                f(6),
                f(7),
                f(8),
                f(9),
                f(10),
                r[11].clone(),
            )
        })
        .collect()
}

fn check_order(order: &str) {
    let dir = tmp(order);
    let (fw_pairs, raw) = simulate(&dir, order);
    assert_eq!(fw_pairs.len(), 12, "{order}: the firmware's 12 levels");
    let export = dir.join("run1.txt");
    std::fs::write(&export, logger_pro_export(&raw, 11)).unwrap();
    let out = dir.join("pairs");
    let o = condition_at(
        &export,
        &out,
        &["--diameter-mm", "12.7", "--drive-v", "10", "--json"],
    );
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{order}: {stderr}");
    assert!(stderr.contains("as logger-pro"), "{stderr}");
    let found = levels(&out);
    assert_eq!(found.len(), 12, "{order}: every level found\n{stderr}");
    for ((step, n, t1, sd1, t2, sd2, status), (fw_step, fw1, fw2)) in found.iter().zip(&fw_pairs) {
        assert_eq!(status, "ok");
        assert_eq!(step, fw_step);
        // The window holds the firmware's 7 s at 30 Hz.
        assert!(
            (*n - 7.0 * LOGGER_HZ).abs() <= 8.0,
            "{order} step {step}: {n} samples"
        );
        // Within the noise of the logger's mean (4 sd of it), plus 5 mN for the rig's own
        // drift inside a window the change detection places a sample or so later.
        for (mean, sd, fw, ch) in [(t1, sd1, fw1, "T1"), (t2, sd2, fw2, "T2")] {
            let tol = 4.0 * sd / n.sqrt() + 0.005;
            assert!(
                (mean - fw).abs() <= tol,
                "{order} step {step} {ch}: {mean} against the firmware's {fw} (tolerance {tol})"
            );
            // The noise seen is the logger's.
            assert!(
                *sd > 0.8 * LOGGER_NOISE_N && *sd < 1.5 * LOGGER_NOISE_N,
                "{sd}"
            );
        }
    }
    // Placed by the protocol instead of found: the firmware's windows, the same pairs.
    let proto = dir.join("protocol");
    let o = condition_at(
        &export,
        &proto,
        &["--first-change-s", "10.5", "--dwell-s", "10"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for ((step, n, t1, sd1, _, _, _), (_, fw1, _)) in levels(&proto).iter().zip(&fw_pairs) {
        let tol = 4.0 * sd1 / n.sqrt() + 0.005;
        assert!(
            (t1 - fw1).abs() <= tol,
            "{order} protocol step {step}: {t1} against {fw1}"
        );
    }
    // The pairs are what analyze reads.
    let pairs = std::fs::read_to_string(out.join("pairs.csv")).unwrap();
    assert!(pairs.starts_with("capstan_diameter_mm,wrap_deg,drive_v,run,step,time_s,t1_n,t2_n"));
    assert_eq!(pairs.lines().count(), 13);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_30_hz_logger_pro_export_gives_the_firmwares_pairs_monotone() {
    check_order("monotone");
}

#[test]
fn a_30_hz_logger_pro_export_gives_the_firmwares_pairs_updown() {
    check_order("updown");
}

/// A level the series lacks (the logger dropped 8 s of it) is reported, by the count of
/// levels found and, with the protocol, as that level's window without samples.
#[test]
fn a_level_that_cannot_be_found_is_reported_never_dropped() {
    let dir = tmp("missing");
    let (_, raw) = simulate(&dir, "monotone");
    let text = logger_pro_export(&raw, 3);
    // Step 4 of the thesis protocol: 40.5 to 50.5 s after the trigger. Cut 41-50 s.
    let cut: String = text
        .lines()
        .filter(
            |l| match l.split('\t').next().and_then(|t| t.parse::<f64>().ok()) {
                Some(t) => !(41.0..50.0).contains(&t),
                None => true,
            },
        )
        .map(|l| format!("{l}\n"))
        .collect();
    let export = dir.join("cut.txt");
    std::fs::write(&export, cut).unwrap();
    let run = |extra: &[&str], out: &str| {
        let out = dir.join(out);
        (condition_at(&export, &out, extra), out)
    };
    let (o, out) = run(&[], "found");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{stderr}");
    // Found from the tensions: the gap is a level whose window holds no sample (or, were it
    // merged into a neighbour, one level fewer than the 12 expected), said either way.
    assert!(
        stderr.contains("not found") || stderr.contains("12 expected"),
        "{stderr}"
    );
    assert!(
        out.join("levels.csv").is_file(),
        "the levels found are kept"
    );
    let (o, out) = run(&["--first-change-s", "10.5", "--dwell-s", "10"], "protocol");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{stderr}");
    let lv = levels(&out);
    assert_eq!(lv.len(), 12, "every level of the protocol is listed");
    let missing: Vec<_> = lv.iter().filter(|l| l.6 != "ok").map(|l| l.0).collect();
    assert_eq!(missing, vec![4], "{lv:?}");
    assert!(
        stderr.contains("step  4") && stderr.contains("not found"),
        "{stderr}"
    );
    let pairs = std::fs::read_to_string(out.join("pairs.csv")).unwrap();
    assert_eq!(
        pairs.lines().count(),
        12,
        "the 11 levels found, and the header"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_cells_are_named_by_file_line_and_column_and_units_are_honoured() {
    let dir = tmp("bad");
    let f = dir.join("daq.csv");
    std::fs::write(&f, "Time (ms),T1 [kgf],T2 [kgf]\n0,0.1,0.2\n33,0.1,zero\n").unwrap();
    let o = condition_at(&f, &dir.join("o"), &[]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        stderr.contains("daq.csv:3:3:") && stderr.contains("zero"),
        "{stderr}"
    );
    // Refused before it wrote anything: no output directory is left behind.
    assert!(!dir.join("o").exists(), "{stderr}");
    // Ambiguous force columns: the user is asked to name them.
    std::fs::write(&f, "time,a (N),b (N)\n0,1,2\n").unwrap();
    let o = condition_at(&f, &dir.join("o"), &[]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("--t1-column"), "{stderr}");
    // Units: kgf and ms, read as N and s.
    let mut s = String::from("Time (ms)\tT1 [kgf]\tT2 [kgf]\n");
    for i in 0..4200 {
        let t = i as f64 * 33.333;
        // The thesis protocol: rest until 10.5 s, 12 levels of 10 s, rest again.
        let k = ((t / 1000.0 - 0.5) / 10.0).floor();
        let level = if (1.0..=12.0).contains(&k) { k } else { 0.0 };
        s += &format!("{t:.1}\t{:.4}\t{:.4}\n", 0.1 * level, 0.2 * level);
    }
    std::fs::write(&f, s).unwrap();
    let out = dir.join("units");
    let o = condition_at(&f, &out, &[]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    let lv = levels(&out);
    assert_eq!(lv.len(), 12, "{stderr}");
    assert!((lv[0].2 - 0.1 * 9.80665).abs() < 1e-9, "{:?}", lv[0]);
    assert!((lv[11].4 - 2.4 * 9.80665).abs() < 1e-9, "{:?}", lv[11]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The firmware's own raw log (100 Hz of its 1 kHz samples), conditioned again with the
/// firmware's windows, gives its pairs (to the noise of a tenth of the samples); with other
/// windows, the windows asked for.
/// Recondition our own raw log with the defaults (levels found from the tensions): the
/// firmware's twelve pairs, each within 4 standard errors of its window's mean.
fn recondition(dir: &Path, fw_pairs: &[(u32, f64, f64)]) {
    let raw = dir.join("sim/raw/d12.7_w360_v10_run1.csv");
    let out = dir.join("again");
    let o = condition_at(&raw, &out, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let lv = levels(&out);
    assert_eq!(lv.len(), 12);
    for (l, (step, fw1, fw2)) in lv.iter().zip(fw_pairs) {
        assert_eq!(l.0, *step);
        let tol1 = 4.0 * l.3 / l.1.sqrt() + 0.002;
        let tol2 = 4.0 * l.5 / l.1.sqrt() + 0.002;
        assert!(
            (l.2 - fw1).abs() <= tol1,
            "step {step}: T1 {} against {fw1}",
            l.2
        );
        assert!(
            (l.4 - fw2).abs() <= tol2,
            "step {step}: T2 {} against {fw2}",
            l.4
        );
    }
}

/// The thesis rig's noise (12-bit counts of 15 mN, a wandering friction, zero errors): the
/// median of a quantised reading flips by a count when a level sits near a count's edge, and
/// that is not a change of level (it split every dwell in two before).
#[test]
fn our_thesis_noise_raw_log_reconditioned_gives_the_firmwares_twelve_pairs() {
    let dir = tmp("raw-thesis");
    let (fw_pairs, _) = simulate_with(&dir, "monotone", &["--noise", "thesis"]);
    recondition(&dir, &fw_pairs);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn our_raw_log_reconditioned_gives_the_firmwares_pairs_and_other_windows_on_request() {
    let dir = tmp("raw");
    let (fw_pairs, _) = simulate(&dir, "updown");
    recondition(&dir, &fw_pairs);
    let raw = dir.join("sim/raw/d12.7_w360_v10_run1.csv");
    let out = dir.join("late");
    let o = condition_at(
        &raw,
        &out,
        &["--window-after-ms", "5000", "--window-before-ms", "500"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(out.join("levels.csv")).unwrap();
    for row in text.lines().skip(1) {
        let c: Vec<f64> = row.split(',').take(6).map(|x| x.parse().unwrap()).collect();
        assert!(
            (c[4] - c[2] - 5.0).abs() < 1e-9 && (c[3] - c[5] - 0.5).abs() < 1e-9,
            "{row}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--levels 0` is not a protocol: refused before anything is read or written.
#[test]
fn zero_levels_are_refused_at_the_command_line() {
    let out = tmp("zero-levels").join("out");
    let o = capstan(&[
        "condition",
        "no-such.csv",
        "--wrap-deg",
        "360",
        "--levels",
        "0",
        "--out",
        out.to_str().unwrap(),
    ]);
    let text = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && text.contains("--levels"), "{text}");
    assert!(!out.exists(), "refused, yet {} was made", out.display());
}

/// `--drive-v` outside the rig's drive (0 to the 13.2 V `simulate` and `predict` refuse: a
/// negative or non-finite voltage too) and `--run 0` (runs are numbered from 1) are refused by
/// name before anything is written; an adversarial pass found them conditioned with exit 0.
/// The top itself is a drive the rig runs.
#[test]
fn a_drive_the_rig_cannot_run_and_run_zero_are_refused() {
    let dir = tmp("drive-run");
    simulate(&dir, "monotone");
    let raw = dir.join("sim/raw/d12.7_w360_v10_run1.csv");
    for (more, says) in [
        (
            ["--drive-v", "99"],
            "--drive-v 99: the rig's drive gives 0 to 13.2 V",
        ),
        (
            ["--drive-v", "13.3"],
            "--drive-v 13.3: the rig's drive gives 0 to 13.2 V",
        ),
        // Below 0 V (and no number at all) is outside the drive too, said in the same words.
        (
            ["--drive-v", "-1"],
            "--drive-v -1: the rig's drive gives 0 to 13.2 V (the firmware's full control \
             voltage times the amplifier's gain); the pairs would record a drive the rig cannot \
             run",
        ),
        (
            ["--drive-v", "-0.01"],
            "--drive-v -0.01: the rig's drive gives 0 to 13.2 V",
        ),
        (
            ["--drive-v", "inf"],
            "--drive-v inf: the rig's drive gives 0 to 13.2 V",
        ),
        (
            ["--drive-v", "nan"],
            "--drive-v NaN: the rig's drive gives 0 to 13.2 V",
        ),
        (["--run", "0"], "--run 0: runs are numbered from 1"),
    ] {
        let out = dir.join("refused");
        let o = condition_at(&raw, &out, &more);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{more:?} was accepted: {err}");
        assert!(err.contains(says), "{more:?}: {err}");
        assert!(
            !out.exists(),
            "{more:?} refused, yet {} was made",
            out.display()
        );
    }
    let out = dir.join("top");
    let o = condition_at(&raw, &out, &["--drive-v", "13.2", "--run", "1"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let pairs = std::fs::read_to_string(out.join("pairs.csv")).unwrap();
    let header: Vec<&str> = pairs.lines().next().unwrap().split(',').collect();
    let k = header.iter().position(|c| *c == "drive_v").unwrap();
    let rows = csv_rows(&out.join("pairs.csv"));
    assert_eq!(rows.len(), 12);
    assert!(rows.iter().all(|r| r[k] == "13.2"), "{rows:?}");
    // −0 V is the bottom of the drive, recorded as 0 (a cell "-0" read as a sign error).
    let out = dir.join("zero");
    let o = condition_at(&raw, &out, &["--drive-v", "-0", "--run", "1"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows = csv_rows(&out.join("pairs.csv"));
    assert!(rows.iter().all(|r| r[k] == "0"), "{rows:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A wrong `--first-change-s` puts a change inside every window: each level is reported as
/// mixing two, none gives a pair, and the command fails (it said "ok" to all twelve before).
#[test]
fn a_wrong_first_change_is_caught_in_every_window() {
    let dir = tmp("wrong-first");
    let (_, raw) = simulate(&dir, "monotone");
    let export = dir.join("run1.txt");
    std::fs::write(&export, logger_pro_export(&raw, 5)).unwrap();
    let out = dir.join("late");
    let o = condition_at(
        &export,
        &out,
        &["--first-change-s", "15.5", "--dwell-s", "10"],
    );
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{stderr}");
    let lv = levels(&out);
    assert_eq!(lv.len(), 12);
    assert!(
        lv.iter()
            .all(|l| l.6.contains("mixed: the tensions change inside")),
        "{lv:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Two runs logged at once, the rows sorted by time so that the `run` column alternates: two
/// runs of twelve levels (it made one run of every row before: 26,202 runs).
#[test]
fn interleaved_runs_in_time_order_stay_two_runs() {
    let dir = tmp("interleaved");
    let runs = simulate_runs(&dir, "monotone", 2, &[]);
    let mut rows: Vec<(f64, u32, f64, f64)> = Vec::new();
    for (k, (_, raw)) in runs.iter().enumerate() {
        // The second run's samples half a sample later on the shared clock.
        rows.extend(
            raw.iter()
                .map(|r| (r.0 + 0.005 * k as f64, k as u32 + 1, r.1, r.2)),
        );
    }
    rows.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut text = String::from("time_s,run,t1_n,t2_n\n");
    for r in &rows {
        text += &format!("{:.3},{},{},{}\n", r.0, r.1, r.2, r.3);
    }
    let file = dir.join("both.csv");
    std::fs::write(&file, text).unwrap();
    let out = dir.join("pairs");
    let o = condition_at(&file, &out, &[]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    let lv = levels(&out);
    assert_eq!(lv.len(), 24, "{stderr}");
    for (k, (fw, _)) in runs.iter().enumerate() {
        let mine: Vec<_> = csv_rows(&out.join("levels.csv"))
            .into_iter()
            .filter(|r| r[0] == (k + 1).to_string())
            .collect();
        assert_eq!(mine.len(), 12);
        for (r, (step, t1, _)) in mine.iter().zip(fw) {
            let got: f64 = r[7].parse().unwrap();
            assert!(
                (got - t1).abs() < 0.01,
                "run {} step {step}: {got} against {t1}",
                k + 1
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Times in milliseconds under a header that says seconds: named, with the unit to give.
#[test]
fn a_time_in_milliseconds_read_as_seconds_is_named() {
    let dir = tmp("ms-as-s");
    let f = dir.join("daq.csv");
    let mut s = String::from("Time (s),T1 (N),T2 (N)\n");
    for i in 0..4200 {
        let t_ms = i as f64 * 1000.0 / 30.0;
        let k = ((t_ms / 1000.0 - 0.5) / 10.0).floor();
        let level = if (1.0..=12.0).contains(&k) { k } else { 0.0 };
        s += &format!("{t_ms:.1},{:.4},{:.4}\n", 0.5 * level, 1.0 * level);
    }
    std::fs::write(&f, s).unwrap();
    let out = dir.join("out");
    let o = condition_at(&f, &out, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert!(
        err.contains("33.3") && err.contains("s apart") && err.contains("`Time (ms)`"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
