//! The planner on planted truths: a campaign is simulated with a known truth on a design that
//! cannot tell it from its rivals; `plan` is run on it; then fresh campaigns (seeds the planner
//! never used) are simulated with the truth under the recommended design and under the
//! original one, and diagnosed. The recommendation must name the truth alone in ≥ 90 % of them
//! (the target); the original design's rate is printed beside it.
//!
//! * `cargo test -p capstan-plan --test validate` runs a fixed slice (drift on monotone runs
//!   and a speed effect at one drive voltage, small designs, few campaigns: about a minute);
//! * `CAPSTAN_PLAN=full cargo test --release -p capstan-plan --test validate -- --nocapture`
//!   runs every scenario at the thesis's design with 10 fresh campaigns each (CI);
//!   `CAPSTAN_PLAN_ONLY=TEXT` beside it runs only the scenarios whose name contains TEXT.

use capstan_physics::{Effect, EffectKind};
use capstan_plan::candidates::Design;
use capstan_plan::hypotheses::Hypothesis;
use capstan_plan::trial::{config, World};
use capstan_plan::{plan, Options};
use capstan_rig::{Protocol, StepOrder};
use capstan_validation::cases::{Case, Class};
use capstan_validation::score;

fn full() -> bool {
    std::env::var("CAPSTAN_PLAN").is_ok_and(|v| v == "full")
}

struct Scenario {
    name: &'static str,
    truth: Vec<(&'static str, f64)>,
    design: Design,
    /// The 90 % is not reached here (measured, reported in docs/README-plan.md):
    /// asserted only not to fall below the original design.
    known_short: bool,
}

fn thesis_design(order: StepOrder) -> Design {
    Design {
        order,
        runs_per_cord: 6,
        wraps_deg: vec![270.0, 360.0, 450.0, 630.0, 720.0],
        diameters_mm: vec![12.7, 25.4],
        drive_v: vec![10.0],
    }
}

/// A design that can test every effect of the catalogue (wide wraps, two capstans, two drive
/// voltages): the clean control's, so that nothing is left untestable.
fn complete_design(order: StepOrder) -> Design {
    Design {
        order,
        runs_per_cord: 4,
        wraps_deg: vec![270.0, 450.0, 720.0],
        diameters_mm: vec![12.7, 25.4],
        drive_v: vec![5.0, 10.0],
    }
}

fn small_design(order: StepOrder) -> Design {
    Design {
        order,
        runs_per_cord: 4,
        wraps_deg: vec![360.0, 540.0, 720.0],
        diameters_mm: vec![25.4],
        drive_v: vec![10.0],
    }
}

fn truth(s: &Scenario) -> Hypothesis {
    Hypothesis {
        effects: (s.truth.iter())
            .map(|(n, v)| Effect {
                kind: EffectKind::from_name(n).expect("a catalogue effect"),
                value: *v,
            })
            .collect(),
        origin: "planted".to_string(),
    }
}

fn world() -> World {
    World {
        mu: 0.115,
        cord_pct: capstan_sim::noise::thesis::CORD_SCATTER_PCT,
        run_pct: capstan_sim::noise::thesis::RUN_SCATTER_PCT,
        protocol: Protocol::default(),
    }
}

fn case(design: &Design, h: &Hypothesis, seed: u64) -> Case {
    Case {
        seed,
        class: Class::Single,
        effects: h.effects.clone(),
        outside: None,
        config: config(design, h, &world(), seed),
        drop_columns: Vec::new(),
    }
}

/// The share of `n` fresh campaigns of `design` (seeds from `base`) that name `h` alone.
fn rate(design: &Design, h: &Hypothesis, base: u64, n: u64) -> f64 {
    let cases: Vec<Case> = (0..n).map(|i| case(design, h, base + i)).collect();
    let outcomes = score::run(&cases, 2, capstan_engine::diagnose::diagnose).expect("simulates");
    let ok = outcomes
        .iter()
        .filter(|o| capstan_plan::trial::decides(o))
        .count();
    ok as f64 / n as f64
}

/// Plan on one campaign of the scenario; the recommended and original designs' rates on fresh
/// seeds.
fn run(s: &Scenario, reps: usize, fresh: u64) -> (String, f64, f64) {
    let h = truth(s);
    let (data, _) = case(&s.design, &h, 11).generate().expect("simulates");
    let opts = Options {
        reps,
        seed: 5,
        threads: 2,
        max_hours: None,
        // The protocols are validated here; how many cords is the cord calibration's.
        cords: false,
        stop: None,
    };
    let p = plan(&data, &opts, &mut |_, _| true).expect("plans");
    let rec = &p.recommended.candidate;
    let rec_rate = rate(&rec.design, &h, 50_000, fresh);
    let orig_rate = rate(&s.design, &h, 60_000, fresh);
    eprintln!(
        "{:<36} open: {:<60} recommended: {:<40} truth alone: {:>3.0} % (original design {:>3.0} %)",
        s.name,
        p.hypotheses.iter().map(|h| h.label()).collect::<Vec<_>>().join(" | "),
        rec.name,
        100.0 * rec_rate,
        100.0 * orig_rate
    );
    let counts = |c: &capstan_plan::Scored| {
        (c.per_hypothesis.iter())
            .map(|r| format!("{} {}/{}", r.hypothesis, r.decided, r.campaigns))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let current = p
        .candidates
        .iter()
        .find(|c| c.candidate.name == "current design");
    eprintln!(
        "    planner: recommended {}; current design {}",
        counts(&p.recommended),
        current.map(counts).unwrap_or_default()
    );
    (rec.name.clone(), rec_rate, orig_rate)
}

fn scenarios() -> Vec<Scenario> {
    let thesis = thesis_design(StepOrder::Monotone);
    vec![
        Scenario {
            name: "drift on monotone runs",
            truth: vec![("thermal_drift", -0.1)],
            design: thesis.clone(),
            known_short: false,
        },
        Scenario {
            name: "contact heating on monotone runs",
            truth: vec![("contact_heating", 0.006)],
            design: thesis.clone(),
            known_short: false,
        },
        Scenario {
            name: "wear on monotone runs",
            truth: vec![("wear", -0.03)],
            design: thesis,
            known_short: false,
        },
        Scenario {
            name: "T2 offset at two close wraps",
            truth: vec![("t2_offset", 0.6)],
            design: Design {
                order: StepOrder::UpDown,
                runs_per_cord: 5,
                wraps_deg: vec![360.0, 450.0],
                diameters_mm: vec![25.4],
                drive_v: vec![10.0],
            },
            known_short: false,
        },
        Scenario {
            name: "speed effect at one drive voltage",
            truth: vec![("speed_dependence", -0.03)],
            design: Design {
                runs_per_cord: 4,
                ..thesis_design(StepOrder::UpDown)
            },
            known_short: false,
        },
        Scenario {
            name: "control: T2 offset, design decides",
            truth: vec![("t2_offset", 0.8)],
            design: Design {
                drive_v: vec![5.0, 10.0],
                ..thesis_design(StepOrder::UpDown)
            },
            known_short: false,
        },
        Scenario {
            name: "control: nothing, design decides",
            truth: vec![],
            design: complete_design(StepOrder::Monotone),
            known_short: false,
        },
    ]
}

#[test]
fn the_recommended_protocol_names_the_planted_truth_alone() {
    if !full() {
        let drift = Scenario {
            name: "drift on monotone runs (slice)",
            truth: vec![("thermal_drift", -0.15)],
            design: small_design(StepOrder::Monotone),
            known_short: false,
        };
        let speed = Scenario {
            name: "speed effect at one drive voltage (slice)",
            truth: vec![("speed_dependence", -0.03)],
            design: Design {
                runs_per_cord: 3,
                diameters_mm: vec![12.7, 25.4],
                ..small_design(StepOrder::UpDown)
            },
            known_short: false,
        };
        for s in [drift, speed] {
            let (_, rec, orig) = run(&s, 2, 4);
            assert!(
                rec >= 0.75,
                "{}: recommended design named the truth alone in {rec}",
                s.name
            );
            assert!(
                rec >= orig,
                "{}: recommended {rec} below the original design's {orig}",
                s.name
            );
        }
        return;
    }
    let mut failures = Vec::new();
    // CAPSTAN_PLAN_ONLY=TEXT: only the scenarios whose name contains TEXT (while iterating).
    let only = std::env::var("CAPSTAN_PLAN_ONLY").unwrap_or_default();
    for s in scenarios().into_iter().filter(|s| s.name.contains(&only)) {
        let (name, rec, orig) = run(&s, 4, 10);
        if rec < 0.9 && !s.known_short {
            failures.push(format!(
                "{}: {name} names the truth alone in {rec} (< 0.9)",
                s.name
            ));
        }
        if s.name.starts_with("control") && name != "current design" {
            failures.push(format!(
                "{}: recommended {name}, not the current design",
                s.name
            ));
        }
        if rec + 1e-9 < orig {
            failures.push(format!(
                "{}: recommended {rec} below the original {orig}",
                s.name
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
