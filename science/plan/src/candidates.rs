//! Candidate protocols: the data's own design, and what the rig can do instead — without a
//! rebuild (`capstan rig set`: order, runs, drive voltage through the amplifier control) or
//! with a physical change the user makes (more wraps, a second capstan), marked as such.

use crate::commands;
use capstan_physics::entry::CaseDesign;
use capstan_physics::EffectKind;
use capstan_rig::{Protocol, StepOrder};
use capstan_wire::Key;

pub use crate::design::{Candidate, Design, BETWEEN_RUNS_S, MAX_RUNS_PER_CORD};

/// The data's design and its variants (the data's own first); `open`: effects the data could
/// not test, for which a variant that tests them all is added (what each needs of a design is
/// its catalogue entry's `cases.design`).
/// `as_data`: the current design is the data's own ([`Design::is_the_datas`]); else the
/// procedure does not say "as before".
pub fn candidates(current: &Design, open: &[EffectKind], as_data: bool) -> Vec<Candidate> {
    let mut out = vec![Candidate {
        name: "current design".to_string(),
        design: current.clone(),
        rig_commands: Vec::new(),
        procedure: vec![if as_data {
            format!("{}, as before", runs_on_each_cord(current.runs_per_cord))
        } else {
            format!(
                "{} run{} on each of {} (the data's design as the simulator makes it: see \
                 assumed)",
                current.runs_per_cord,
                if current.runs_per_cord == 1 { "" } else { "s" },
                cords_text(current.cords())
            )
        }],
        physical_changes: Vec::new(),
    }];
    let updown = rig_only(
        "up-down order",
        Design {
            order: StepOrder::UpDown,
            ..current.clone()
        },
    );
    if current.order != StepOrder::UpDown {
        out.push(updown.clone());
    }
    let twice = Design {
        runs_per_cord: current.runs_per_cord * 2,
        ..current.clone()
    };
    out.push(rig_only("twice the runs per cord", twice));
    with_covariates(&updown, &mut out);
    let all = open
        .iter()
        .map(|k| k.entry().cases.design)
        .fold(CaseDesign::default(), union);
    let names: Vec<&str> = open.iter().map(|k| k.name()).collect();
    push_new(
        &mut out,
        Candidate {
            name: format!("up-down order testing {}", names.join(", ")),
            ..meeting(&updown, all)
        },
    );
    out.iter_mut().for_each(commands::switch_voltages);
    out
}

/// The up-down order with every combination of the changes that add a covariate the design
/// lacks (a second drive voltage, a wide span of wraps, a second capstan), and the wide span
/// with twice the runs; appended to `out` where new.
fn with_covariates(updown: &Candidate, out: &mut Vec<Candidate>) {
    // Every combination of the changes that add a covariate: a second drive voltage, a wide
    // span of wraps, a second capstan (those the design lacks).
    let changes = [
        (
            " at two drive voltages",
            CaseDesign {
                voltages: true,
                ..CaseDesign::default()
            },
        ),
        (
            " over 270-720 degree wraps",
            CaseDesign {
                wide_wraps: true,
                ..CaseDesign::default()
            },
        ),
        (
            " on a second capstan",
            CaseDesign {
                diameters: true,
                ..CaseDesign::default()
            },
        ),
    ];
    for mask in 1..(1 << changes.len()) {
        let mut name = "up-down order".to_string();
        let mut needs = CaseDesign::default();
        for (i, (words, n)) in changes.iter().enumerate() {
            if mask & (1 << i) != 0 {
                name += words;
                needs = union(needs, *n);
            }
        }
        push_new(
            out,
            Candidate {
                name,
                ..meeting(updown, needs)
            },
        );
    }
    // More runs per cord where the wraps span wide: a T1 and a T2 offset differ only in how
    // the wrap amplifies them, and each run's own mu leaves few degrees of freedom per cord.
    let wide = meeting(updown, changes[1].1);
    if wide.design != updown.design {
        let runs = wide.design.runs_per_cord * 2;
        let mut c = Candidate {
            name: "up-down order over 270-720 degree wraps, twice the runs".to_string(),
            ..wide
        };
        c.design.runs_per_cord = runs;
        c.procedure[0] = runs_on_each_cord(runs);
        push_new(out, c);
    }
}

/// Both designs' needs.
fn union(a: CaseDesign, b: CaseDesign) -> CaseDesign {
    CaseDesign {
        wide_wraps: a.wide_wraps || b.wide_wraps,
        voltages: a.voltages || b.voltages,
        diameters: a.diameters || b.diameters,
        min_runs: a.min_runs.max(b.min_runs),
    }
}

/// `c` appended unless a candidate already has its design.
fn push_new(out: &mut Vec<Candidate>, c: Candidate) {
    if out.iter().all(|o| o.design != c.design) {
        out.push(c);
    }
}

/// The candidate design that tests the most of `open` (the first such: the fewest changes),
/// with runs of `protocol`: where the planner reads the span an untestable effect's
/// planted-case size is spread over.
pub fn testing_design(current: &Design, open: &[EffectKind], protocol: &Protocol) -> Design {
    let all = candidates(current, open, true);
    let mut best = all[0].design.clone();
    for c in &all {
        let tests = |d: &Design| {
            (open.iter())
                .filter(|k| d.untestable(**k, protocol).is_none())
                .count()
        };
        if tests(&c.design) > tests(&best) {
            best = c.design.clone();
        }
    }
    best
}

fn rig_only(name: &str, design: Design) -> Candidate {
    let rig_commands = vec![
        format!(
            "capstan rig set {} {}",
            Key::Order.name(),
            design.order.name()
        ),
        "capstan rig store".to_string(),
    ];
    let procedure = vec![runs_on_each_cord(design.runs_per_cord)];
    Candidate {
        name: name.to_string(),
        design,
        rig_commands,
        procedure,
        physical_changes: Vec::new(),
    }
}

/// `base` changed as far as `needs` asks and the design lacks it: a second drive voltage (the
/// amplifier control, a rig setting), a span of wraps from 270° to 720° and a second capstan
/// (physical changes, marked as such), more runs per cord.
pub fn meeting(base: &Candidate, needs: CaseDesign) -> Candidate {
    let mut c = base.clone();
    let d = &mut c.design;
    if needs.voltages && d.drive_v.len() == 1 {
        let v = d.drive_v[0];
        let volts = [v, (v / 2.0 * 10.0).round() / 10.0];
        // Ascending, as the data's design lists them; the rig keeps the data's voltage first.
        d.drive_v = vec![volts[1].min(volts[0]), volts[1].max(volts[0])];
        c.rig_commands.insert(1, commands::set_drive(volts[0]).0);
        c.procedure.push(commands::switch_step(volts[1]));
    }
    let span = |v: &[f64]| {
        v.iter().cloned().fold(f64::MIN, f64::max) - v.iter().cloned().fold(f64::MAX, f64::min)
    };
    if needs.wide_wraps && (d.wraps_deg.len() < 3 || span(&d.wraps_deg) < 300.0) {
        d.wraps_deg.extend([270.0, 450.0, 720.0]);
        d.wraps_deg.sort_by(f64::total_cmp);
        d.wraps_deg.dedup();
        let wraps: Vec<String> = d.wraps_deg.iter().map(|w| format!("{w}°")).collect();
        c.physical_changes
            .push(format!("wrap a new cord at each of {}", wraps.join(", ")));
    }
    if needs.diameters && d.diameters_mm.len() == 1 {
        let one = d.diameters_mm[0];
        let other = if one > 19.0 { 12.7 } else { 25.4 };
        d.diameters_mm = vec![one.min(other), one.max(other)];
        c.physical_changes.push(format!(
            "fit a {other} mm capstan and repeat every wrap on it"
        ));
    }
    if needs.min_runs > d.runs_per_cord {
        d.runs_per_cord = needs.min_runs;
        c.procedure[0] = runs_on_each_cord(d.runs_per_cord);
    }
    c
}

/// "1 run on each cord", "6 runs on each cord".
fn cords_text(n: usize) -> String {
    format!("{n} cord{}", if n == 1 { "" } else { "s" })
}

fn runs_on_each_cord(n: impl Into<u64>) -> String {
    let n = n.into();
    format!("{n} run{} on each cord", if n == 1 { "" } else { "s" })
}
