//! The report's "Next experiment" section and its `next_experiment` object in `metrics.json`:
//! what the data leave open and, when `capstan analyze --plan` ran the planner, the protocol
//! that decides (its `capstan rig` commands, physical changes, rig hours and chance of deciding,
//! with the current design's chance beside it). Without the planner (it simulates for about a
//! minute) the section lists what is open and gives the `capstan plan` command that answers it.
//! The section is rendered from the `metrics.json` object ([`NextExperiment`]) alone.

use crate::cells::esc;
use capstan_plan::cords::Cords;
use capstan_plan::design::Design;
use capstan_plan::hypotheses::NotSimulated;
use capstan_plan::{Beyond, Current, First, Open, Plan};
use serde::Serialize;
use std::fmt::Write as _;

/// The `next_experiment` object of `metrics.json`.
#[derive(Clone, Debug, Serialize)]
pub struct NextExperiment {
    /// The planner ran (`capstan analyze --plan`).
    pub planned: bool,
    /// The `capstan plan` command that plans these data.
    pub command: String,
    /// The hypotheses the data leave open.
    pub open: Vec<OpenHypothesis>,
    /// What the data leave open that is not simulated, and why.
    pub not_simulated: Vec<NotSimulated>,
    /// What the planner had to assume.
    pub assumed: Vec<String>,
    /// The plan, when the planner ran.
    #[serde(flatten)]
    pub plan: Option<Planned>,
}

/// An open hypothesis: its label and where it comes from.
#[derive(Clone, Debug, Serialize)]
pub struct OpenHypothesis {
    /// Its effects joined by `+` (`euler_eytelwein` for none).
    pub label: String,
    /// Where it comes from.
    pub origin: String,
}

/// What the planner recommends, against the current design.
#[derive(Clone, Debug, Serialize)]
pub struct Planned {
    /// The recommended protocol.
    pub recommended: Recommended,
    /// The data's own design's chance.
    pub current_design: Current,
    /// The current design already decides.
    pub current_decides: bool,
    /// Some candidate decides.
    pub any_decides: bool,
    /// The recommendation fits in the hours given.
    pub within_hours: bool,
    /// Simulated campaigns behind each chance.
    pub reps: usize,
    /// How many cords each open question between cords needs.
    pub cords: Option<Cords>,
    /// Which recommendation comes first, and why.
    pub first: First,
    /// The best protocol beyond the hours given, when better.
    pub better_beyond_hours: Option<Beyond>,
    /// How the chances were estimated.
    pub method: String,
    /// The planner's wall time, s.
    pub elapsed_s: f64,
}

/// The recommended protocol and how to run it.
#[derive(Clone, Debug, Serialize)]
pub struct Recommended {
    /// Its name.
    pub name: String,
    /// The design.
    pub protocol: Design,
    /// The `capstan rig` commands that set it.
    pub rig_commands: Vec<String>,
    /// Physical changes, by hand.
    pub physical_changes: Vec<String>,
    /// What to do then.
    pub procedure: Vec<String>,
    /// The `capstan simulate` arguments of its campaign.
    pub simulate_args: Vec<String>,
    /// Rig time, h.
    pub rig_hours: f64,
    /// Its worst chance of deciding over the hypotheses.
    pub p_decide_worst: f64,
}

impl Planned {
    fn of(p: &Plan) -> Self {
        let r = &p.recommended;
        Planned {
            recommended: Recommended {
                name: r.candidate.name.clone(),
                protocol: r.candidate.design.clone(),
                rig_commands: r.candidate.rig_commands.clone(),
                physical_changes: r.candidate.physical_changes.clone(),
                procedure: r.candidate.procedure.clone(),
                simulate_args: r.simulate_args.clone(),
                rig_hours: r.rig_hours,
                p_decide_worst: r.p_decide_worst,
            },
            current_design: p.current_design.clone(),
            current_decides: p.current_decides,
            any_decides: p.any_decides,
            within_hours: p.within_hours,
            reps: p.reps,
            cords: p.cords.clone(),
            first: p.first.clone(),
            better_beyond_hours: p.better_beyond_hours.clone(),
            method: p.method.clone(),
            elapsed_s: p.elapsed_s,
        }
    }
}

/// The `next_experiment` object from the planner's open hypotheses, the plan if it ran (its
/// open hypotheses then), and the `capstan plan` command that plans these data.
pub fn next_experiment(open: &Open, plan: Option<&Plan>, command: &str) -> NextExperiment {
    let (hypotheses, not_simulated, assumed) = match plan {
        Some(p) => (&p.hypotheses, &p.not_simulated, &p.assumed),
        None => (&open.hypotheses, &open.not_simulated, &open.assumed),
    };
    NextExperiment {
        planned: plan.is_some(),
        command: command.to_string(),
        open: (hypotheses.iter())
            .map(|h| OpenHypothesis {
                label: h.label(),
                origin: h.origin.clone(),
            })
            .collect(),
        not_simulated: not_simulated.clone(),
        assumed: assumed.clone(),
        plan: plan.map(Planned::of),
    }
}

/// The report's section, from the `next_experiment` object of `metrics.json`.
pub fn next_html(n: &NextExperiment) -> String {
    let mut h = String::from("<h2>Next experiment</h2>");
    open_list(&mut h, n);
    let Some(p) = &n.plan else {
        let _ = write!(
            h,
            "<p>The planner did not run (it simulates campaigns for about a minute). <code>{}</code> ranks the protocols that would decide between these, with the <code>capstan rig</code> commands of the best and its chance of deciding; <code>capstan analyze --plan</code> puts that here.</p>",
            esc(&n.command)
        );
        return h;
    };
    let cords_first = p.first.which == "cords";
    if cords_first {
        cords_html(&mut h, p);
    }
    recommendation(&mut h, p);
    if !cords_first {
        cords_html(&mut h, p);
    }
    let r = &p.recommended;
    list(&mut h, "Physical changes (by hand):", &r.physical_changes);
    if !r.rig_commands.is_empty() {
        let lines: Vec<String> = r.rig_commands.iter().map(|c| esc(c)).collect();
        let _ = write!(h, "<p>On the board:</p><pre>{}</pre>", lines.join("\n"));
    }
    list(&mut h, "Then:", &r.procedure);
    let args: Vec<String> = r.simulate_args.iter().map(|a| esc(a)).collect();
    let _ = write!(
        h,
        "<p>Check it: <code>capstan simulate --out DIR {}</code>. Method: {} ({} s; <code>{}</code> gives the full ranking).</p>",
        args.join(" "),
        esc(&p.method),
        hours(p.elapsed_s),
        esc(&n.command)
    );
    h
}

/// How many cords each open question between cords needs (the planner's `cords`), the first
/// of them as the first recommendation when the plan puts it first.
fn cords_html(h: &mut String, p: &Planned) {
    let Some(c) = p.cords.as_ref().filter(|c| !c.questions.is_empty()) else {
        return;
    };
    if p.first.which == "cords" {
        if let Some((q, t)) = (c.questions.iter()).find_map(|q| q.needed.as_ref().map(|t| (q, t))) {
            let _ = write!(
                h,
                "<p>Recommended first: <b>{} new cords</b> ({} runs on each, {} rig hours) to establish {} ({} of {} simulated campaigns do). Why first: {}.</p>",
                t.cords, t.runs_per_cord, hours(t.rig_hours), esc(&q.question), t.established, t.campaigns, esc(&p.first.why)
            );
        }
    }
    h.push_str("<p>How many cords each open question between cords needs (80 % of simulated campaigns establishing it):</p><ul>");
    for q in &c.questions {
        let mut answer = match &q.needed {
            Some(t) => format!("{} cords, {} runs on each", t.cords, t.runs_per_cord),
            None => "more cords than the simulation tried".into(),
        };
        // The held-out gain: also the cords at the data's own spread of the gain (resampling
        // the cords' held-out errors), which the simulated world need not have.
        if let Some(spread) = &q.at_observed_spread {
            let _ = match spread.cords {
                Some(k) => write!(answer, "; about {k} cords at the data's own spread of the gain from cord to cord (resampling the cords' held-out errors)"),
                None => write!(answer, "; more than {} cords at the data's own spread of the gain", spread.tried_up_to),
            };
        }
        let _ = write!(
            h,
            "<li>{}: {answer}; observed {}</li>",
            esc(&q.question),
            esc(&q.observed)
        );
    }
    let _ = write!(h, "</ul><p>Method: {}</p>", esc(&c.method));
}

/// A chance as a percentage ("-" if not a number).
fn pct(x: f64) -> String {
    if x.is_finite() {
        format!("{:.0} %", 100.0 * x)
    } else {
        "-".to_string()
    }
}

/// A chance with the campaigns behind it ("7 of 8 simulated campaigns, 88 %"): a rate from a
/// few campaigns, not a certainty.
fn chance(x: f64, reps: usize) -> String {
    if x.is_finite() && reps > 0 {
        format!(
            "{} of {reps} simulated campaigns ({:.0} %)",
            (x * reps as f64).round(),
            100.0 * x
        )
    } else {
        pct(x)
    }
}

/// Rig hours (or seconds) to one decimal ("-" if not a number).
fn hours(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.1}")
    } else {
        "-".to_string()
    }
}

/// What the data leave open: the hypotheses, and those not simulated with why.
fn open_list(h: &mut String, n: &NextExperiment) {
    h.push_str("<p>What these data leave open:</p><ul>");
    for o in &n.open {
        let _ = write!(
            h,
            "<li><code>{}</code> ({})</li>",
            esc(&o.label),
            esc(&o.origin)
        );
    }
    for o in &n.not_simulated {
        let _ = write!(
            h,
            "<li><code>{}</code>, not simulated: {}</li>",
            esc(&o.what),
            esc(&o.why)
        );
    }
    h.push_str("</ul>");
}

/// The recommendation against the current design (or that the current design decides), and a
/// warning when no candidate decided at all.
fn recommendation(h: &mut String, p: &Planned) {
    let r = &p.recommended;
    let cur = &p.current_design;
    let pct = |x: f64| chance(x, p.reps);
    if p.current_decides {
        let _ = write!(
            h,
            "<p>The current design already decides between the simulated hypotheses: chance of naming the true one alone {} (worst case), {} rig hours. Run it again as it is.</p>",
            pct(cur.p_decide_worst),
            hours(cur.rig_hours)
        );
    } else {
        let _ = write!(
            h,
            "<p>Recommended: <b>{}</b>, {} rig hours: chance of naming the true hypothesis alone {} (worst case over the open hypotheses), against {} for the current design ({} h).</p>",
            esc(&r.name),
            hours(r.rig_hours),
            pct(r.p_decide_worst),
            pct(cur.p_decide_worst),
            hours(cur.rig_hours)
        );
    }
    if let Some(b) = &p.better_beyond_hours {
        let _ = write!(
            h,
            "<p>Within the hours given nothing does better; <b>{}</b> reaches {} but needs {} rig hours.</p>",
            esc(&b.name),
            pct(b.p_decide_worst),
            hours(b.rig_hours)
        );
    }
    if !p.any_decides {
        h.push_str("<p>No candidate protocol named the true hypothesis alone in any simulated campaign: this is only the least bad.</p>");
    }
}

/// A titled list of strings, if there are any.
fn list(h: &mut String, title: &str, items: &[String]) {
    if !items.is_empty() {
        let _ = write!(h, "<p>{title}</p><ul>");
        for i in items {
            let _ = write!(h, "<li>{}</li>", esc(i));
        }
        h.push_str("</ul>");
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use capstan_plan::First;

    fn open() -> NextExperiment {
        let hyp = |label: &str, origin: &str| OpenHypothesis {
            label: label.into(),
            origin: origin.into(),
        };
        NextExperiment {
            planned: false,
            command: "capstan plan data.csv".into(),
            open: vec![
                hyp("t2_offset", "named"),
                hyp(
                    "t2_offset+speed_dependence",
                    "not testable in these data (a single drive voltage)",
                ),
            ],
            not_simulated: vec![NotSimulated {
                what: "unexplained".into(),
                why: "structure no catalogue effect explains".into(),
            }],
            assumed: vec![],
            plan: None,
        }
    }

    #[test]
    fn without_the_planner_the_section_lists_what_is_open_and_the_command() {
        let h = next_html(&open());
        for s in [
            "t2_offset+speed_dependence",
            "unexplained",
            "capstan plan data.csv",
            "--plan",
        ] {
            assert!(h.contains(s), "no {s} in {h}");
        }
        assert!(!h.contains("Recommended"));
        let v = serde_json::to_value(open()).unwrap();
        assert_eq!(v["planned"], serde_json::json!(false));
        assert!(v.get("recommended").is_none(), "{v}");
    }

    #[test]
    fn the_open_hypotheses_of_the_thesis_data_are_the_planners() {
        let o = capstan_plan::open(&capstan_data::thesis_dataset());
        let n = next_experiment(&o, None, "capstan plan");
        assert_eq!(n.open.len(), o.hypotheses.len());
        assert_eq!(n.open[0].label, o.hypotheses[0].label());
        assert!(!n.planned && n.plan.is_none());
    }

    #[test]
    fn the_section_is_rendered_from_the_metrics_object() {
        let mut n = open();
        n.planned = true;
        n.command = "capstan plan".into();
        n.plan = Some(Planned {
            recommended: Recommended {
                name: "up-down order at two drive voltages".into(),
                protocol: Design {
                    order: capstan_wire::StepOrder::UpDown,
                    runs_per_cord: 6,
                    wraps_deg: vec![360.0],
                    diameters_mm: vec![25.4],
                    drive_v: vec![10.0, 5.0],
                },
                rig_commands: vec![
                    "capstan rig set order updown".into(),
                    "capstan rig set amp_control_v 2.5".into(),
                    "capstan rig store".into(),
                ],
                physical_changes: vec![],
                procedure: vec!["6 runs on each cord".into()],
                simulate_args: vec!["--drive-v".into(), "10,5".into()],
                rig_hours: 6.25,
                p_decide_worst: 0.875,
            },
            current_design: Current {
                p_decide_worst: 0.0,
                rig_hours: 3.125,
            },
            current_decides: false,
            any_decides: true,
            within_hours: true,
            reps: 0,
            cords: None,
            first: First {
                which: "protocol",
                why: "no question between cords".into(),
            },
            better_beyond_hours: None,
            method: "simulation: 8 campaigns".into(),
            elapsed_s: 41.0,
        });
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
        let p = n.plan.as_mut().unwrap();
        p.recommended.p_decide_worst = 0.5;
        p.recommended.rig_commands[1] = "capstan rig set amp_control_v 1.25".into();
        let h = next_html(&n);
        assert!(h.contains("50 %") && h.contains("amp_control_v 1.25") && !h.contains("88 %"));
        // The plan's fields stand beside the open ones in the object, as before.
        let v = serde_json::to_value(&n).unwrap();
        assert_eq!(v["recommended"]["p_decide_worst"], serde_json::json!(0.5));
        assert_eq!(v["cords"], serde_json::Value::Null);
    }
}
