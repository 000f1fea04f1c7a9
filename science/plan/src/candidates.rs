//! Candidate protocols: the data's own design, and what the rig can do instead — without a
//! rebuild (`capstan rig set`: order, runs, drive voltage through the amplifier control) or
//! with a physical change the user makes (more wraps, a second capstan), marked as such.

use crate::commands;
use capstan_engine::diagnose::Diagnosis;
use capstan_physics::entry::CaseDesign;
use capstan_physics::{EffectKind, Facts};
use capstan_rig::{Protocol, StepOrder};
use capstan_wire::Key;
use serde::Serialize;

/// Re-tensioning the cord, taring and starting a run: the time between runs, s (an estimate).
pub const BETWEEN_RUNS_S: f64 = 60.0;

/// The most runs per cord the planner simulates (4× the thesis's 6): a larger data set's
/// design is planned at this size, and says so; without a cap a million-row file made one
/// simulated campaign of ~83,000 runs.
pub const MAX_RUNS_PER_CORD: u32 = 24;

/// A design: what is run, on what, how often.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Design {
    /// Order of the tension levels.
    #[serde(serialize_with = "order_name")]
    pub order: StepOrder,
    /// Runs per cord.
    pub runs_per_cord: u32,
    /// Wrap angles, deg.
    pub wraps_deg: Vec<f64>,
    /// Capstan diameters, mm.
    pub diameters_mm: Vec<f64>,
    /// Drive voltages, V.
    pub drive_v: Vec<f64>,
}

fn order_name<S: serde::Serializer>(o: &StepOrder, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(o.name())
}

impl Design {
    /// The design of the diagnosed data (`assumed` gets what it had to guess).
    pub fn of(d: &Diagnosis, assumed: &mut Vec<String>) -> Design {
        let g = &d.design;
        let mut pick = |v: &[f64], default: f64, what: &str| {
            if v.is_empty() {
                assumed.push(format!("no {what} in the data: {default} assumed"));
                vec![default]
            } else {
                v.to_vec()
            }
        };
        let diameters_mm = pick(&g.diameters_mm, 25.4, "capstan diameter");
        let drive_v = pick(&g.drive_v, 10.0, "drive voltage");
        let wraps_deg = pick(&g.wraps_deg, 360.0, "wrap angle");
        // The simulator makes one cord per (wrap, diameter, voltage); the data's runs are shared
        // out over those so that the simulated campaign is as large as the data's.
        let cells = wraps_deg.len() * diameters_mm.len() * drive_v.len();
        let data_runs = (g.runs as f64 / cells as f64).round().max(1.0) as u32;
        let runs_per_cord = data_runs.min(MAX_RUNS_PER_CORD);
        if data_runs > MAX_RUNS_PER_CORD {
            assumed.push(format!(
                "the data's {data_runs} runs per cord are planned as {MAX_RUNS_PER_CORD}: \
                 a campaign of more would take the planner minutes per simulation, and \
                 decides at least as often"
            ));
        }
        if g.cords > cells {
            assumed.push(format!(
                "the data hold {} cords on {cells} (wrap, diameter, drive voltage) combinations; \
                 the simulator makes one cord per combination, so {} runs on each ({} in all, \
                 the data's {})",
                g.cords,
                runs_per_cord,
                runs_per_cord as usize * cells,
                g.runs
            ));
        } else if g.cords < cells {
            assumed.push(format!(
                "the data hold {} cords, not every combination of their wraps, diameters and \
                 drive voltages ({cells}); the simulator crosses them all, so the current design \
                 is planned as that crossing: {} runs on each of {cells} cords ({} in all, the \
                 data's {})",
                g.cords,
                runs_per_cord,
                runs_per_cord as usize * cells,
                g.runs
            ));
        }
        let order = if g.both_directions {
            StepOrder::UpDown
        } else {
            StepOrder::Monotone
        };
        let mut design = Design {
            order,
            runs_per_cord,
            wraps_deg,
            diameters_mm,
            drive_v,
        };
        crate::bounds::bound(&mut design, assumed);
        design
    }

    /// This design is the data's own: as many cords and runs on each (the data are a full
    /// crossing of their wraps, diameters and voltages, with no cap on their runs).
    pub fn is_the_datas(&self, d: &Diagnosis) -> bool {
        let g = &d.design;
        self.cords() == g.cords && self.runs_per_cord as usize * g.cords == g.runs
    }

    /// Cords: one per (wrap, diameter, drive voltage), as the simulator makes them.
    pub fn cords(&self) -> usize {
        self.wraps_deg.len() * self.diameters_mm.len() * self.drive_v.len()
    }

    /// What the campaign of this design offers the entries' testability conditions (the
    /// engine's facts of the data it would produce, for the fields those conditions read).
    pub fn facts(&self, protocol: &Protocol) -> Facts {
        let span = |v: &[f64]| {
            let max = v.iter().cloned().fold(f64::MIN, f64::max);
            let min = v.iter().cloned().fold(f64::MAX, f64::min);
            if v.is_empty() {
                0.0
            } else {
                max - min
            }
        };
        let cords = self.cords();
        let run_s = protocol.end_ms() as f64 / 1000.0;
        Facts {
            wraps: self.wraps_deg.len(),
            diameters: self.diameters_mm.len(),
            voltages: self.drive_v.len(),
            cords,
            runs: cords * self.runs_per_cord as usize,
            max_runs_per_cord: self.runs_per_cord as usize,
            max_time_spread_s: run_s,
            latest_time_s: run_s.max(1.0),
            run_span: self.runs_per_cord.saturating_sub(1) as f64,
            diameter_span_mm: span(&self.diameters_mm),
            voltage_span_v: span(&self.drive_v),
            max_load_n: 0.0,
            max_wrap_rad: (self.wraps_deg.iter().cloned().fold(0.0, f64::max)).to_radians(),
        }
    }

    /// Why a campaign of this design cannot test `kind` (its entry's condition), if it cannot.
    pub fn untestable(&self, kind: EffectKind, protocol: &Protocol) -> Option<&'static str> {
        (kind.entry().untestable)(&self.facts(protocol))
    }

    /// Rig time, h: every run's levels and dwell, and [`BETWEEN_RUNS_S`] between runs.
    pub fn rig_hours(&self, protocol: &Protocol) -> f64 {
        let run_s = protocol.end_ms() as f64 / 1000.0 + BETWEEN_RUNS_S;
        (self.cords() as f64 * self.runs_per_cord as f64 * run_s) / 3600.0
    }

    /// The `capstan simulate` arguments of the design (the protocol only: no effects, noise,
    /// seed or output).
    pub fn simulate_args(&self) -> Vec<String> {
        let list = |v: &[f64]| {
            v.iter()
                .map(|x| x.to_string())
                .collect::<Vec<_>>()
                .join(",")
        };
        let order = match self.order {
            StepOrder::UpDown => "updown",
            o => o.name(),
        };
        [
            ("--wraps", list(&self.wraps_deg)),
            ("--diameters", list(&self.diameters_mm)),
            ("--drive-v", list(&self.drive_v)),
            ("--runs", self.runs_per_cord.to_string()),
            ("--order", order.to_string()),
        ]
        .into_iter()
        .flat_map(|(k, v)| [k.to_string(), v])
        .collect()
    }
}

/// A candidate protocol: a design and how to get there from the data's.
#[derive(Clone, Debug, Serialize)]
pub struct Candidate {
    /// Short name.
    pub name: String,
    /// The design.
    #[serde(rename = "protocol")]
    pub design: Design,
    /// The `capstan rig` commands that set the protocol on the board.
    pub rig_commands: Vec<String>,
    /// What the person at the rig does with it (runs per cord, switching voltages).
    pub procedure: Vec<String>,
    /// What the user must change by hand (none for a protocol the firmware runs as is).
    pub physical_changes: Vec<String>,
}

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
