//! A design (what is run, on what, how often) and a candidate protocol, and what bounds the
//! planner's work on any data: the simulated campaign is at most
//! [`MAX_CAMPAIGN_RUNS`] runs on at most [`MAX_WRAPS`] × [`MAX_DIAMETERS`] × [`MAX_VOLTAGES`]
//! cords, whatever the data hold (a 720-cord file planned its campaigns, and its cords
//! question's sets of up to 8× them, at the data's size: past 9 minutes); (the world the
//! campaigns are simulated in is checked in [`crate::world::check`]).

use capstan_engine::diagnose::Diagnosis;
use capstan_physics::{EffectKind, Facts};
use capstan_rig::{Protocol, StepOrder};
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
        bound(&mut design, assumed);
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

/// The most runs one simulated campaign of the data's design holds (twice the thesis's 60):
/// a larger design is planned at this size, with fewer runs on each cord, and says so.
pub const MAX_CAMPAIGN_RUNS: u32 = 120;
/// The most wrap angles a simulated design keeps.
pub const MAX_WRAPS: usize = 6;
/// The most capstan diameters a simulated design keeps.
pub const MAX_DIAMETERS: usize = 3;
/// The most drive voltages a simulated design keeps.
pub const MAX_VOLTAGES: usize = 3;

/// The most cords of data on which the cords question is asked: it runs the whole analysis
/// (its fits held out cord by cord) on the data first, which grows with their cords (35 s
/// for 720 cords in a release build), and data with this many cords have answered it.
pub const MAX_CORDS_ASKED: usize = 60;

/// At most `max` of the sorted `values`: the smallest, the largest and evenly spaced ranks
/// between (so the span, which the testability conditions read, is kept).
pub fn spread(values: &[f64], max: usize) -> Vec<f64> {
    let mut values = values.to_vec();
    values.sort_by(f64::total_cmp);
    if values.len() <= max || max < 2 {
        values.truncate(max.max(1));
        return values;
    }
    let last = values.len() - 1;
    let mut out: Vec<f64> = (0..max)
        .map(|i| values[(i * last + (max - 1) / 2) / (max - 1)])
        .collect();
    out.dedup();
    out
}

/// `design` within the bounds; what was cut goes to `assumed`, in words.
pub fn bound(design: &mut Design, assumed: &mut Vec<String>) {
    for (what, list, max) in [
        ("wrap angles", &mut design.wraps_deg, MAX_WRAPS),
        ("capstan diameters", &mut design.diameters_mm, MAX_DIAMETERS),
        ("drive voltages", &mut design.drive_v, MAX_VOLTAGES),
    ] {
        if list.len() > max {
            let kept = spread(list, max);
            assumed.push(format!(
                "the data's {} {what} are simulated as {} of them ({}): the smallest, the \
                 largest and evenly spaced between, so that a simulated campaign stays bounded",
                list.len(),
                kept.len(),
                kept.iter()
                    .map(|x| x.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
            *list = kept;
        }
    }
    let cells = design.cords() as u32;
    let most = (MAX_CAMPAIGN_RUNS / cells.max(1)).max(1);
    if design.runs_per_cord > most {
        assumed.push(format!(
            "a simulated campaign holds at most {MAX_CAMPAIGN_RUNS} runs: the data's design is \
             planned with {most} runs on each of its {cells} cords, not {} (a larger campaign \
             decides at least as often)",
            design.runs_per_cord
        ));
        design.runs_per_cord = most;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use capstan_rig::StepOrder;

    #[test]
    fn spread_keeps_the_ends_and_spaces_the_rest() {
        let v: Vec<f64> = (0..720).map(|i| 90.0 + i as f64).collect();
        let s = spread(&v, 6);
        assert_eq!(s.len(), 6);
        assert_eq!(s[0], 90.0);
        assert_eq!(s[5], 809.0);
        assert_eq!(spread(&[1.0, 2.0], 6), vec![1.0, 2.0]);
    }

    #[test]
    fn a_design_of_720_wraps_and_24_runs_is_bounded() {
        let mut d = Design {
            order: StepOrder::Monotone,
            runs_per_cord: 24,
            wraps_deg: (0..720).map(|i| 90.0 + i as f64).collect(),
            diameters_mm: vec![12.7, 19.0, 25.4, 31.0],
            drive_v: vec![10.0],
        };
        let mut assumed = Vec::new();
        bound(&mut d, &mut assumed);
        // 6 wraps × 3 diameters = 18 cords, 6 runs each: 108 runs, not 69,120.
        assert_eq!((d.wraps_deg.len(), d.diameters_mm.len()), (6, 3));
        assert_eq!(d.runs_per_cord, 6);
        assert_eq!(d.diameters_mm, vec![12.7, 25.4, 31.0]);
        assert_eq!(assumed.len(), 3, "{assumed:?}");
        // The thesis's design (10 cords × 6 runs) is left as it is.
        let mut t = Design {
            order: StepOrder::Monotone,
            runs_per_cord: 6,
            wraps_deg: vec![270.0, 360.0, 450.0, 540.0, 720.0],
            diameters_mm: vec![12.7, 25.4],
            drive_v: vec![10.0],
        };
        let before = t.clone();
        bound(&mut t, &mut assumed);
        assert_eq!(t, before);
    }
}
