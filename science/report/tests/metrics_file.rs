//! `metrics.json` written and read back by the one crate that owns it: the model `capstan
//! predict` reads is the analysis's, and each way a file can be wrong is its own error, naming
//! the file.

use capstan_engine::analysis::{self, Options};
use capstan_report::metrics::ModelProblem;
use capstan_report::{read_and_validate, Metrics, MetricsError};
use serde_json::{json, Value};
use std::path::PathBuf;

fn write(dir: &std::path::Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn the_model_read_back_is_the_one_written_and_each_defect_is_named() {
    let dir = std::env::temp_dir().join(format!("capstan-metrics-file-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let a = analysis::run(&capstan_data::thesis_dataset(), Options::default()).unwrap();
    let ctx = capstan_report::Context::library();
    let text = Metrics::new(&a, None, &ctx).to_json().unwrap();
    let good = write(&dir, "metrics.json", &text);
    let read = read_and_validate(&good).unwrap();
    assert_eq!(
        serde_json::to_value(&read.prediction_model).unwrap(),
        serde_json::to_value(&a.prediction_model).unwrap()
    );
    // The one-mu Euler-Eytelwein fit, as the models table has it (thesis data: 0.116).
    let mu = read.euler_eytelwein_mu.unwrap();
    assert!(
        (mu - a.baseline_fit.model(None).law.mu).abs() < 1e-12,
        "{mu}"
    );
    assert!((0.11..0.12).contains(&mu), "{mu}");
    // The layout's version is in the file; its keys are sorted, as they always were.
    let v: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(
        v["schema_version"],
        json!(capstan_report::metrics::METRICS_SCHEMA)
    );
    let keys: Vec<&String> = v.as_object().unwrap().keys().collect();
    assert!(keys.windows(2).all(|w| w[0] < w[1]), "{keys:?}");
    assert!(text.find("\"causes\"").unwrap() < text.find("\"unexplained\"").unwrap());

    let schema = capstan_engine::analysis::prediction::SCHEMA as u64;
    let edited = |name: &str, edit: &dyn Fn(&mut Value)| {
        let mut w = v.clone();
        edit(&mut w);
        let p = write(&dir, name, &w.to_string());
        (read_and_validate(&p).unwrap_err(), p)
    };
    let cases: Vec<(MetricsError, PathBuf)> = vec![
        edited("newer.json", &|w| {
            w["prediction_model"]["schema"] = json!(schema + 1)
        }),
        edited("older.json", &|w| {
            w["prediction_model"]["schema"] = json!(schema - 1)
        }),
        edited("word.json", &|w| {
            w["prediction_model"]["schema"] = json!("4")
        }),
        edited("none.json", &|w| {
            w["prediction_model"]
                .as_object_mut()
                .unwrap()
                .remove("schema");
        }),
        edited("nomodel.json", &|w| {
            w.as_object_mut().unwrap().remove("prediction_model");
        }),
        edited("null.json", &|w| {
            w["prediction_model"]["new_cord_error"]["abs_n"] = Value::Null
        }),
        edited("mu.json", &|w| {
            w["prediction_model"]["values"]["mu"] = json!(3.0)
        }),
    ];
    let [newer, older, word, none, nomodel, null, mu] = &cases[..] else {
        unreachable!()
    };
    assert!(
        matches!(newer.0, MetricsError::SchemaNewer { found, reads, .. } if found == schema + 1 && reads == schema)
    );
    assert!(matches!(older.0, MetricsError::SchemaOlder { found, .. } if found == schema - 1));
    assert!(matches!(&word.0, MetricsError::SchemaNotNumber { found, .. } if found == "\"4\""));
    assert!(matches!(none.0, MetricsError::NoSchema { .. }));
    assert!(matches!(nomodel.0, MetricsError::NoPredictionModel { .. }));
    assert!(
        matches!(&null.0, MetricsError::Malformed { at: Some(f), .. } if f == "new_cord_error.abs_n"),
        "{}",
        null.0
    );
    assert!(
        matches!(mu.0, MetricsError::Invalid { problem: ModelProblem::Mu { mu }, .. } if mu == 3.0),
        "{}",
        mu.0
    );
    assert!(
        mu.0.to_string()
            .contains("mu 3 is not a friction coefficient"),
        "{}",
        mu.0
    );
    for (e, p) in &cases {
        assert!(e.to_string().starts_with(&p.display().to_string()), "{e}");
    }
    // The file's layout version: anything but the one written is its own error, typed with
    // what stands there (a file without a model is named as that first: layout 1 had none).
    let layout = capstan_report::metrics::METRICS_SCHEMA;
    for (found, json) in [
        (Some("1"), json!(1)),
        (Some("3"), json!(3)),
        (Some("\"x\""), json!("x")),
        (Some("null"), Value::Null),
        (Some("2.0"), json!(2.0)),
        (None, Value::Null),
    ] {
        let (e, p) = edited("layout.json", &|w| match found {
            Some(_) => w["schema_version"] = json.clone(),
            None => {
                w.as_object_mut().unwrap().remove("schema_version");
            }
        });
        assert!(
            matches!(&e, MetricsError::SchemaVersion { found: f, reads, .. }
                if f.as_deref() == found && *reads == layout),
            "{found:?}: {e}"
        );
        let said = e.to_string();
        assert!(said.starts_with(&format!("{}: ", p.display())), "{said}");
        assert!(
            said.contains("schema_version")
                && said.contains(&format!("this capstan reads {layout}"))
                || said.contains(&format!("this capstan reads ({layout})")),
            "{said}"
        );
    }
    let (e, _) = edited("layout-nomodel.json", &|w| {
        w.as_object_mut().unwrap().remove("prediction_model");
        w["schema_version"] = json!(1);
    });
    assert!(matches!(e, MetricsError::NoPredictionModel { .. }), "{e}");
    let bad = write(&dir, "bad.json", "{\n  \"schema_version\": 2,\n  oops\n}");
    let e = read_and_validate(&bad).unwrap_err();
    assert!(matches!(e, MetricsError::NotJson { line: 3, .. }), "{e}");
    assert!(
        e.to_string().starts_with(&format!("{}:3:", bad.display())),
        "{e}"
    );
    let e = read_and_validate(&dir.join("absent.json")).unwrap_err();
    assert!(matches!(e, MetricsError::Read { .. }), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}
