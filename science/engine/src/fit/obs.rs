//! Measured pairs arranged for fitting: groups (cords), runs in time order, step timing.
//!
//! * A **group** is one cord: one (capstan diameter, wrap, drive voltage) combination and its
//!   cord labels. The thesis fitted a new cord for each and reused it for its runs, so
//!   cord-to-cord variation lives at this level.
//! * A **run** is one pass of the step protocol on one cord.
//!   The contact's load memory H ([`capstan_physics::LoadMemory`]) starts at zero at the
//!   start of each run and is carried from step to step.
//! * **Step timing.** With a `time_s` column (the centre of each conditioning window) the
//!   step changes are reconstructed from the protocol's conditioning rule (window from 2 s
//!   after a change to 1 s before the next, so the centre is (dwell + 1)/2 after the change),
//!   with the dwell taken from the spacing of consecutive centres. Without `time_s` but with
//!   `step` k, the thesis protocol gives the times: the step starts at 10k + 0.5 s after the
//!   trigger, its window centre is at 10k + 6 s and it ends at 10(k+1) + 0.5 s. Without
//!   either, the rows carry no load history (each starts from a cold contact).
//!
//! Cords and runs are the data set's structure ([`capstan_data::Structure`]): the same for
//! `analyze` and `diagnose`. Missing optional columns take the reference values of
//! `capstan_physics` (12.7 mm, 10 V, run 1), as the structure says.

use capstan_data::Dataset;
use capstan_physics::Operating;

/// When a step's tension was set, measured and left, s since the trigger.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepTiming {
    /// The servo moved to this step.
    pub change_s: f64,
    /// Centre of the conditioning window (the time the pair stands for).
    pub centre_s: f64,
    /// The servo moved on to the next step.
    pub end_s: f64,
}

impl StepTiming {
    /// The thesis protocol: step k (1-based, first kept step) changes at 10k + 0.5 s.
    pub fn thesis_step(step: f64) -> Self {
        StepTiming {
            change_s: 10.0 * step + 0.5,
            centre_s: 10.0 * step + 6.0,
            end_s: 10.0 * step + 10.5,
        }
    }
}

/// Where the step times came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TimingSource {
    /// The `time_s` column.
    TimeColumn,
    /// Reconstructed from `step` with the thesis protocol (10 s steps).
    ThesisProtocolFromStep,
    /// No timing: the rows of a run carry no load memory from one to the next.
    None,
}

/// One measured pair, ready for the models.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// Measured T1, N.
    pub t1_n: f64,
    /// Measured T2, N.
    pub t2_n: f64,
    /// Operating point (time = window centre; `load_memory_ns` is filled by the predictor).
    pub op: Operating,
    /// Group (cord) index.
    pub group: usize,
    /// Run index (into [`Observations::runs`]).
    pub run: usize,
    /// Step timing.
    pub timing: StepTiming,
    /// Step index if known.
    pub step: Option<f64>,
}

/// A cord: one (diameter, wrap) pair.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Group {
    /// e.g. `D12.7/270deg`.
    pub label: String,
    /// Capstan diameter, mm.
    pub diameter_mm: f64,
    /// Wrap, degrees.
    pub wrap_deg: f64,
}

/// All rows with their grouping.
#[derive(Clone, Debug, PartialEq)]
pub struct Observations {
    /// Rows in file order.
    pub rows: Vec<Row>,
    /// Cords, sorted by diameter then wrap.
    pub groups: Vec<Group>,
    /// Each run's row indices in time order.
    pub runs: Vec<Vec<usize>>,
    /// How step times were obtained.
    pub timing: TimingSource,
}

impl Observations {
    /// Arrange a data set: its cords and runs as its structure says ([`Dataset::structure`],
    /// the same for every command), cords sorted by diameter, wrap, voltage and labels.
    pub fn from_dataset(d: &Dataset) -> Self {
        let timing = if d.has_column("time_s") {
            TimingSource::TimeColumn
        } else if d.has_column("step") {
            TimingSource::ThesisProtocolFromStep
        } else {
            TimingSource::None
        };
        let st = &d.structure;
        let (groups, group_of_cord) = groups_in_order(st);
        let rows: Vec<Row> = (d.pairs.iter().enumerate())
            .map(|(i, p)| {
                let c = st.cord_of_row[i];
                let mut row = row_of(p, &st.cords[c], timing);
                (row.group, row.run) = (group_of_cord[c], st.run_of_row[i]);
                row
            })
            .collect();
        let mut obs = Observations {
            runs: runs_in_time_order(&rows, st.run_cord.len()),
            rows,
            groups,
            timing,
        };
        if timing == TimingSource::TimeColumn {
            obs.time_steps_by_spacing();
        }
        obs
    }

    /// With a time column, each row's step from the spacing of its run's window centres: the
    /// dwell is the gap to the next centre (the previous for a run's last, 10 s alone or when
    /// under 1 s), and centre = change + (dwell + 1)/2.
    fn time_steps_by_spacing(&mut self) {
        for run in &self.runs {
            let centres: Vec<f64> = run.iter().map(|&i| self.rows[i].timing.centre_s).collect();
            for (k, &i) in run.iter().enumerate() {
                let dwell = if k + 1 < run.len() {
                    centres[k + 1] - centres[k]
                } else if k > 0 {
                    centres[k] - centres[k - 1]
                } else {
                    10.0
                };
                let dwell = if dwell > 1.0 { dwell } else { 10.0 };
                let c = centres[k];
                let change = c - 0.5 * (dwell + 1.0);
                self.rows[i].timing = StepTiming {
                    change_s: change,
                    centre_s: c,
                    end_s: change + dwell,
                };
            }
        }
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// True if there are no rows.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// Indices of the runs whose cord is not `group` (a leave-one-group-out training set).
    pub fn runs_without_group(&self, group: usize) -> Vec<usize> {
        (0..self.runs.len())
            .filter(|&r| self.rows[self.runs[r][0]].group != group)
            .collect()
    }

    /// Indices of every run.
    pub fn all_runs(&self) -> Vec<usize> {
        (0..self.runs.len()).collect()
    }

    /// Row indices of the given runs, in run order.
    pub fn rows_of(&self, runs: &[usize]) -> Vec<usize> {
        runs.iter()
            .flat_map(|&r| self.runs[r].iter().copied())
            .collect()
    }

    /// Group of every row.
    pub fn group_of_rows(&self) -> Vec<usize> {
        self.rows.iter().map(|r| r.group).collect()
    }

    /// Indices of the runs on cord `group`.
    pub fn runs_of_group(&self, group: usize) -> Vec<usize> {
        (0..self.runs.len())
            .filter(|&r| self.rows[self.runs[r][0]].group == group)
            .collect()
    }

    /// Indices of the rows on cord `group`, in file order.
    pub fn rows_of_group(&self, group: usize) -> Vec<usize> {
        (0..self.rows.len())
            .filter(|&i| self.rows[i].group == group)
            .collect()
    }

    /// The capstan diameters of the cords, ascending, mm.
    pub fn diameters(&self) -> Vec<f64> {
        crate::fit::stats::distinct(self.groups.iter().map(|g| g.diameter_mm))
    }

    /// RMSE of predicted against measured T2 over the rows where the prediction is finite, N.
    pub fn rmse_t2(&self, pred: &[f64]) -> f64 {
        let (mut s, mut n) = (0.0, 0usize);
        for (r, p) in self.rows.iter().zip(pred) {
            if p.is_finite() {
                s += (p - r.t2_n).powi(2);
                n += 1;
            }
        }
        (s / n as f64).sqrt()
    }
}

/// The cords as groups, sorted by diameter, wrap, voltage and labels, and each cord's group.
fn groups_in_order(st: &capstan_data::Structure) -> (Vec<Group>, Vec<usize>) {
    let mut order: Vec<usize> = (0..st.cords.len()).collect();
    order.sort_by(|&a, &b| {
        let (x, y) = (&st.cords[a], &st.cords[b]);
        x.diameter_mm
            .total_cmp(&y.diameter_mm)
            .then(x.wrap_deg.total_cmp(&y.wrap_deg))
            .then(x.drive_v.total_cmp(&y.drive_v))
            .then(x.labels.cmp(&y.labels))
    });
    let mut group_of_cord = vec![0; st.cords.len()];
    for (g, &c) in order.iter().enumerate() {
        group_of_cord[c] = g;
    }
    let groups: Vec<Group> = order
        .iter()
        .map(|&c| Group {
            label: st.cord_label(c),
            diameter_mm: st.cords[c].diameter_mm,
            wrap_deg: st.cords[c].wrap_deg,
        })
        .collect();
    (groups, group_of_cord)
}

/// One pair as a row of its cord (group and run 0: the caller sets them), its step timed by
/// the thesis's protocol from its step, by its time (a 10 s step, the window centred 5.5 s
/// after the change, until the spacing says better), or as the protocol's first step.
fn row_of(
    p: &capstan_data::Pair,
    cord: &capstan_data::structure::CordKey,
    timing: TimingSource,
) -> Row {
    let timing_row = match (timing, p.time_s, p.step) {
        (TimingSource::ThesisProtocolFromStep, _, Some(k)) => StepTiming::thesis_step(k),
        (TimingSource::TimeColumn, Some(t), _) => StepTiming {
            change_s: t - 5.5,
            centre_s: t,
            end_s: t + 4.5,
        },
        _ => StepTiming::thesis_step(1.0),
    };
    Row {
        t1_n: p.t1_n,
        t2_n: p.t2_n,
        op: Operating {
            wrap_rad: p.wrap_rad(),
            diameter_mm: cord.diameter_mm,
            drive_v: cord.drive_v,
            run: p.run.unwrap_or(1.0),
            time_s: timing_row.centre_s,
            load_memory_ns: 0.0,
        },
        group: 0,
        run: 0,
        timing: timing_row,
        step: p.step,
    }
}

/// Each of `n` runs' row indices, sorted by window centre.
fn runs_in_time_order(rows: &[Row], n: usize) -> Vec<Vec<usize>> {
    let mut runs: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (i, r) in rows.iter().enumerate() {
        runs[r.run].push(i);
    }
    for run in &mut runs {
        run.sort_by(|&a, &b| rows[a].timing.centre_s.total_cmp(&rows[b].timing.centre_s));
    }
    runs
}

#[cfg(test)]
mod tests {
    use super::*;
    use capstan_data::{read_pairs, thesis_dataset};

    #[test]
    fn thesis_has_ten_cords_sixty_runs_and_protocol_times() {
        let o = Observations::from_dataset(&thesis_dataset());
        assert_eq!(o.groups.len(), 10);
        assert_eq!(o.runs.len(), 60);
        assert!(o.runs.iter().all(|r| r.len() == 12));
        assert_eq!(o.timing, TimingSource::ThesisProtocolFromStep);
        let r = &o.rows[1]; // step 2
        assert_eq!((r.timing.change_s, r.timing.centre_s), (20.5, 26.0));
        assert_eq!(o.groups[0].label, "D12.7/270deg");
    }

    #[test]
    fn time_column_gives_the_same_timing_as_the_protocol() {
        let csv = "wrap_deg,run,time_s,t1_n,t2_n\n270,1,16,1,2\n270,1,26,2,4\n270,1,36,3,6\n";
        let o = Observations::from_dataset(&read_pairs(csv.as_bytes(), "t").unwrap());
        assert_eq!(o.timing, TimingSource::TimeColumn);
        for (k, r) in o.rows.iter().enumerate() {
            assert_eq!(r.timing, StepTiming::thesis_step(k as f64 + 1.0));
        }
    }
}
