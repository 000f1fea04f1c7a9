//! The "discovered" part of the report and of `metrics.json`: what `capstan discover` proposes
//! beyond the catalogue (docs/README-discover.md), kept apart from the catalogue's causes and
//! never worded as an established cause, with the held-out RMSE with and without each term.
//! It takes the discovery as JSON (the crate does not depend on `capstan-discover`).

use crate::cells::esc;
use serde_json::{json, Value};
use std::fmt::Write as _;

/// The `discovered` object of `metrics.json` from `capstan discover`'s JSON.
pub fn discovered_json(d: &Value) -> Value {
    let terms: Vec<Value> = d["terms"]
        .as_array()
        .map(|ts| {
            ts.iter()
                .map(|t| {
                    json!({
                        "name": t["name"],
                        "status": "discovered (a candidate, not an established cause)",
                        "formula": t["formula"],
                        "acts_on": t["acts_on"],
                        "depends_on": t["depends_on"],
                        "parameters": t["parameters"],
                        "parameter_se": t["parameter_se"],
                        "delta_bic_given_others": t["delta_bic_given_others"],
                        "stability": t["stability"],
                        "held_out": {
                            "rmse_without_n": t["loco_rmse_ratio"]["rmse_without_n"],
                            "rmse_with_n": t["loco_rmse_ratio"]["rmse_with_n"],
                            "ratio": t["loco_rmse_ratio"]["value"],
                            "ci95": t["loco_rmse_ratio"]["ci95"],
                            "method": t["loco_rmse_ratio"]["method"],
                        },
                        "shown_to_predict_better": t["shown_to_predict_better"],
                        "partial": t["partial"],
                        "lack_of_fit_after": t["lack_of_fit_after"],
                        "rivals": t["rivals"],
                        "replicate_gate_not_applied": t["replicate_gate_not_applied"],
                    })
                })
                .collect()
        })
        .unwrap_or_default();
    json!({
        "terms": terms,
        "unexplained_after": d["unexplained_after"],
        "residual_pattern": d["residual_pattern"],
        "verdict": d["verdict"],
        "declined": d["declined"],
        "library_size": d["search"]["library_size"],
        "library_tried": d["search"]["tried"],
        "first_bar": d["search"]["first_bar"],
        "elapsed_s": d["elapsed_s"],
    })
}

/// The report's section.
pub fn discovered_html(d: &Value) -> String {
    let mut h = String::from("<h2>Beyond the catalogue: discovered</h2>");
    let _ = write!(
        h,
        "<p><code>capstan discover</code> searched {} of {} library terms (those these data can test) for what the catalogue leaves (bar ΔBIC &lt; {:.1}, the search paid for; stability over whole-cord resamples; held-out cords). {}</p>",
        d["search"]["tried"].as_u64().unwrap_or(0),
        d["search"]["library_size"].as_u64().unwrap_or(0),
        d["search"]["first_bar"].as_f64().unwrap_or(f64::NAN),
        esc(d["verdict"].as_str().unwrap_or(""))
    );
    if let Some(ts) = d["terms"].as_array().filter(|t| !t.is_empty()) {
        h.push_str("<table><tr><th>term (discovered, not an established cause)</th><th>acts on</th><th>depends on</th><th>held-out RMSE without → with (N)</th><th>ratio [95 %]</th><th>predicts new cords better</th><th>lack of fit after it</th><th>stability</th></tr>");
        for t in ts {
            let r = &t["loco_rmse_ratio"];
            let gate = match t["replicate_gate_not_applied"].as_str() {
                Some(why) => format!(" (without the replicate gate: {})", esc(why)),
                None => String::new(),
            };
            let f = |v: &Value| v.as_f64().map_or("-".into(), |x| format!("{x:.3}"));
            let _ = write!(
                h,
                "<tr><td>{}{gate}</td><td>{}</td><td>{}</td><td>{} → {}</td><td>{} [{}, {}]</td><td>{}</td><td>{}</td><td>{}</td></tr>",
                esc(t["name"].as_str().unwrap_or("")),
                esc(t["acts_on"].as_str().unwrap_or("")),
                esc(&words_of(&t["depends_on"])),
                f(&r["rmse_without_n"]),
                f(&r["rmse_with_n"]),
                f(&r["value"]),
                f(&r["ci95"]["lo"]),
                f(&r["ci95"]["hi"]),
                match t["shown_to_predict_better"].as_bool() {
                    Some(true) => "shown (upper end below 1)",
                    Some(false) => "not shown (interval reaches 1)",
                    None => "-",
                },
                esc(&lack_of_fit_words(t)),
                f(&t["stability"])
            );
        }
        h.push_str("</table>");
    }
    if let Some(x) = d["declined"].as_array().and_then(|v| v.first()) {
        let r = &x["loco_rmse_ratio"];
        let held = match (
            r["value"].as_f64(),
            r["ci95"]["lo"].as_f64(),
            r["ci95"]["hi"].as_f64(),
        ) {
            (Some(v), Some(lo), Some(hi)) => {
                format!(" Held-out RMSE ratio with it: {v:.3} [{lo:.3}, {hi:.3}].")
            }
            _ => String::new(),
        };
        let _ = write!(
            h,
            "<p>The strongest candidate not proposed: <code>{}</code> (ΔBIC {:.1}): {}.{held}</p>",
            esc(x["name"].as_str().unwrap_or("")),
            x["delta_bic"].as_f64().unwrap_or(f64::NAN),
            esc(x["reason"].as_str().unwrap_or(""))
        );
    }
    h
}

/// A JSON list of names as words ("t1, diameter").
fn words_of(v: &Value) -> String {
    v.as_array().map_or(String::new(), |xs| {
        xs.iter()
            .filter_map(|x| x.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    })
}

/// A term's lack of fit against the replicate runs with it in, and whether it is partial.
fn lack_of_fit_words(t: &Value) -> String {
    let l = &t["lack_of_fit_after"];
    match (l["p"].as_f64(), t["partial"].as_bool()) {
        (Some(p), Some(true)) => {
            format!("partial: structure still left (p = {p:.3}); explains most, not all")
        }
        (Some(p), _) if p < 0.01 => format!("still significant (p = {p:.3})"),
        (Some(p), _) => format!("not significant (p = {p:.3})"),
        (None, _) => "cannot be tested (no replicate runs)".into(),
    }
}

/// `html` with `section` placed before its "Reproducing" heading (or at the end).
pub fn insert_section(html: String, section: &str) -> String {
    match html.find("<h2>Reproducing</h2>") {
        Some(i) => format!("{}{section}{}", &html[..i], &html[i..]),
        None => html + section,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nothing_discovered_is_said_and_a_term_is_kept_apart() {
        let none = json!({"terms": [], "unexplained_after": true, "residual_pattern": "diameter",
            "verdict": "Nothing in the library explains what the catalogue leaves (pattern: diameter).",
            "declined": [{"name": "t2_lowforce", "delta_bic": -13.1, "reason": "unstable",
                          "loco_rmse_ratio": {"value": 0.986, "ci95": {"lo": 0.95, "hi": 1.02}}}],
            "search": {"library_size": 28, "first_bar": -12.5}, "elapsed_s": 0.1});
        let h = discovered_html(&none);
        assert!(h.contains("Nothing in the library") && h.contains("t2_lowforce"));
        let m = discovered_json(&none);
        assert_eq!(m["terms"], json!([]));
        let one = json!({"terms": [{"name": "t1_offset_diameter", "acts_on": "t1_reading",
            "depends_on": ["t1", "diameter"], "stability": 0.9, "partial": true,
            "shown_to_predict_better": true, "lack_of_fit_after": {"p": 0.002},
            "loco_rmse_ratio": {"value": 0.9, "ci95": {"lo": 0.8, "hi": 0.99},
                                "rmse_with_n": 0.3, "rmse_without_n": 0.33}}],
            "verdict": "Discovered", "search": {"library_size": 28, "tried": 26}});
        let m = discovered_json(&one);
        assert!(m["terms"][0]["status"]
            .as_str()
            .unwrap()
            .contains("not an established cause"));
        assert_eq!(m["terms"][0]["held_out"]["rmse_without_n"], json!(0.33));
        // Partial and "shown to predict better" are carried, and shown in words (D5).
        assert_eq!(m["terms"][0]["partial"], json!(true));
        assert_eq!(m["terms"][0]["shown_to_predict_better"], json!(true));
        assert_eq!(m["terms"][0]["lack_of_fit_after"]["p"], json!(0.002));
        let h = discovered_html(&one);
        assert!(h.contains("t1, diameter") && !h.contains("[\"t1\""), "{h}");
        assert!(h.contains("partial: structure still left"), "{h}");
        assert!(h.contains("searched 26 of 28 library terms"), "{h}");
        let h = insert_section(
            "<h2>A</h2><h2>Reproducing</h2>".into(),
            &discovered_html(&one),
        );
        assert!(h.find("t1_offset_diameter").unwrap() < h.find("Reproducing").unwrap());
    }
}
