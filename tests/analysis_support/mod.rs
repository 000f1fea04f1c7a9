//! Shared by the analysis tests: the report's verdict sentences against `metrics.json`.

use capstan_engine::evidence::Level;
use capstan_engine::verdict::{words, Numbers, Verdict};
use capstan_physics::EffectKind;
use serde_json::Value;

fn unescape(s: &str) -> String {
    s.replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&amp;", "&")
}

/// The text of the report's summary cell of mechanism `name`.
fn summary_cell<'a>(html: &'a str, name: &str) -> &'a str {
    let row = html
        .find(&format!("<tr data-mechanism=\"{name}\">"))
        .unwrap_or_else(|| panic!("no row for {name}"));
    let cell = row + html[row..].find("<td class=\"summary\">").unwrap() + 20;
    &html[cell..cell + html[cell..].find("</td>").unwrap()]
}

fn verdict(s: &str) -> Verdict {
    match s {
        "ruled_in" => Verdict::RuledIn,
        "explained_away" => Verdict::ExplainedAway,
        "ruled_out" => Verdict::RuledOut,
        "not_established" => Verdict::NotEstablished,
        "not_testable" => Verdict::NotTestable,
        other => panic!("unknown verdict {other}"),
    }
}

fn level(s: &str) -> Level {
    match s {
        "within_run" => Level::WithinRun,
        "between_cord" => Level::BetweenCord,
        _ => Level::BetweenRun,
    }
}

/// A mechanism's rival from `metrics.json` (null: none).
fn rival(r: &Value) -> Option<capstan_engine::evidence::Rival> {
    if r.is_null() {
        return None;
    }
    let kind = |k: &Value| EffectKind::from_name(k.as_str().unwrap()).unwrap();
    let (instead_of, effect) = (kind(&r["instead_of"]), kind(&r["effect"]));
    Some(capstan_engine::evidence::Rival {
        instead_of: instead_of.name(),
        effect: effect.name(),
        parameters: r["parameters"]
            .as_object()
            .unwrap()
            .values()
            .map(|v| (effect.parameter().unwrap(), num(v)))
            .collect(),
        delta_bic: num(&r["delta_bic"]),
        reason: r["reason"].as_str().map(String::from),
        instead_of_kind: instead_of,
        kind: effect,
    })
}

fn num(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

/// Every mechanism's sentence in the report is the one its verdict and numbers in
/// `metrics.json` make; the headline names exactly the causes of `metrics.json`; no sentence
/// written for other data is left.
pub fn check(metrics: &Value, html: &str) {
    let causes: Vec<&str> = metrics["causes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["name"].as_str().unwrap())
        .collect();
    for m in metrics["mechanisms"].as_array().unwrap() {
        let name = m["name"].as_str().unwrap();
        let kind = EffectKind::from_name(name).unwrap();
        let v = verdict(m["verdict"].as_str().unwrap());
        let numbers = (!m["evidence"].is_null()).then(|| {
            let e = &m["evidence"];
            Numbers {
                parameter: kind.parameter().unwrap(),
                value: num(&e["value"]),
                se: num(&e["se"]),
                edge_interval: e["edge_interval"]
                    .as_array()
                    .map(|a| (num(&a[0]), num(&a[1]))),
                delta_bic_given_causes: num(&e["delta_bic_given_causes"]),
                delta_bic_alone: num(&e["delta_bic_alone"]),
                value_alone: num(&e["value_alone"]),
                relevance_width: num(&e["relevance_width"]),
                level: level(e["level"].as_str().unwrap()),
            }
        });
        let others: Vec<&str> = causes.iter().copied().filter(|c| *c != name).collect();
        let reason = m["not_testable_reason"].as_str().unwrap();
        let mut made = words::sentence(kind, v, numbers.as_ref(), &others, reason);
        assert!(
            m.get("rival").is_some(),
            "{name}: metrics.json has no rival key"
        );
        if let Some(r) = rival(&m["rival"]) {
            // A rival of this mechanism, in place of a cause the report names.
            assert_eq!(r.effect, name);
            assert!(
                causes.contains(&r.instead_of),
                "{name}: rival of {}",
                r.instead_of
            );
            made.push(' ');
            made += &capstan_engine::verdict::words::rival_sentences(&[r]);
        }
        let json = m["summary"].as_str().unwrap();
        // Numbers round-trip through JSON exactly, so the sentence does too.
        assert_eq!(
            made, json,
            "{name}: metrics.json's sentence is not its verdict's"
        );
        // The page sets the signs of negative numbers as minus signs.
        assert_eq!(
            unescape(summary_cell(html, name)),
            capstan_report::cells::minus_signs(json),
            "{name}: the report's"
        );
        assert_eq!(v == Verdict::RuledIn, causes.contains(&name), "{name}");
    }
    // The headline names the causes of metrics.json, no more, no less.
    let head =
        &html[html.find("<h2>Headline</h2>").unwrap()..html.find("<h2>The gain</h2>").unwrap()];
    for k in EffectKind::ALL.into_iter().skip(1) {
        assert_eq!(
            head.contains(&format!("<b>{}</b>", k.name())),
            causes.contains(&k.name()),
            "headline and {}",
            k.name()
        );
    }
    assert_eq!(
        head.contains("<b>Unexplained</b>"),
        metrics["unexplained"]["flag"].as_bool().unwrap()
    );
    // Sentences that were once typed in for the thesis data must not come back.
    for stale in [
        "does not remain",
        "collapse on T1, not T1/R",
        "ten per-cord offsets",
        "up to about 0.69",
        "2 s of settling",
    ] {
        assert!(!html.contains(stale), "stale sentence: {stale}");
    }
    let both = metrics["evidence"]["design"]["both_directions"]
        .as_bool()
        .unwrap();
    assert_eq!(html.contains("Steps only rise"), !both);
}
