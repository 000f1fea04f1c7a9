//! The report's "Next experiment" section and its `next_experiment` object in `metrics.json`:
//! what the data leave open and, when `capstan analyze --plan` ran the planner, the protocol
//! that decides (its `capstan rig` commands, physical changes, rig hours and chance of deciding,
//! with the current design's chance beside it). Without the planner (it simulates for about a
//! minute) the section lists what is open and gives the `capstan plan` command that answers it.
//! The section is rendered from the `metrics.json` object alone; the crate takes the plan as
//! JSON (it does not depend on `capstan-plan`).

use crate::cells::esc;
use serde_json::{json, Value};
use std::fmt::Write as _;

/// The `next_experiment` object from the planner's open hypotheses (`capstan_plan::Open` as
/// JSON: `hypotheses`, `not_simulated`, `assumed`), the plan if it ran (`capstan_plan::Plan`
/// as JSON), and the `capstan plan` command that plans these data.
pub fn next_json(open: &Value, plan: Option<&Value>, command: &str) -> Value {
    let hyps = |v: &Value| -> Vec<Value> {
        (v["hypotheses"].as_array().into_iter().flatten())
            .map(|h| json!({"label": h["label"], "origin": h["origin"]}))
            .collect()
    };
    let mut next = json!({
        "planned": plan.is_some(),
        "command": command,
        "open": hyps(plan.unwrap_or(open)),
        "not_simulated": plan.unwrap_or(open)["not_simulated"],
        "assumed": plan.unwrap_or(open)["assumed"],
    });
    if let Some(p) = plan {
        let r = &p["recommended"];
        next["recommended"] = json!({
            "name": r["name"],
            "protocol": r["protocol"],
            "rig_commands": r["rig_commands"],
            "physical_changes": r["physical_changes"],
            "procedure": r["procedure"],
            "simulate_args": r["simulate_args"],
            "rig_hours": r["rig_hours"],
            "p_decide_worst": r["p_decide_worst"],
        });
        for key in [
            "current_design",
            "current_decides",
            "any_decides",
            "within_hours",
        ] {
            next[key] = p[key].clone();
        }
        next["reps"] = p["reps"].clone();
        next["cords"] = p["cords"].clone();
        next["first"] = p["first"].clone();
        next["better_beyond_hours"] = p["better_beyond_hours"].clone();
        next["method"] = p["method"].clone();
        next["elapsed_s"] = p["elapsed_s"].clone();
    }
    next
}

/// The report's section, from the `next_experiment` object of `metrics.json`.
pub fn next_html(n: &Value) -> String {
    let mut h = String::from("<h2>Next experiment</h2>");
    open_list(&mut h, n);
    if n["planned"].as_bool() != Some(true) {
        let _ = write!(
            h,
            "<p>The planner did not run (it simulates campaigns for about a minute). <code>{}</code> ranks the protocols that would decide between these, with the <code>capstan rig</code> commands of the best and its chance of deciding; <code>capstan analyze --plan</code> puts that here.</p>",
            text(&n["command"])
        );
        return h;
    }
    let cords_first = n["first"]["which"].as_str() == Some("cords");
    if cords_first {
        cords_html(&mut h, n);
    }
    recommendation(&mut h, n);
    if !cords_first {
        cords_html(&mut h, n);
    }
    let r = &n["recommended"];
    list(
        &mut h,
        "Physical changes (by hand):",
        &r["physical_changes"],
    );
    if let Some(cmds) = r["rig_commands"].as_array().filter(|a| !a.is_empty()) {
        let lines: Vec<String> = cmds.iter().map(text).collect();
        let _ = write!(h, "<p>On the board:</p><pre>{}</pre>", lines.join("\n"));
    }
    list(&mut h, "Then:", &r["procedure"]);
    let args: Vec<String> = (r["simulate_args"].as_array().into_iter().flatten())
        .map(text)
        .collect();
    let _ = write!(
        h,
        "<p>Check it: <code>capstan simulate --out DIR {}</code>. Method: {} ({} s; <code>{}</code> gives the full ranking).</p>",
        args.join(" "),
        text(&n["method"]),
        n["elapsed_s"].as_f64().map_or("-".to_string(), |x| format!("{x:.1}")),
        text(&n["command"])
    );
    h
}

/// How many cords each open question between cords needs (the planner's `cords`), the first
/// of them as the first recommendation when the plan puts it first.
fn cords_html(h: &mut String, n: &Value) {
    let qs = n["cords"]["questions"]
        .as_array()
        .cloned()
        .unwrap_or_default();
    if qs.is_empty() {
        return;
    }
    if n["first"]["which"].as_str() == Some("cords") {
        if let Some(q) = qs.iter().find(|q| q["needed"].is_object()) {
            let t = &q["needed"];
            let _ = write!(
                h,
                "<p>Recommended first: <b>{} new cords</b> ({} runs on each, {} rig hours) to establish {} ({} of {} simulated campaigns do). Why first: {}.</p>",
                t["cords"], t["runs_per_cord"], hours(&t["rig_hours"]), text(&q["question"]), t["established"], t["campaigns"], text(&n["first"]["why"])
            );
        }
    }
    h.push_str("<p>How many cords each open question between cords needs (80 % of simulated campaigns establishing it):</p><ul>");
    for q in &qs {
        let mut answer = if q["needed"].is_object() {
            format!(
                "{} cords, {} runs on each",
                q["needed"]["cords"], q["needed"]["runs_per_cord"]
            )
        } else {
            "more cords than the simulation tried".into()
        };
        // The held-out gain: also the cords at the data's own spread of the gain (resampling
        // the cords' held-out errors), which the simulated world need not have.
        let spread = &q["at_observed_spread"];
        if spread.is_object() {
            let _ = match spread["cords"].as_u64() {
                Some(k) => write!(answer, "; about {k} cords at the data's own spread of the gain from cord to cord (resampling the cords' held-out errors)"),
                None => write!(answer, "; more than {} cords at the data's own spread of the gain", spread["tried_up_to"]),
            };
        }
        let _ = write!(
            h,
            "<li>{}: {answer}; observed {}</li>",
            text(&q["question"]),
            text(&q["observed"])
        );
    }
    let _ = write!(h, "</ul><p>Method: {}</p>", text(&n["cords"]["method"]));
}

/// A string value, escaped for HTML ("" for anything else).
fn text(v: &Value) -> String {
    esc(v.as_str().unwrap_or(""))
}

/// A chance as a percentage ("-" if missing).
fn pct(v: &Value) -> String {
    v.as_f64()
        .map_or("-".to_string(), |x| format!("{:.0} %", 100.0 * x))
}

/// A chance with the campaigns behind it ("7 of 8 simulated campaigns, 88 %"): a rate from a
/// few campaigns, not a certainty.
fn chance(p: &Value, reps: &Value) -> String {
    match (p.as_f64(), reps.as_u64().filter(|&n| n > 0)) {
        (Some(x), Some(n)) => format!(
            "{} of {n} simulated campaigns ({:.0} %)",
            (x * n as f64).round(),
            100.0 * x
        ),
        _ => pct(p),
    }
}

/// Rig hours to one decimal ("-" if missing).
fn hours(v: &Value) -> String {
    v.as_f64().map_or("-".to_string(), |x| format!("{x:.1}"))
}

/// What the data leave open: the hypotheses, and those not simulated with why.
fn open_list(h: &mut String, n: &Value) {
    h.push_str("<p>What these data leave open:</p><ul>");
    for o in n["open"].as_array().into_iter().flatten() {
        let _ = write!(
            h,
            "<li><code>{}</code> ({})</li>",
            text(&o["label"]),
            text(&o["origin"])
        );
    }
    for o in n["not_simulated"].as_array().into_iter().flatten() {
        let _ = write!(
            h,
            "<li><code>{}</code>, not simulated: {}</li>",
            text(&o["what"]),
            text(&o["why"])
        );
    }
    h.push_str("</ul>");
}

/// The recommendation against the current design (or that the current design decides), and a
/// warning when no candidate decided at all.
fn recommendation(h: &mut String, n: &Value) {
    let r = &n["recommended"];
    let cur = &n["current_design"];
    let pct = |v: &Value| chance(v, &n["reps"]);
    if n["current_decides"].as_bool() == Some(true) {
        let _ = write!(
            h,
            "<p>The current design already decides between the simulated hypotheses: chance of naming the true one alone {} (worst case), {} rig hours. Run it again as it is.</p>",
            pct(&cur["p_decide_worst"]),
            hours(&cur["rig_hours"])
        );
    } else {
        let _ = write!(
            h,
            "<p>Recommended: <b>{}</b>, {} rig hours: chance of naming the true hypothesis alone {} (worst case over the open hypotheses), against {} for the current design ({} h).</p>",
            text(&r["name"]),
            hours(&r["rig_hours"]),
            pct(&r["p_decide_worst"]),
            pct(&cur["p_decide_worst"]),
            hours(&cur["rig_hours"])
        );
    }
    let b = &n["better_beyond_hours"];
    if b.is_object() {
        let _ = write!(
            h,
            "<p>Within the hours given nothing does better; <b>{}</b> reaches {} but needs {} rig hours.</p>",
            text(&b["name"]),
            pct(&b["p_decide_worst"]),
            hours(&b["rig_hours"])
        );
    }
    if n["any_decides"].as_bool() == Some(false) {
        h.push_str("<p>No candidate protocol named the true hypothesis alone in any simulated campaign: this is only the least bad.</p>");
    }
}

/// A titled list of strings, if there are any.
fn list(h: &mut String, title: &str, v: &Value) {
    if let Some(items) = v.as_array().filter(|a| !a.is_empty()) {
        let _ = write!(h, "<p>{title}</p><ul>");
        for i in items {
            let _ = write!(h, "<li>{}</li>", text(i));
        }
        h.push_str("</ul>");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn open() -> Value {
        json!({"hypotheses": [
                {"label": "t2_offset", "origin": "named", "effects": []},
                {"label": "t2_offset+speed_dependence", "origin": "not testable in these data (a single drive voltage)", "effects": []}],
               "not_simulated": [{"what": "unexplained", "why": "structure no catalogue effect explains"}],
               "assumed": []})
    }

    #[test]
    fn without_the_planner_the_section_lists_what_is_open_and_the_command() {
        let n = next_json(&open(), None, "capstan plan data.csv");
        assert_eq!(n["planned"], json!(false));
        let h = next_html(&n);
        for s in [
            "t2_offset+speed_dependence",
            "unexplained",
            "capstan plan data.csv",
            "--plan",
        ] {
            assert!(h.contains(s), "no {s} in {h}");
        }
        assert!(!h.contains("Recommended"));
    }

    #[test]
    fn the_section_is_rendered_from_the_metrics_object() {
        let plan = json!({"hypotheses": open()["hypotheses"], "not_simulated": [], "assumed": [],
            "recommended": {"name": "up-down order at two drive voltages", "protocol": {},
                "rig_commands": ["capstan rig set order updown", "capstan rig set amp_control_v 2.5", "capstan rig store"],
                "physical_changes": [], "procedure": ["6 runs on each cord"],
                "simulate_args": ["--drive-v", "10,5"], "rig_hours": 6.25, "p_decide_worst": 0.875},
            "current_design": {"p_decide_worst": 0.0, "rig_hours": 3.125},
            "current_decides": false, "any_decides": true, "within_hours": true,
            "method": "simulation: 8 campaigns", "elapsed_s": 41.0});
        let n = next_json(&open(), Some(&plan), "capstan plan");
        // What the metrics carry, the section says; change the metrics and the section follows.
        let h = next_html(&n);
        for s in [
            "up-down order at two drive voltages",
            "88 %",
            "0 %",
            "6.2",
            "3.1",
            "capstan rig set amp_control_v 2.5",
            "--drive-v 10,5",
            "simulation: 8 campaigns",
        ] {
            assert!(h.contains(s), "no {s} in {h}");
        }
        let mut m = n.clone();
        m["recommended"]["p_decide_worst"] = json!(0.5);
        m["recommended"]["rig_commands"][1] = json!("capstan rig set amp_control_v 1.25");
        let h = next_html(&m);
        assert!(h.contains("50 %") && h.contains("amp_control_v 1.25") && !h.contains("88 %"));
    }
}
