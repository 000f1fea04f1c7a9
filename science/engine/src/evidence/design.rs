//! A data set laid out for the evidence engine: rows with their operating points, runs (the
//! clusters that share one mu and one tare), cords (the units the rig scatters mu over), the
//! time order and step direction inside runs, the replicate cells that give the pure error,
//! and which optional columns are there.

use crate::fit::obs::{Observations, StepTiming, TimingSource};
use crate::fit::stats::distinct;
use capstan_data::structure::StructureSummary;
use capstan_data::{Basis, Dataset};
use capstan_physics::Operating;
use serde::Serialize;
use std::collections::HashMap;

/// A cord: one (capstan diameter, drive voltage, wrap) combination (and its cord labels, see
/// [`capstan_data::Structure`]), reused for its runs.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Cord {
    /// Capstan diameter, mm (12.7 if the column is absent).
    pub diameter_mm: f64,
    /// Drive voltage, V (10 if the column is absent).
    pub drive_v: f64,
    /// Wrap, deg.
    pub wrap_deg: f64,
}

/// Which optional columns the data set has.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Columns {
    /// `capstan_diameter_mm`.
    pub capstan_diameter_mm: bool,
    /// `drive_v`.
    pub drive_v: bool,
    /// `run`.
    pub run: bool,
    /// `step`.
    pub step: bool,
    /// `time_s` (or times taken from `step` with the thesis protocol, when asked for).
    pub time_s: bool,
}

impl Columns {
    /// Is the named column present?
    pub fn has(&self, name: &str) -> bool {
        match name {
            "capstan_diameter_mm" => self.capstan_diameter_mm,
            "drive_v" => self.drive_v,
            "run" => self.run,
            "step" => self.step,
            "time_s" => self.time_s,
            _ => false,
        }
    }
}

/// Rows, runs, cords and their order.
#[derive(Clone, Debug)]
pub struct Design {
    /// Measured T1, N (any sign: a zero offset makes readings at or below zero real).
    pub t1: Vec<f64>,
    /// Measured T2, N.
    pub t2: Vec<f64>,
    /// Operating point of each row (time = window centre, 0 when times are not known).
    pub op: Vec<Operating>,
    /// Step timing of each row (for the load memory).
    pub timing: Vec<StepTiming>,
    /// The rows of each run carry their load memory from step to step (their time order and
    /// step timing are known).
    pub timed: bool,
    /// Row indices of each run, in time order (file order when times are not known): the runs
    /// of the data set's structure (without a `run` column inferred from `step` or `time_s`
    /// restarting, or each cord taken as one run).
    pub units: Vec<Vec<usize>>,
    /// Cord of each run.
    pub unit_cord: Vec<usize>,
    /// Run number of each run (1 without the column).
    pub unit_run: Vec<f64>,
    /// The cords.
    pub cords: Vec<Cord>,
    /// Per row: the tension fell from the previous step of its run (None: order unknown).
    pub falling: Vec<Option<bool>>,
    /// Per row: its replicate cell (cord × step, shared by the cord's runs), if steps are known.
    pub cell: Vec<Option<usize>>,
    /// Per cell: its step (the step number × 1000, or the window time × 10, rounded): the cells
    /// of different cords at one step.
    pub cell_step: Vec<i64>,
    /// Per row: the measured T1 at which the law's shape is read, NaN where the row keeps its
    /// own (see [`shape_t1`]).
    pub t1_shape: Vec<f64>,
    /// Optional columns present.
    pub columns: Columns,
    /// The arrangement of [`crate::fit`] (cords by diameter and wrap, for the population fits).
    pub obs: Observations,
    /// Where the data set came from.
    pub source: String,
    /// How its rows map to cords and runs, and how that was found.
    pub structure: StructureSummary,
}

impl Design {
    /// Lay out `d`. With `protocol_times`, a data set without `time_s` but with `step` gets the
    /// thesis protocol's window centres (10 k + 6 s) as its times.
    pub fn new(d: &Dataset, protocol_times: bool) -> Design {
        let obs = Observations::from_dataset(d);
        let columns = Columns {
            capstan_diameter_mm: d.has_column("capstan_diameter_mm"),
            drive_v: d.has_column("drive_v"),
            run: d.has_column("run"),
            step: d.has_column("step"),
            time_s: d.has_column("time_s") || (protocol_times && d.has_column("step")),
        };
        let timed = obs.timing != TimingSource::None;
        // Cords and runs as the data set's structure says (the same for every command).
        let st = &d.structure;
        let cords: Vec<Cord> = st
            .cords
            .iter()
            .map(|c| Cord {
                diameter_mm: c.diameter_mm,
                drive_v: c.drive_v,
                wrap_deg: c.wrap_deg,
            })
            .collect();
        let unit_cord = st.run_cord.clone();
        let mut units: Vec<Vec<usize>> = vec![Vec::new(); unit_cord.len()];
        let mut unit_run = vec![1.0; unit_cord.len()];
        let n = obs.rows.len();
        let (mut t1, mut t2, mut op, mut timing) = (
            Vec::with_capacity(n),
            Vec::with_capacity(n),
            Vec::with_capacity(n),
            Vec::with_capacity(n),
        );
        for (i, row) in obs.rows.iter().enumerate() {
            let u = st.run_of_row[i];
            if columns.run {
                unit_run[u] = row.op.run;
            }
            units[u].push(i);
            t1.push(row.t1_n);
            t2.push(row.t2_n);
            let mut o = row.op;
            if !columns.time_s {
                o.time_s = 0.0;
            }
            op.push(o);
            timing.push(row.timing);
        }
        if timed {
            for u in &mut units {
                u.sort_by(|&a, &b| timing[a].centre_s.total_cmp(&timing[b].centre_s));
            }
        }
        let falling = directions(&units, &t1, timed);
        let (cell, cell_step) = cells(&units, &unit_cord, d, &obs);
        let t1_shape = shape_t1(&t1, &cell, &units);
        Design {
            t1,
            t2,
            op,
            timing,
            timed,
            units,
            unit_cord,
            unit_run,
            cords,
            falling,
            cell,
            cell_step,
            t1_shape,
            columns,
            obs,
            source: d.source.clone(),
            structure: d.structure.summary(),
        }
    }

    /// Number of rows.
    pub fn n(&self) -> usize {
        self.t1.len()
    }

    /// Rows whose T1 and T2 are both above zero (the ones a logarithm can take).
    pub fn positive_rows(&self) -> usize {
        (0..self.n())
            .filter(|&i| self.t1[i] > 0.0 && self.t2[i] > 0.0)
            .count()
    }

    /// Distinct wraps, deg.
    pub fn wraps(&self) -> Vec<f64> {
        distinct(self.cords.iter().map(|c| c.wrap_deg))
    }

    /// Distinct diameters, mm.
    pub fn diameters(&self) -> Vec<f64> {
        distinct(self.cords.iter().map(|c| c.diameter_mm))
    }

    /// Distinct drive voltages, V.
    pub fn voltages(&self) -> Vec<f64> {
        distinct(self.cords.iter().map(|c| c.drive_v))
    }

    /// Largest number of runs on one cord.
    pub fn max_runs_per_cord(&self) -> usize {
        let mut count = vec![0usize; self.cords.len()];
        for &c in &self.unit_cord {
            count[c] += 1;
        }
        count.into_iter().max().unwrap_or(0)
    }

    /// Largest spread of time within a run, s.
    pub fn max_time_spread_s(&self) -> f64 {
        self.units
            .iter()
            .map(|u| {
                let (lo, hi) = u.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, &i| {
                    (a.0.min(self.op[i].time_s), a.1.max(self.op[i].time_s))
                });
                hi - lo
            })
            .fold(0.0, f64::max)
    }

    /// Does the step direction vary inside runs (both rising and falling steps)?
    pub fn has_both_directions(&self) -> bool {
        let fall = self.falling.iter().filter(|f| **f == Some(true)).count();
        let rise = self.falling.iter().filter(|f| **f == Some(false)).count();
        fall >= 2 && rise >= 2
    }

    /// Number of replicate cells with at least two runs.
    pub fn replicated_cells(&self) -> usize {
        let mut count = HashMap::new();
        for c in self.cell.iter().flatten() {
            *count.entry(*c).or_insert(0usize) += 1;
        }
        count.values().filter(|&&k| k >= 2).count()
    }
}

/// Step direction of each row from the measured T1 of consecutive steps of its run: the first
/// step rises from rest. Unknown when the time order is not.
fn directions(units: &[Vec<usize>], t1: &[f64], timed: bool) -> Vec<Option<bool>> {
    let mut out = vec![None; t1.len()];
    if !timed {
        return out;
    }
    for u in units {
        let mut prev: Option<f64> = None;
        for &i in u {
            out[i] = Some(prev.is_some_and(|p| t1[i] < p));
            prev = Some(t1[i]);
        }
    }
    out
}

/// Rows whose measured T1, or whose shape reading, is below this (N) keep their own T1 (NaN in
/// [`Design::t1_shape`]). At low tension a run's zero error (~0.1 N on the thesis rig) moves T1
/// by more than the wander does, and the shapes that live there (the lift-off of a stiff cord,
/// offsets) are better read at the row's own reading; the wander's pull on a shape read at the
/// row's T1 is largest late in rising runs, at high tension. Chosen on the calibration seed (99)
/// from 2, 4 and 8 N, for this rig's tensions (docs/README-diagnose.md). Decided on the
/// measured readings, so whether a row is read at its shape point does not move with a fitted
/// T1 offset.
pub const SHAPE_MIN_T1_N: f64 = 8.0;

/// The measured T1 at which each row's law is read (its shape in tension, and the load the
/// contact remembers), NaN where the row keeps its own: the mean T1 of the *other runs* in its
/// replicate cell, brought to the row's run's own level (times exp of the run's mean of
/// ln(T1/that mean) over its rows read this way).
///
/// The servo sets the lever's travel, not T1: the cord is a spring on both sides of the
/// capstan, so where mu is momentarily higher (its wander inside a run) the same travel gives
/// less T1 and a little more T2. A shape read at a row's own T1 — the load memory of contact
/// heating, a power law in tension — follows that noise and takes part of the wander for an
/// effect; a drift in time, read from the clock, cannot. The other runs at the same step are
/// moved by the lever alone as far as this row's wander goes; the run's own level is kept (a
/// run's mu, and a real rig's setup, set it; every run has its own mu anyway). The law is read
/// there and its amplification applied to the row's own T1. (A nonlinear law evaluated at a
/// substitute regressor is not a textbook instrumental-variable estimator; it is measured on
/// planted truth in docs/README-diagnose.md.)
pub fn shape_t1(t1: &[f64], cell: &[Option<usize>], units: &[Vec<usize>]) -> Vec<f64> {
    let cells = cell.iter().flatten().map(|&c| c + 1).max().unwrap_or(0);
    let (mut sum, mut cnt) = (vec![0.0; cells], vec![0usize; cells]);
    // The same sums per run, to leave the row's whole run out (a step number may repeat).
    let mut own: HashMap<(usize, usize), (f64, usize)> = HashMap::new();
    for (u, rows) in units.iter().enumerate() {
        for &i in rows {
            if let (Some(c), true) = (cell[i], t1[i].is_finite()) {
                sum[c] += t1[i];
                cnt[c] += 1;
                let e = own.entry((c, u)).or_insert((0.0, 0));
                e.0 += t1[i];
                e.1 += 1;
            }
        }
    }
    let mut out = vec![f64::NAN; t1.len()];
    for (u, rows) in units.iter().enumerate() {
        let others = |i: usize| -> Option<f64> {
            let c = cell[i]?;
            let (s, n) = own.get(&(c, u)).copied().unwrap_or((0.0, 0));
            let m = cnt[c].checked_sub(n).filter(|&m| m > 0)?;
            let mean = (sum[c] - s) / m as f64;
            (t1[i] >= SHAPE_MIN_T1_N && mean >= SHAPE_MIN_T1_N).then_some(mean)
        };
        let read: Vec<(usize, f64)> = rows
            .iter()
            .filter_map(|&i| others(i).map(|m| (i, m)))
            .collect();
        if read.is_empty() {
            continue;
        }
        let level = read.iter().map(|&(i, m)| (t1[i] / m).ln()).sum::<f64>() / read.len() as f64;
        for (i, m) in read {
            out[i] = m * level.exp();
        }
    }
    out
}

/// Replicate cells: the rows of a cord at the same step (or the same window time), across
/// its runs.
fn cells(
    units: &[Vec<usize>],
    unit_cord: &[usize],
    d: &Dataset,
    obs: &Observations,
) -> (Vec<Option<usize>>, Vec<i64>) {
    let n = obs.rows.len();
    let mut out = vec![None; n];
    let mut step = Vec::new();
    let has_step = d.has_column("step");
    let has_time = d.has_column("time_s");
    if !(has_step || has_time) || d.structure.run_level.from == Basis::Assumed {
        return (out, step);
    }
    let mut keys: HashMap<(usize, i64), usize> = HashMap::new();
    for (u, rows) in units.iter().enumerate() {
        for &i in rows {
            let k = match (has_step, d.pairs[i].step, d.pairs[i].time_s) {
                (true, Some(s), _) => (s * 1000.0).round() as i64,
                (_, _, Some(t)) => (t * 10.0).round() as i64,
                _ => continue,
            };
            let next = keys.len();
            let c = *keys.entry((unit_cord[u], k)).or_insert(next);
            if c == step.len() {
                step.push(k);
            }
            out[i] = Some(c);
        }
    }
    (out, step)
}

#[cfg(test)]
mod tests {
    use super::shape_t1;

    #[test]
    fn the_shape_reading_is_the_other_runs_mean_at_the_runs_own_level() {
        // Three runs over two steps (cells 0 and 1); run 2 repeats step 1 (a repeated step
        // number); run 3 sits ~10 % low.
        let t1 = [10.0, 20.0, 10.0, 10.4, 20.0, 9.0, 17.64];
        let cell = [
            Some(0),
            Some(1),
            Some(0),
            Some(0),
            Some(1),
            Some(0),
            Some(1),
        ];
        let units = vec![vec![0, 1], vec![2, 3, 4], vec![5, 6]];
        let s = shape_t1(&t1, &cell, &units);
        // Run 2's own rows at step 1 are not in its instrument: runs 1 and 3 give 9.5.
        let level2 = ((10.0f64 / 9.5).ln() + (10.4f64 / 9.5).ln() + (20.0f64 / 18.82).ln()) / 3.0;
        assert!((s[2] - 9.5 * level2.exp()).abs() < 1e-12);
        // Run 3: the other runs' means, at its own level (its mean ln(T1/mean) is 0 after).
        let m: [f64; 2] = [(10.0 + 10.0 + 10.4) / 3.0, 20.0];
        let level3 = ((9.0 / m[0]).ln() + (17.64 / m[1]).ln()) / 2.0;
        assert!((s[5] - m[0] * level3.exp()).abs() < 1e-12);
        assert!((s[6] - m[1] * level3.exp()).abs() < 1e-12);
        assert!(((t1[5] / s[5]).ln() + (t1[6] / s[6]).ln()).abs() < 1e-12);
        // A row below the floor, or alone in its cell, keeps its own T1 (NaN).
        assert!(s.iter().all(|v| v.is_finite()));
        let cells = [Some(0), Some(1), Some(0), Some(1)];
        let low = shape_t1(&[5.0, 20.0, 5.0, 20.0], &cells, &[vec![0, 1], vec![2, 3]]);
        assert!(low[0].is_nan() && low[2].is_nan() && low[1] == 20.0 && low[3] == 20.0);
        let alone = shape_t1(&[20.0, 20.0], &[Some(0), None], &[vec![0], vec![1]]);
        assert!(alone.iter().all(|v| v.is_nan()));
    }
}
