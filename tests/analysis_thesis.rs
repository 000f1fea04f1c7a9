//! `capstan analyze` on the bundled thesis data: the reference numbers, the targets, and the
//! outputs (one analysis run shared by all tests of this file).

use capstan::cli::{analyze, run, Cli, Command};
use capstan_data::thesis_dataset;
use capstan_engine::analysis::{self, Analysis};
use std::path::PathBuf;
use std::sync::OnceLock;

fn analysis() -> &'static Analysis {
    static A: OnceLock<Analysis> = OnceLock::new();
    A.get_or_init(|| analysis::run(&thesis_dataset(), analysis::Options::default()).unwrap())
}

/// The CLI's outputs for the bundled data, written once.
fn outputs() -> &'static PathBuf {
    static OUT: OnceLock<PathBuf> = OnceLock::new();
    OUT.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("capstan-analyze-test-{}", std::process::id()));
        run(Cli {
            command: Command::Analyze(analyze::Args {
                input: capstan::cli::input::DataArgs { data: None },
                out: dir.clone(),
                json: false,
                timing: capstan::cli::input::TimingArgs {
                    protocol_times: false,
                },
                threads: None,
                validate: false,
                seed: 0,
                figures: None,
                width_mm: 170.0,
                font_pt: 8.0,
                figure_numbers: false,
                thesis_comparison: false,
                plan: false,
            }),
        })
        .unwrap();
        dir
    })
}

fn model<'a>(a: &'a Analysis, name: &str) -> &'a analysis::ModelMetrics {
    a.models.iter().find(|m| m.name == name).unwrap()
}

#[test]
fn thesis_table3_r2_per_angle_is_reproduced() {
    // Independent reference (Python, pooled over diameters): 0.564, 0.676, −0.177, 0.629, 0.347.
    // The thesis reports "negative up to 0.687".
    let want = [
        (270.0, 0.564),
        (360.0, 0.676),
        (450.0, -0.177),
        (630.0, 0.629),
        (720.0, 0.347),
    ];
    let got = &analysis().thesis_per_angle_r2;
    assert_eq!(got.len(), 5);
    for (g, (w, r2)) in got.iter().zip(want) {
        assert_eq!(g.wrap_deg, w);
        assert!((g.r2 - r2).abs() < 1e-3, "{w}: {} vs {r2}", g.r2);
    }
    let max = got.iter().map(|g| g.r2).fold(f64::MIN, f64::max);
    let min = got.iter().map(|g| g.r2).fold(f64::MAX, f64::min);
    assert!(min < 0.0 && (0.66..=0.69).contains(&max), "{min} {max}");
}

#[test]
fn golden_numbers_match_the_independent_reference() {
    let a = analysis();
    let b = model(a, "baseline");
    let mu = a.baseline_fit.model(None).law.mu;
    assert!((mu - 0.1162).abs() < 1e-4, "mu {mu}");
    assert!((b.rmse_t2_n - 1.718).abs() < 1e-3, "{}", b.rmse_t2_n);
    assert!((b.loco_rmse_t2_n.unwrap() - 1.786).abs() < 2e-3);
    assert!((b.aic - 781.4).abs() < 0.2 && (b.bic - 786.0).abs() < 0.2);
    let t = model(a, "thesis");
    assert!((t.rmse_t2_n - 1.081).abs() < 1e-3, "{}", t.rmse_t2_n);
    assert_eq!(t.n_params, 25.0);
    assert!(t.loco_rmse_t2_n.is_none());
    let pc = model(a, "baseline_per_cord");
    assert!((pc.rmse_t2_n - 1.542).abs() < 1e-3);
}

#[test]
fn extended_model_is_counted_straight_and_meets_the_in_sample_target() {
    let a = analysis();
    let e = model(a, "extended");
    // The count is fixed values + the cord effects' effective dof, within the budget.
    let d = &e.n_params_detail;
    assert!((e.n_params - (d.fixed as f64 + d.edf_random)).abs() < 1e-9);
    assert!(e.n_params <= 12.0 + 1e-9, "{}", e.n_params);
    assert!(e.rmse_t2_n <= 0.80, "in-sample {}", e.rmse_t2_n);
    // Leave-one-cord-out: the 1.30 N is not reached (docs/README-analysis.md says so);
    // this guards the figure the README quotes.
    let loco = e.loco_rmse_t2_n.unwrap();
    assert!(loco <= 1.45, "LOCO {loco}");
    // Every RMSE carries its cord-bootstrap interval around it.
    for m in &a.models {
        let u = &m.rmse_t2_uncertainty;
        assert!(
            u.ci95.lo < m.rmse_t2_n && m.rmse_t2_n < u.ci95.hi,
            "{}",
            m.name
        );
        assert!(u.jackknife_se > 0.0, "{}", m.name);
    }
    // The held-out gain has its interval, and every cord its held-out error.
    assert!(a.gain.ci95.lo < a.gain.value && a.gain.value < a.gain.ci95.hi);
    assert_eq!(a.held_out.len(), 10);
}

#[test]
fn named_causes_are_the_evidence_engines() {
    let a = analysis();
    let m = &a.mechanisms;
    let causes: Vec<&str> = m.causes.iter().map(|c| c.name).collect();
    let engine: Vec<&str> = a.evidence.effects.iter().map(|e| e.effect).collect();
    assert_eq!(causes, engine);
    // The same as `capstan diagnose` on the same data.
    let d = capstan_engine::diagnose::diagnose(&thesis_dataset());
    let diag: Vec<&str> = d.effects.iter().map(|e| e.effect).collect();
    assert_eq!(causes, diag);
    assert!(causes.contains(&"contact_heating"), "{causes:?}");
    // Every catalogue effect is a mechanism with a verdict, and a ruled-in one is a cause.
    assert_eq!(m.tests.len(), capstan_physics::EffectKind::ALL.len() - 1);
    for t in &m.tests {
        assert_eq!(
            t.verdict == capstan_engine::verdict::Verdict::RuledIn,
            causes.contains(&t.name),
            "{}",
            t.name
        );
    }
    // Parameter uncertainties: cluster-robust, NaN with the reason when not identified.
    for v in &a.extended.values {
        assert!(
            v.jackknife_se > 0.0 || (v.jackknife_se.is_nan() && !v.note.is_empty()),
            "{v:?}"
        );
    }
}

fn csv_column(csv: &str, name: &str) -> Vec<f64> {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let k = header
        .iter()
        .position(|h| *h == name)
        .unwrap_or_else(|| panic!("no {name}"));
    lines
        .map(|l| l.split(',').nth(k).unwrap().parse().unwrap())
        .collect()
}

#[test]
fn predictions_csv_recomputes_the_metrics() {
    let dir = outputs();
    let csv = std::fs::read_to_string(dir.join("predictions.csv")).unwrap();
    let metrics: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("metrics.json")).unwrap()).unwrap();
    let t1 = csv_column(&csv, "t1_n");
    let t2 = csv_column(&csv, "t2_n");
    assert_eq!(t2.len(), 720);
    let rmse =
        |p: &[f64]| (p.iter().zip(&t2).map(|(p, m)| (p - m).powi(2)).sum::<f64>() / 720.0).sqrt();
    let models = metrics["models"].as_array().unwrap();
    let get = |n: &str| models.iter().find(|m| m["name"] == n).unwrap();
    for (name, col, loco) in [
        ("baseline", "t2_baseline_n", Some("t2_baseline_loco_n")),
        ("thesis", "t2_thesis_n", None),
        ("extended", "t2_extended_n", Some("t2_extended_loco_n")),
    ] {
        let m = get(name);
        let p = csv_column(&csv, col);
        assert!(
            (rmse(&p) - m["rmse_t2_n"].as_f64().unwrap()).abs() < 1e-9,
            "{name}"
        );
        // Over the rows where the predicted T2 is above zero (no logarithm otherwise); the
        // others are counted apart.
        let defined: Vec<f64> = (p.iter().zip(&t2).zip(&t1))
            .filter(|((p, m), t1)| **p > 0.0 && **m > 0.0 && **t1 > 0.0)
            .map(|((p, m), t1)| ((p / t1).ln() - (m / t1).ln()).powi(2))
            .collect();
        let ln = (defined.iter().sum::<f64>() / defined.len() as f64).sqrt();
        assert!(
            (ln - m["rmse_ln_amp"].as_f64().unwrap()).abs() < 1e-9,
            "{name} ln"
        );
        let left_out = p.iter().filter(|p| **p <= 0.0).count();
        assert_eq!(
            m["ln_amp_undefined_rows"].as_u64().unwrap() as usize,
            left_out,
            "{name}"
        );
        match loco {
            Some(c) => assert!(
                (rmse(&csv_column(&csv, c)) - m["loco_rmse_t2_n"].as_f64().unwrap()).abs() < 1e-9
            ),
            None => assert!(m["loco_rmse_t2_n"].is_null()),
        }
        for k in ["n_params", "aic", "bic", "per_cord_r2_amp"] {
            assert!(!m[k].is_null(), "{name}.{k}");
        }
    }
    assert_eq!(
        metrics["causes"].as_array().unwrap().len(),
        metrics["evidence"]["effects"].as_array().unwrap().len()
    );
    assert!(metrics["elapsed_s"]["total_s"].as_f64().unwrap() > 0.0);
}

#[test]
fn report_has_an_svg_for_every_figure() {
    let html = std::fs::read_to_string(outputs().join("report.html")).unwrap();
    let figures = html.matches("<figure class=\"plot\"").count();
    assert!(figures >= 5, "{figures} figures");
    for part in html.split("<figure class=\"plot\"").skip(1) {
        let body = &part[..part.find("</figure>").unwrap()];
        assert!(
            body.contains("<svg") && body.contains("</svg>"),
            "figure without svg"
        );
        assert!(body.contains("class=\"mark"), "figure without data marks");
    }
    assert!(
        !html.contains("src=\"http"),
        "the report must be self-contained"
    );
}

fn figure_body<'a>(html: &'a str, id: &str) -> &'a str {
    let start = html
        .find(&format!("data-figure=\"{id}\""))
        .unwrap_or_else(|| panic!("no figure {id}"));
    &html[start..start + html[start..].find("</figure>").unwrap()]
}

#[test]
fn figures_have_one_colour_per_wrap_and_a_style_per_model() {
    let html = std::fs::read_to_string(outputs().join("report.html")).unwrap();
    // Okabe-Ito, one colour per wrap, the same in every per-wrap figure.
    let wrap_colours = ["#0072B2", "#E69F00", "#009E73", "#D55E00", "#CC79A7"];
    for id in ["t2_vs_t1", "amp_vs_t1", "residuals", "closed_loop"] {
        let body = figure_body(&html, id);
        for (c, w) in wrap_colours.iter().zip(["270", "360", "450", "630", "720"]) {
            assert!(body.contains(c), "{id}: no {c}");
            assert!(
                body.contains(&format!("{w}° wrap")),
                "{id}: no legend for {w}°"
            );
        }
    }
    // Three models, three line styles, named in the legend.
    for id in ["t2_vs_t1", "amp_vs_t1"] {
        let body = figure_body(&html, id);
        for (style, label) in [
            ("stroke-dasharray=\"7 4\"", "Euler-Eytelwein"),
            ("stroke-dasharray=\"0.1 4.5\"", "thesis Table 3"),
            ("stroke-width=\"3\"", "extended model"),
        ] {
            assert!(
                body.contains(style) && body.contains(label),
                "{id}: {label}"
            );
        }
    }
    // The gain is a grouped bar chart by model, named in words; Table 3 has no LOCO bar.
    // No-break spaces keep "one mu" together when a name wraps: read them as spaces.
    let gain = figure_body(&html, "gain")
        .replace('\u{a0}', " ")
        .replace("&#160;", " ")
        .replace("&nbsp;", " ");
    assert_eq!(
        gain.matches("class=\"mark bar\"").count(),
        7,
        "4 in-sample + 3 LOCO bars"
    );
    // (A name may wrap onto two lines at a narrow width; at 170 mm each is one line.)
    for name in [
        "Euler-Eytelwein, one mu",
        "Euler-Eytelwein, a mu per cord",
        "thesis Table 3",
        "extended model",
        "not refittable",
    ] {
        assert!(gain.contains(&format!(">{name}<")), "gain: {name}");
    }
    // No identifier on a figure: the mechanisms by the catalogue's words.
    let evidence = figure_body(&html, "mechanism_evidence");
    for (id, words) in [
        ("t2_offset", "T2 offset"),
        ("contact_heating", "contact heating"),
    ] {
        assert!(!evidence.contains(&format!(">{id}<")), "{id} on the figure");
        assert!(evidence.contains(&format!(">{words}<")), "{words}");
    }
    assert!(!gain.contains(">baseline_per_cord<"));
}

#[test]
fn every_verdict_sentence_is_made_from_its_verdict() {
    let dir = outputs();
    let metrics: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("metrics.json")).unwrap()).unwrap();
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    analysis_support::check(&metrics, &html);
}

mod analysis_support;
