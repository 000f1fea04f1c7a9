//! `capstan predict` against data it did not see: leave one wrap out of the thesis data,
//! analyse the rest, predict the held-out wrap's T2 as measured at its measured T1 values.
//! The 95 % prediction interval (a new cord's error from the analysis's own held-out cords,
//! and beyond the fitted wraps the error of extrapolating in wrap) must cover at least 85 % of
//! all the held-out measured T2, and of each wrap's inside the fitted wrap range. Every wrap's
//! figure is reported, with and without the extrapolation error, and per cord. A wrap beyond
//! the fitted span is two draws of a new cord and is reported, not asserted: no factor widens
//! the interval to cover one. The point prediction, pooled over the held-out wraps, must beat
//! Euler-Eytelwein with one mu fitted to the same rows.
//!
//! And leave one *cord* out (what a new cord is): the interval must cover ≥ 92 % of the 720
//! thesis rows and ≥ 65 % of every cord's (`new_cords_are_covered`; the figures printed by
//! `cargo run --release -p capstan-engine --example coverage`).

use capstan_engine::analysis::prediction::{predict, PredictionModel, Query};
use capstan_engine::analysis::{self, Options};

/// The thesis CSV without the rows of `wrap_deg`.
fn without_wrap(wrap_deg: f64) -> capstan_data::Dataset {
    let mut lines = capstan_data::THESIS_CSV.lines();
    let header = lines.next().unwrap();
    let col = header.split(',').position(|c| c == "wrap_deg").unwrap();
    let kept: Vec<&str> = lines
        .filter(|l| l.split(',').nth(col).and_then(|v| v.parse::<f64>().ok()) != Some(wrap_deg))
        .collect();
    let text = format!("{header}\n{}\n", kept.join("\n"));
    capstan_data::read_pairs(text.as_bytes(), "thesis without one wrap").unwrap()
}

struct Held {
    wrap: f64,
    coverage: f64,
    /// Coverage without the extrapolation term.
    coverage_without: f64,
    /// Mean width of the 95 % PI, N, with and without the extrapolation term.
    width: f64,
    width_without: f64,
    /// A new cord's error the analysis without this wrap estimated: a (N), b.
    new_cord_error: (f64, f64),
    /// Its error of extrapolating in wrap, N (in the interval only beyond the fitted wraps).
    wrap_error_sd_n: f64,
    /// The held-out residual RMS behind it, N.
    heldout_rms: f64,
    rmse_model: f64,
    rmse_ee: f64,
    /// Per cord (capstan diameter, mm): rows inside the PI, rows.
    per_cord: Vec<(f64, usize, usize)>,
    extrapolating: bool,
    why: Vec<String>,
}

fn hold_out(wrap: f64, dir: &std::path::Path) -> Held {
    let a = analysis::run(&without_wrap(wrap), Options::default()).unwrap();
    let ctx = capstan_report::Context::library();
    let m = serde_json::to_value(capstan_report::Metrics::new(&a, None, &ctx)).unwrap();
    let path = dir.join(format!("metrics-{wrap}.json"));
    std::fs::write(&path, serde_json::to_string(&m).unwrap()).unwrap();
    let pm = load_model(&path).unwrap();
    let mut pm0 = pm.clone();
    pm0.wrap_extrapolation_error.sd_n = 0.0;
    let mu_ee = a.baseline_fit.model(None).law.mu;
    let test = capstan_data::thesis_dataset();
    let (mut inside, mut n, mut se_m, mut se_ee) = (0usize, 0usize, 0.0, 0.0);
    let (mut inside0, mut width, mut width0) = (0usize, 0.0, 0.0);
    let mut why: Vec<String> = Vec::new();
    let mut per_cord: Vec<(f64, usize, usize)> = Vec::new();
    for p in test
        .pairs
        .iter()
        .filter(|p| p.wrap_deg == wrap && p.t1_n > 0.0)
    {
        let q = Query {
            wrap_deg: wrap,
            diameter_mm: p.capstan_diameter_mm.unwrap(),
            drive_v: p.drive_v.unwrap_or(10.0),
            t1_n: p.t1_n,
            as_measured: true,
        };
        for w in pm.extrapolates(&q) {
            let kind = w.split(' ').next().unwrap_or("").to_string();
            if !why.contains(&kind) {
                why.push(kind);
            }
        }
        let r = predict(&pm, &q);
        let r0 = predict(&pm0, &q);
        n += 1;
        let hit = r.t2_pi95.lo <= p.t2_n && p.t2_n <= r.t2_pi95.hi;
        inside += usize::from(hit);
        match per_cord.iter_mut().find(|c| c.0 == q.diameter_mm) {
            Some(c) => {
                c.1 += usize::from(hit);
                c.2 += 1;
            }
            None => per_cord.push((q.diameter_mm, usize::from(hit), 1)),
        }
        inside0 += usize::from(r0.t2_pi95.lo <= p.t2_n && p.t2_n <= r0.t2_pi95.hi);
        width += r.t2_pi95.hi - r.t2_pi95.lo;
        width0 += r0.t2_pi95.hi - r0.t2_pi95.lo;
        se_m += (r.t2_n - p.t2_n).powi(2);
        se_ee += (p.t1_n * (mu_ee * wrap.to_radians()).exp() - p.t2_n).powi(2);
    }
    Held {
        wrap,
        coverage: inside as f64 / n as f64,
        coverage_without: inside0 as f64 / n as f64,
        width: width / n as f64,
        width_without: width0 / n as f64,
        new_cord_error: (pm.new_cord_error.abs_n, pm.new_cord_error.rel),
        wrap_error_sd_n: pm.wrap_extrapolation_error.sd_n,
        heldout_rms: pm.new_cord_error.heldout_rms_n,
        rmse_model: (se_m / n as f64).sqrt(),
        rmse_ee: (se_ee / n as f64).sqrt(),
        per_cord,
        extrapolating: !why.is_empty(),
        why,
    }
}

#[test]
fn leave_one_wrap_out_prediction_intervals_cover_and_the_model_beats_euler_eytelwein() {
    let dir = std::env::temp_dir().join(format!("capstan-lowo-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let wraps = capstan_engine::fit::stats::distinct(
        capstan_data::thesis_dataset()
            .pairs
            .iter()
            .map(|p| p.wrap_deg),
    );
    let held: Vec<Held> = wraps.iter().map(|w| hold_out(*w, &dir)).collect();
    for h in &held {
        eprintln!(
            "held-out {:.0}°: 95 % PI covers {:.1} % of measured T2 ({:.1} % without the wrap extrapolation error, SD {:.3} N; a new cord's SD √({:.3}² + ({:.4}·T2)²) N from held-out RMS {:.3} N), mean PI width {:.2} N ({:.2} N without); RMSE model {:.3} N vs Euler-Eytelwein {:.3} N{}",
            h.wrap,
            100.0 * h.coverage,
            100.0 * h.coverage_without,
            h.wrap_error_sd_n,
            h.new_cord_error.0,
            h.new_cord_error.1,
            h.heldout_rms,
            h.width,
            h.width_without,
            h.rmse_model,
            h.rmse_ee,
            if h.extrapolating { format!(" (extrapolating in {})", h.why.join(", ")) } else { String::new() }
        );
    }
    for h in &held {
        let cords: Vec<String> = h
            .per_cord
            .iter()
            .map(|c| format!("{} mm {}/{}", c.0, c.1, c.2))
            .collect();
        eprintln!(
            "  {:.0}° per cord, inside the PI: {}",
            h.wrap,
            cords.join(", ")
        );
    }
    // Over every held-out measurement the interval must cover ≥ 85 % (the figure).
    let (inside, rows) = held
        .iter()
        .flat_map(|h| &h.per_cord)
        .fold((0, 0), |s, c| (s.0 + c.1, s.1 + c.2));
    let pooled = inside as f64 / rows as f64;
    eprintln!(
        "pooled over the held-out wraps: {inside}/{rows} = {:.1} %",
        100.0 * pooled
    );
    assert!(pooled >= 0.85, "pooled coverage {pooled:.3}");
    // Inside the fitted wraps it must hold wrap by wrap too; beyond them (270° and 720° held
    // out) each wrap's figure is reported, not asserted: there a wrap's two cords are two draws
    // of a new cord, and no fudge factor widens the interval to cover one that falls outside.
    for h in held.iter().filter(|h| !h.why.iter().any(|w| w == "wrap")) {
        assert!(
            h.coverage >= 0.85,
            "{:.0}°: coverage {:.3}",
            h.wrap,
            h.coverage
        );
    }
    let (m, ee): (f64, f64) = held.iter().fold((0.0, 0.0), |s, h| {
        (s.0 + h.rmse_model.powi(2), s.1 + h.rmse_ee.powi(2))
    });
    assert!(
        m < ee,
        "pooled RMSE model {:.3} vs Euler-Eytelwein {:.3}",
        m.sqrt(),
        ee.sqrt()
    );
}

/// A new cord, left out and predicted by the analysis of the others: the 95 % prediction
/// interval covers ≥ 92 % of the 720 thesis rows and ≥ 65 % of every cord's (measured on
/// 2026-11-28: 716/720 = 99.4 %, every cord ≥ 95.8 %, mean width 6.12 N).
#[test]
fn new_cords_are_covered() {
    let c = analysis::coverage::coverage(&capstan_data::thesis_dataset(), Options::default());
    for l in c.lines() {
        eprintln!("{l}");
    }
    assert!(c.failed.is_empty(), "{:?}", c.failed);
    assert_eq!(c.overall.rows, 720);
    assert!(c.overall.fraction() >= 0.92, "{:?}", c.overall);
    for cord in &c.per_cord {
        assert!(cord.fraction() >= 0.65, "{cord:?}");
    }
    // Not bought with an interval as wide as the data: under 8 N on average (T2 spans 1-50 N).
    assert!(c.overall.mean_width_n < 8.0, "{:?}", c.overall);
}

/// An edited or damaged model is refused by name, never turned into intervals that mean
/// nothing; the unedited one loads.
#[test]
fn an_edited_prediction_model_is_refused() {
    let dir = std::env::temp_dir().join(format!("capstan-edited-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let a = analysis::run(&capstan_data::thesis_dataset(), Options::default()).unwrap();
    let ctx = capstan_report::Context::library();
    let m = serde_json::to_value(capstan_report::Metrics::new(&a, None, &ctx)).unwrap();
    let write = |name: &str, v: &serde_json::Value| {
        let p = dir.join(name);
        std::fs::write(&p, serde_json::to_string(v).unwrap()).unwrap();
        p
    };
    assert!(load_model(&write("good.json", &m)).is_ok());
    type Edit = fn(&mut serde_json::Value);
    let edits: [(&str, Edit); 15] = [
        ("covariance", |v| {
            v["covariance"] = serde_json::json!([[1.0, 0.0], [0.0, 1.0]])
        }),
        ("negative variance", |v| {
            v["covariance"][0][0] = serde_json::json!(-1.0)
        }),
        ("mu", |v| v["values"]["mu"] = serde_json::json!(50.0)),
        ("a negative new-cord error", |v| {
            v["new_cord_error"]["abs_n"] = serde_json::json!(-1.0)
        }),
        ("folds", |v| v["folds"] = serde_json::json!(1)),
        ("free", |v| {
            v["free"][0] = serde_json::json!("no_such_parameter")
        }),
        ("schema 1 (no model error)", |v| {
            v["schema"] = serde_json::json!(1)
        }),
        ("a new-cord error without rows", |v| {
            v["new_cord_error"]["rows"] = serde_json::json!(0)
        }),
        ("a new-cord error with no degrees of freedom", |v| {
            v["new_cord_error"]["dof"] = serde_json::json!(0)
        }),
        ("a new-cord error not a number", |v| {
            v["new_cord_error"]["rel"] = serde_json::json!("wide")
        }),
        ("schema 3 (the mixed model's variance components)", |v| {
            v["schema"] = serde_json::json!(3)
        }),
        ("wrap extrapolation error beyond its residuals", |v| {
            v["wrap_extrapolation_error"]["sd_n"] = serde_json::json!(1e3)
        }),
        ("wrap extrapolation error with an SD and no rows", |v| {
            v["wrap_extrapolation_error"]["rows"] = serde_json::json!(0)
        }),
        ("schema 2 (no wrap extrapolation error)", |v| {
            v["schema"] = serde_json::json!(2)
        }),
        ("range", |v| {
            v["fitted_range"]["wrap_deg"] = serde_json::json!({"min": 900.0, "max": 100.0})
        }),
    ];
    for (what, edit) in edits {
        let mut bad = m.clone();
        edit(&mut bad["prediction_model"]);
        let err = load_model(&write("bad.json", &bad)).err();
        assert!(err.is_some(), "an edited {what} was accepted");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// With two fitted wraps nothing measured what extrapolating in wrap costs: the model says
/// so (no rows, no distance), `predict`'s scale is `None` beyond the span (never a fake 0),
/// and inside the span the term is 0.
#[test]
fn two_wraps_give_no_measured_extrapolation_error() {
    let mut lines = capstan_data::THESIS_CSV.lines();
    let header = lines.next().unwrap();
    let col = header.split(',').position(|c| c == "wrap_deg").unwrap();
    let kept: Vec<&str> = lines
        .filter(|l| {
            let w = l.split(',').nth(col).and_then(|v| v.parse::<f64>().ok());
            w == Some(360.0) || w == Some(450.0)
        })
        .collect();
    let text = format!("{header}\n{}\n", kept.join("\n"));
    let ds = capstan_data::read_pairs(text.as_bytes(), "two wraps").unwrap();
    let a = analysis::run(&ds, Options::default()).unwrap();
    let ctx = capstan_report::Context::library();
    let m = serde_json::to_value(capstan_report::Metrics::new(&a, None, &ctx)).unwrap();
    let dir = std::env::temp_dir().join(format!("capstan-two-wraps-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("metrics.json");
    std::fs::write(&path, serde_json::to_string(&m).unwrap()).unwrap();
    let pm = load_model(&path).unwrap();
    assert_eq!(pm.wrap_extrapolation_error.rows, 0);
    assert_eq!(pm.wrap_extrapolation_step_deg, 0.0);
    assert_eq!(pm.wrap_extrapolation_sd(720.0), None);
    assert_eq!(pm.wrap_extrapolation_sd(400.0), Some(0.0));
    let _ = std::fs::remove_dir_all(&dir);
}

/// The prediction model of the `metrics.json` at `path`, as `capstan predict` reads it.
fn load_model(path: &std::path::Path) -> Result<PredictionModel, capstan_report::MetricsError> {
    capstan_report::read_and_validate(path).map(|r| r.prediction_model)
}
