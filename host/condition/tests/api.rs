//! The library as a caller meets it: a file conditioned into the pairs a physicist would
//! compute by hand from the firmware's windows, and every refusal a typed error that says
//! where (file, line, column) and what to give. (`capstan condition` through the binary is
//! tested in the root `tests/`.)

use capstan_condition::{condition_file, output, Error, ReadOptions, Request, Settings};
use std::path::{Path, PathBuf};

/// A fresh file `capstan-condition-api-PID-NAME` in the system's temp directory.
fn file(name: &str, text: &str) -> PathBuf {
    let p = std::env::temp_dir().join(format!(
        "capstan-condition-api-{}-{name}",
        std::process::id()
    ));
    std::fs::write(&p, text).unwrap();
    p
}

/// The thesis protocol as a noiseless staircase at 50 Hz: rest until 10.5 s, then level k
/// (1..=12) for 10 s with T1 = 1.5·k + 0.3 N and T2 = 3·k + 0.3 N, then rest until 140 s.
/// `time_scale` writes the time in another unit (1000: milliseconds under an `s` header).
fn staircase(time_scale: f64) -> String {
    let mut s = String::from("time_s,t1_n,t2_n\n");
    for i in 0..7000 {
        let t = i as f64 / 50.0;
        let k = ((t - 10.5) / 10.0).floor() + 1.0;
        let level = if (1.0..=12.0).contains(&k) { k } else { 0.0 };
        s += &format!(
            "{},{},{}\n",
            t * time_scale,
            1.5 * level + 0.3,
            3.0 * level + 0.3
        );
    }
    s
}

/// What `capstan condition --wrap-deg 360` asks for: every other setting the firmware's.
fn request() -> Request {
    Request {
        first_change_s: None,
        dwell_s: None,
        trigger: false,
        levels: None,
        min_dwell_s: 3.0,
        window_after_ms: None,
        window_before_ms: None,
        wrap_deg: 360.0,
        diameter_mm: None,
        drive_v: None,
        first_run: 1,
    }
}

fn settings() -> Settings {
    Settings::from_request(&request()).unwrap()
}

#[test]
fn a_staircase_gives_each_levels_tensions_at_the_middle_of_its_window() {
    let path = file("staircase.csv", &staircase(1.0));
    let c = condition_file(&path, &ReadOptions::default(), &settings()).unwrap();
    let _ = std::fs::remove_file(&path);
    assert_eq!(c.not_found(), 0, "{:?}", c.runs[0].problems);
    assert_eq!(c.pairs.len(), 12);
    for (k, p) in c.pairs.iter().enumerate() {
        let level = (k + 1) as f64;
        assert!((p.t1_n - (1.5 * level + 0.3)).abs() < 1e-9, "{p:?}");
        assert!((p.t2_n - (3.0 * level + 0.3)).abs() < 1e-9, "{p:?}");
        // The firmware's window: 2 s after the change at 10.5 + 10·(k-1) s to 1 s before the
        // next, whose middle is 5.5 s after the change (within a sample, 20 ms).
        let mid = 10.5 + 10.0 * k as f64 + 5.5;
        assert!((p.time_s.unwrap() - mid).abs() <= 0.02, "{p:?}");
        assert_eq!(p.wrap_deg, 360.0);
        assert_eq!(p.step, Some(level));
    }
    // 7 s of 50 Hz samples in each window.
    assert!(c.runs[0]
        .levels
        .iter()
        .all(|l| (349..=351).contains(&l.samples)));
    let csv = output::levels_csv(&c.runs);
    assert_eq!(csv.lines().count(), 13, "a header and one line a level");
    assert!(csv.starts_with(output::LEVELS_HEADER));
}

#[test]
fn a_bad_cell_is_an_error_at_its_line_and_column() {
    // Line 1 is the header; 2 s is the 101st sample: line 102, at rest.
    let text: String = staircase(1.0)
        .lines()
        .enumerate()
        .map(|(i, l)| match i + 1 {
            102 => "2,0.3,abc\n".to_string(),
            _ => format!("{l}\n"),
        })
        .collect();
    let path = file("bad-cell.csv", &text);
    let e = condition_file(&path, &ReadOptions::default(), &settings()).unwrap_err();
    let _ = std::fs::remove_file(&path);
    let Error::Cell { place, column, why } = &e else {
        panic!("not a cell error: {e:?}");
    };
    assert_eq!((place.line, place.column), (Some(102), Some(3)));
    assert_eq!(column, "t2_n");
    assert_eq!(why, "`abc` is not a number");
    assert_eq!(
        e.to_string(),
        format!(
            "{}:102:3: column `t2_n`: `abc` is not a number",
            path.display()
        )
    );
}

#[test]
fn a_time_in_milliseconds_under_a_seconds_header_is_refused_as_too_sparse() {
    let path = file("ms.csv", &staircase(1000.0));
    let e = condition_file(&path, &ReadOptions::default(), &settings()).unwrap_err();
    let _ = std::fs::remove_file(&path);
    let Error::Sparse {
        place,
        median_s,
        span_h,
        ..
    } = &e
    else {
        panic!("not a sampling error: {e:?}");
    };
    // 50 Hz in milliseconds: 20 "s" apart, 139.98 "ks" = 38.9 "h".
    assert!((median_s - 20.0).abs() < 1e-6, "{median_s}");
    assert!((span_h - 139_980.0 / 3600.0).abs() < 1e-6, "{span_h}");
    assert_eq!(place.line, Some(2), "the run's first sample");
    assert!(
        e.to_string().contains("is the time in milliseconds?"),
        "{e}"
    );
}

#[test]
fn options_that_cannot_hold_are_typed_errors_naming_the_option() {
    let flag = |r: Request| match Settings::from_request(&r) {
        Err(Error::Option { flag, message }) => (flag, message),
        other => panic!("not an option error: {other:?}"),
    };
    let (f, m) = flag(Request {
        dwell_s: Some(10.0),
        ..request()
    });
    assert_eq!(f, "--dwell-s");
    assert_eq!(m, "--dwell-s needs --first-change-s (or --trigger-column)");
    let (f, m) = flag(Request {
        wrap_deg: 0.0,
        ..request()
    });
    assert_eq!(f, "--wrap-deg");
    assert!(m.starts_with("--wrap-deg 0: must be greater than 0"), "{m}");
    let (f, _) = flag(Request {
        first_change_s: Some(10.5),
        dwell_s: Some(-1.0),
        ..request()
    });
    assert_eq!(f, "--dwell-s");
    let e = condition_file(
        Path::new("no/such/file.csv"),
        &ReadOptions::default(),
        &settings(),
    )
    .unwrap_err();
    assert!(matches!(e, Error::Read { .. }), "{e:?}");
}

#[test]
fn a_trigger_that_never_rises_is_a_problem_of_its_run_never_a_silent_empty_result() {
    let text = staircase(1.0).replace("time_s,t1_n,t2_n\n", "time_s,t1_n,t2_n,trig\n");
    let text: String = text
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if i == 0 {
                format!("{l}\n")
            } else {
                format!("{l},0\n")
            }
        })
        .collect();
    let path = file("flat-trigger.csv", &text);
    let mut opts = ReadOptions::default();
    opts.columns.trigger = Some("trig".into());
    let set = Settings::from_request(&Request {
        trigger: true,
        ..request()
    })
    .unwrap();
    let c = condition_file(&path, &opts, &set).unwrap();
    let _ = std::fs::remove_file(&path);
    assert!(c.pairs.is_empty());
    assert_eq!(c.runs[0].problems, ["the trigger column never rises"]);
    assert_eq!(c.not_found(), 1);
}
