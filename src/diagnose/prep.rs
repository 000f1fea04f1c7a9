//! A data set arranged for the diagnosis: rows with their operating points, runs (the units
//! that share one mu), cords (the units the simulator and the rig scatter mu over), and which
//! optional columns are there.

use crate::data::Dataset;
use crate::fit::obs::Observations;
use crate::fit::stats::distinct;
use capstan_friction::Operating;

/// A cord: one (capstan diameter, drive voltage, wrap) combination, reused for its runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cord {
    /// Capstan diameter, mm (12.7 if the column is absent).
    pub diameter_mm: f64,
    /// Drive voltage, V (10 if the column is absent).
    pub drive_v: f64,
    /// Wrap, deg.
    pub wrap_deg: f64,
}

/// Which optional columns the data set has.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
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

/// Rows, runs and cords.
#[derive(Clone, Debug)]
pub struct Prepared {
    /// Measured T1, N.
    pub t1: Vec<f64>,
    /// Measured T2, N.
    pub t2: Vec<f64>,
    /// Operating point of each row (time = window centre).
    pub op: Vec<Operating>,
    /// Row indices of each unit. A unit is a run (cord + run number) when the `run` column is
    /// there, else a whole cord.
    pub units: Vec<Vec<usize>>,
    /// Cord of each unit.
    pub unit_cord: Vec<usize>,
    /// Run number of each unit (1 without the column).
    pub unit_run: Vec<f64>,
    /// The cords.
    pub cords: Vec<Cord>,
    /// Optional columns present.
    pub columns: Columns,
    /// The arrangement from `src/fit` (used for the population fits).
    pub obs: Observations,
}

impl Prepared {
    /// Arrange `d`. With `protocol_times`, a data set without `time_s` but with `step` gets the
    /// thesis protocol's window centres (10 k + 6 s) as its times.
    pub fn new(d: &Dataset, protocol_times: bool) -> Prepared {
        let obs = Observations::from_dataset(d);
        let columns = Columns {
            capstan_diameter_mm: d.has_column("capstan_diameter_mm"),
            drive_v: d.has_column("drive_v"),
            run: d.has_column("run"),
            step: d.has_column("step"),
            time_s: d.has_column("time_s") || (protocol_times && d.has_column("step")),
        };
        let mut cords: Vec<Cord> = Vec::new();
        let mut unit_keys: Vec<(usize, u64)> = Vec::new();
        let mut units: Vec<Vec<usize>> = Vec::new();
        let mut unit_cord = Vec::new();
        let mut unit_run = Vec::new();
        let (mut t1, mut t2, mut op) = (Vec::new(), Vec::new(), Vec::new());
        for (i, row) in obs.rows.iter().enumerate() {
            let cord = Cord {
                diameter_mm: row.op.diameter_mm,
                drive_v: row.op.drive_v,
                wrap_deg: row.op.wrap_rad.to_degrees(),
            };
            let c = match cords.iter().position(|k| {
                k.diameter_mm == cord.diameter_mm
                    && k.drive_v == cord.drive_v
                    && (k.wrap_deg - cord.wrap_deg).abs() < 1e-9
            }) {
                Some(c) => c,
                None => {
                    cords.push(cord);
                    cords.len() - 1
                }
            };
            let run = if columns.run { row.op.run } else { 1.0 };
            let key = (c, run.to_bits());
            let u = match unit_keys.iter().position(|k| *k == key) {
                Some(u) => u,
                None => {
                    unit_keys.push(key);
                    units.push(Vec::new());
                    unit_cord.push(c);
                    unit_run.push(run);
                    units.len() - 1
                }
            };
            units[u].push(i);
            t1.push(row.t1_n);
            t2.push(row.t2_n);
            let mut o = row.op;
            if !columns.time_s {
                o.time_s = 0.0;
            }
            op.push(o);
        }
        Prepared {
            t1,
            t2,
            op,
            units,
            unit_cord,
            unit_run,
            cords,
            columns,
            obs,
        }
    }

    /// Number of rows.
    pub fn n(&self) -> usize {
        self.t1.len()
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
        (0..self.cords.len())
            .map(|c| self.unit_cord.iter().filter(|&&k| k == c).count())
            .max()
            .unwrap_or(0)
    }

    /// Largest spread of time within a unit, s.
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
}
