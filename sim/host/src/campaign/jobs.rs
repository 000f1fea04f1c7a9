//! A campaign expanded into its runs: every (diameter, voltage, wrap) cord, `runs` times, each
//! with its own seed, its mu drawn from the cord's and the run's scatter, its protocol, plant
//! constants and injections; checked before any thread starts.

use super::{CampaignConfig, CampaignError, CordKey};
use crate::run::{RunSpec, SetupError};
use crate::setup;
use capstan_plant::{CordSetup, Injection};
use capstan_rng::{derive_seed, Rng};

/// One run to make, before it is made.
#[derive(Clone, Debug)]
pub(super) struct Job {
    /// Position in the campaign, from 1.
    pub index: u32,
    /// Its cord.
    pub cord: CordKey,
    /// Repeat run on the cord, from 1.
    pub run: u32,
    /// Everything the run needs.
    pub spec: RunSpec,
}

impl CampaignConfig {
    /// Number of runs the campaign makes.
    pub fn run_count(&self) -> usize {
        self.diameters_mm.len() * self.drive_vs.len() * self.wraps_deg.len() * self.runs as usize
    }

    /// Check everything that can be checked before running.
    pub fn validate(&self) -> Result<(), CampaignError> {
        self.check()
    }

    /// Check the configuration, and let the firmware and the plant refuse a bad setup before
    /// any thread starts.
    pub(super) fn check(&self) -> Result<(), CampaignError> {
        use CampaignError::*;
        for (what, list) in [
            ("diameters_mm", &self.diameters_mm),
            ("wraps_deg", &self.wraps_deg),
            ("drive_vs", &self.drive_vs),
        ] {
            if list.is_empty() {
                return Err(Empty(what));
            }
        }
        if self.runs == 0 {
            return Err(Bad("runs", 0.0, "at least 1".into()));
        }
        let bad = |e: setup::OutOfRange| Bad(e.what, e.value, e.allowed);
        for &d in &self.diameters_mm {
            setup::check_diameter(d).map_err(bad)?;
        }
        for &w in &self.wraps_deg {
            setup::check_wrap(w).map_err(bad)?;
        }
        for &v in &self.drive_vs {
            setup::check_drive_v(v, &self.calibration).map_err(bad)?;
        }
        if !(self.scatter_pct.is_finite() && (0.0..=50.0).contains(&self.scatter_pct)) {
            return Err(Bad(
                "scatter (%)",
                self.scatter_pct,
                "must be 0 to 50".into(),
            ));
        }
        let run_scatter_pct = self.run_scatter();
        if !(run_scatter_pct.is_finite() && (0.0..=50.0).contains(&run_scatter_pct)) {
            return Err(Bad(
                "run scatter (%)",
                run_scatter_pct,
                "must be 0 to 50".into(),
            ));
        }
        let n = self.run_count();
        if n > u32::MAX as usize {
            return Err(Bad(
                "runs",
                n as f64,
                "at most 4294967295 runs in all".into(),
            ));
        }
        for f in &self.faults {
            if let Some(r) = f.run.filter(|&r| r as usize > n) {
                return Err(FaultRun(r, n as u32));
            }
        }
        let j = self.job(0);
        capstan_rig::Rig::new(j.spec.protocol, j.spec.calibration, j.spec.limits)
            .map_err(|e| Setup(SetupError::Protocol(e)))?;
        capstan_plant::Plant::new_at(j.spec.plant, &[j.spec.cord], 0, 0)
            .map_err(|e| Setup(SetupError::Plant(e)))?;
        if self.faults.len() > capstan_plant::MAX_INJECTIONS {
            return Err(Setup(SetupError::Plant(
                capstan_plant::PlantError::BadInjection,
            )));
        }
        Ok(())
    }

    /// The run-to-run scatter of mu the campaign uses, %: as given, or half the cord-to-cord
    /// scatter (what provenance reports).
    pub fn run_scatter(&self) -> f64 {
        self.run_scatter_pct.unwrap_or(0.5 * self.scatter_pct)
    }

    /// Job `i` (0-based) of the campaign, in its order: diameters, then voltages, then wraps,
    /// then repeat runs (innermost). Made on demand, so a campaign of any length holds only
    /// the jobs in flight.
    pub(super) fn job(&self, i: usize) -> Job {
        let runs = self.runs as usize;
        let (nw, nv) = (self.wraps_deg.len(), self.drive_vs.len());
        let run = (i % runs) as u32 + 1;
        let w = self.wraps_deg[(i / runs) % nw];
        let v = self.drive_vs[(i / runs / nw) % nv];
        let d = self.diameters_mm[i / runs / nw / nv];
        let index = i as u32 + 1;
        let cord = CordKey {
            diameter_mm: d,
            wrap_deg: w,
            drive_v: v,
        };
        let mut model = self.model;
        for e in &self.effects {
            e.apply(&mut model);
        }
        let cord_seed = derive_seed(self.seed, &[d.to_bits(), v.to_bits(), w.to_bits()]);
        let cord_z = Rng::new(cord_seed).normal();
        let run_seed = derive_seed(cord_seed, &[run as u64]);
        let run_z = Rng::new(run_seed).normal();
        let (sc, sr) = (self.scatter_pct / 100.0, self.run_scatter() / 100.0);
        model.law.mu = (model.law.mu * (1.0 + sc * cord_z) * (1.0 + sr * run_z)).max(0.0);
        let plant = setup::cord_plant(&self.plant, d, self.sensor_noise);
        let protocol = setup::cord_protocol(&self.protocol, &self.calibration, self.order, d, w, v);
        let injections = self
            .faults
            .iter()
            .filter(|f| f.run.is_none_or(|r| r == index))
            .map(|f| Injection {
                kind: f.kind,
                cord: 0,
                after_trigger_us: (f.at_s * 1e6).round() as u64,
            })
            .collect();
        let mut cs = CordSetup::new(w, model);
        cs.run = run;
        cs.unmodelled = self.unmodelled;
        let spec = RunSpec {
            plant,
            cord: cs,
            protocol,
            calibration: self.calibration,
            limits: setup::cord_limits(&self.limits, &plant),
            seed: derive_seed(run_seed, &[0x0070_6c61_6e74]),
            injections,
            keep_raw: self.keep_raw,
            trace_every_ms: 0,
        };
        Job {
            index,
            cord,
            run,
            spec,
        }
    }
}
