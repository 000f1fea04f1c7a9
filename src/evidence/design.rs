//! A data set laid out for the evidence engine: rows with their operating points, runs (the
//! clusters that share one mu and one tare), cords (the units the rig scatters mu over), the
//! time order and step direction inside runs, the replicate cells that give the pure error,
//! and which optional columns are there.

use crate::data::Dataset;
use crate::fit::obs::{Observations, StepTiming, TimingSource};
use crate::fit::stats::distinct;
use capstan_friction::Operating;
use serde::Serialize;
use std::collections::HashMap;

/// A cord: one (capstan diameter, drive voltage, wrap) combination, reused for its runs.
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
    /// Row indices of each run, in time order (file order when times are not known). Without
    /// a `run` column a cord is one run.
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
    /// Per row: the measured T1 at which the law's shape is read (see [`shape_t1`]).
    pub t1_shape: Vec<f64>,
    /// Optional columns present.
    pub columns: Columns,
    /// The arrangement of `src/fit` (cords by diameter and wrap, for the population fits).
    pub obs: Observations,
}

/// The index of `key` in `list`, added if new (a hash map keeps it linear in the rows).
fn index_of<K: std::hash::Hash + Eq + Copy>(
    map: &mut HashMap<K, usize>,
    key: K,
    add: impl FnMut() -> usize,
) -> usize {
    *map.entry(key).or_insert_with(add)
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
        let mut cords: Vec<Cord> = Vec::new();
        let mut cord_keys: HashMap<[u64; 3], usize> = HashMap::new();
        let mut unit_keys: HashMap<(usize, u64), usize> = HashMap::new();
        let mut units: Vec<Vec<usize>> = Vec::new();
        let (mut unit_cord, mut unit_run) = (Vec::new(), Vec::new());
        let n = obs.rows.len();
        let (mut t1, mut t2, mut op, mut timing) = (
            Vec::with_capacity(n),
            Vec::with_capacity(n),
            Vec::with_capacity(n),
            Vec::with_capacity(n),
        );
        for (i, row) in obs.rows.iter().enumerate() {
            let cord = Cord {
                diameter_mm: row.op.diameter_mm,
                drive_v: row.op.drive_v,
                wrap_deg: d.pairs[i].wrap_deg,
            };
            let ck = [cord.diameter_mm, cord.drive_v, cord.wrap_deg].map(f64::to_bits);
            let c = index_of(&mut cord_keys, ck, || {
                cords.push(cord);
                cords.len() - 1
            });
            let run = if columns.run { row.op.run } else { 1.0 };
            let u = index_of(&mut unit_keys, (c, run.to_bits()), || {
                units.push(Vec::new());
                unit_cord.push(c);
                unit_run.push(run);
                units.len() - 1
            });
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
        let cell = cells(&units, &unit_cord, d, &obs);
        let t1_shape = shape_t1(&t1, &cell);
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
            t1_shape,
            columns,
            obs,
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

/// The T1 at which each row's law is read (its shape in tension, and the load the contact
/// remembers): the mean measured T1 of the other runs in its replicate cell; the row's own
/// where it has no cell or is alone in it (and, in the predictor, below
/// `fit::predict::SHAPE_MIN_T1_N`).
///
/// The servo sets the lever's travel, not T1: the cord is a spring on both sides of the
/// capstan, so where mu is momentarily higher (its wander inside a run) the same travel gives
/// less T1 and a little more T2. A shape read at a row's own T1 — the load memory of contact
/// heating, a power law in tension — follows that noise and takes part of the wander for an
/// effect; a drift in time, read from the clock, cannot. The other runs' mean at the same step
/// is set by the lever alone (their wander is independent of this row's): the law is read
/// there and its amplification applied to the row's own T1, the instrumental-variable fit of
/// the shape (leave-one-out, so the row's own noise is not in its instrument).
/// docs/README-diagnose.md has the measurements.
pub fn shape_t1(t1: &[f64], cell: &[Option<usize>]) -> Vec<f64> {
    let cells = cell.iter().flatten().map(|&c| c + 1).max().unwrap_or(0);
    let (mut sum, mut cnt) = (vec![0.0; cells], vec![0usize; cells]);
    for (i, c) in cell.iter().enumerate() {
        if let Some(c) = *c {
            if t1[i].is_finite() {
                sum[c] += t1[i];
                cnt[c] += 1;
            }
        }
    }
    (0..t1.len())
        .map(|i| match cell[i] {
            Some(c) if t1[i].is_finite() && cnt[c] >= 2 => (sum[c] - t1[i]) / (cnt[c] - 1) as f64,
            _ => t1[i],
        })
        .collect()
}

/// Replicate cells: the rows of a cord at the same step (or the same window time), across
/// its runs.
fn cells(
    units: &[Vec<usize>],
    unit_cord: &[usize],
    d: &Dataset,
    obs: &Observations,
) -> Vec<Option<usize>> {
    let n = obs.rows.len();
    let mut out = vec![None; n];
    let has_step = d.has_column("step");
    let has_time = d.has_column("time_s");
    if !(has_step || has_time) || !d.has_column("run") {
        return out;
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
            out[i] = Some(*keys.entry((unit_cord[u], k)).or_insert(next));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::shape_t1;

    #[test]
    fn the_shape_reading_is_the_other_runs_mean_at_the_step() {
        // Cell 0 holds three runs, cell 1 one, the last row has no cell.
        let t1 = [10.0, 11.0, 12.5, 4.0, 7.0];
        let cell = [Some(0), Some(0), Some(0), Some(1), None];
        let s = shape_t1(&t1, &cell);
        assert_eq!(s, vec![11.75, 11.25, 10.5, 4.0, 7.0]);
        // A non-finite reading is nobody's instrument and keeps its own value.
        let t1 = [10.0, f64::NAN, 12.0];
        let s = shape_t1(&t1, &[Some(0), Some(0), Some(0)]);
        assert_eq!((s[0], s[2]), (12.0, 10.0));
        assert!(s[1].is_nan());
    }
}
