//! What bounds the planner's work on any data: the simulated campaign is at most
//! [`MAX_CAMPAIGN_RUNS`] runs on at most [`MAX_WRAPS`] × [`MAX_DIAMETERS`] × [`MAX_VOLTAGES`]
//! cords, whatever the data hold (a 720-cord file planned its campaigns, and its cords
//! question's sets of up to 8× them, at the data's size: past 9 minutes); and the world the
//! campaigns are simulated in is one the simulator takes, or the plan is refused in one
//! sentence that says which number of the data is out of range.

use crate::candidates::Design;
use crate::world::{campaign, World};
use capstan_engine::diagnose::Diagnosis;
use capstan_sim::campaign::CampaignError;

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

/// The world and design as the simulator takes them, or the plan refused in one sentence: the
/// quantity, its value, the range the simulator takes and what in the data gave it.
pub fn check(design: &Design, world: &World, d: &Diagnosis) -> Result<(), String> {
    let cfg = campaign(design, &[], world, 1);
    match cfg.validate() {
        Ok(()) => Ok(()),
        Err(CampaignError::Bad(what, value, allowed)) => {
            let source = match what {
                "scatter (%)" => format!(
                    "the cord-to-cord scatter of mu these data show ({:.0} % of their mu {:.4}, \
                     from {} cords): cords this different are not one material on one rig — \
                     check the cord labels, the units and which column is T1",
                    d.scatter.cord_pct, d.baseline.mu, d.design.cords
                ),
                "run scatter (%)" => format!(
                    "the run-to-run scatter of mu within cords these data show ({:.0} % of \
                     their mu {:.4}): runs this different are not repeats of one cord — \
                     check the run labels and the units",
                    d.scatter.run_pct, d.baseline.mu
                ),
                _ => "the design these data describe".to_string(),
            };
            Err(format!(
                "cannot plan on these data: the simulated campaigns would need {what} = \
                 {value:.4}, but the simulator takes {}; it comes from {source}",
                allowed.trim_start_matches("must be ")
            ))
        }
        Err(e) => Err(format!(
            "cannot plan on these data: their design cannot be simulated ({e})"
        )),
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
