//! `capstan diagnose`: which catalogue effects (none, one or several) make a data set depart
//! from Euler-Eytelwein, how large they are, and whether anything is left that no catalogue
//! effect explains.
//!
//! The statistics are the evidence engine's ([`crate::evidence`], shared with `capstan
//! analyze`): forward selection of within-run effects with every run's own mu and
//! cluster-robust quasi-likelihood evidence; the runs' mu against the between-cord and
//! between-run covariates; the residuals against the replicate runs' pure error and against
//! T1, time, step direction, wrap and diameter. This module renders the verdict layer's
//! verdicts ([`crate::verdict`], which `capstan analyze` renders too) as the diagnosis: the
//! effects found with their evidence given the others, the verdict in words, and the
//! population fit through [`crate::fit`].

mod diagnosis;

pub use crate::evidence::{Level, NotTestable, BETWEEN_THRESHOLD, WITHIN_THRESHOLD};
pub use diagnosis::{
    Baseline, DataInfo, DesignSummary, Diagnosis, Extended, Found, PathStep, Thresholds,
};

use crate::evidence::{self, Assessment};
use crate::fit::params::{ModelSpec, Param};
use crate::fit::solve::fit_fixed;
use crate::fit::stats;
use crate::verdict::{self, Verdicts};
use capstan_data::Dataset;
use capstan_physics::{Effect, EffectKind, Model};
use std::time::Instant;

/// Options of [`diagnose_with`].
pub type Options = evidence::Options;

/// The data's structure, its statement ending with how many units each question has.
fn with_units(d: &evidence::Design) -> capstan_data::structure::StructureSummary {
    let mut s = d.structure.clone();
    s.statement = format!("{}; {}", s.statement, evidence::cords::units_statement(d));
    s
}

/// Diagnose with the default options (the function behind `capstan diagnose`).
pub fn diagnose(d: &Dataset) -> Diagnosis {
    diagnose_with(d, &Options::default())
}

/// Diagnose `d`.
pub fn diagnose_with(d: &Dataset, opts: &Options) -> Diagnosis {
    let t0 = Instant::now();
    let a = evidence::assess(d, opts);
    from_assessment(&a, opts, t0)
}

/// The diagnosis of an assessment.
pub fn from_assessment(a: &Assessment, opts: &Options, t0: Instant) -> Diagnosis {
    render(a, &verdict::of(a), opts, t0)
}

/// The diagnosis of an assessment, rendering its verdicts `v`.
pub fn render(a: &Assessment, v: &Verdicts, opts: &Options, t0: Instant) -> Diagnosis {
    let des = &a.design;
    let n = des.n() as f64;
    let found: Vec<&evidence::Evidence> = a.selected_evidence();
    let effects: Vec<Found> = v.found.clone();
    let (kind, value) = found
        .first()
        .map_or((EffectKind::None, EffectKind::None.neutral_value()), |e| {
            (e.kind, e.value)
        });
    let (baseline, extended_rmse) = population(a, &found);
    Diagnosis {
        data: DataInfo {
            source: des.source.clone(),
            structure: with_units(des),
            warnings: None,
        },
        provenance: None,
        effect: kind.name(),
        parameters: found
            .first()
            .map(|e| e.parameters.clone())
            .unwrap_or_default(),
        effects,
        unexplained: a.adequacy.unexplained,
        residual_pattern: a.adequacy.pattern,
        rivals: a.rivals.clone(),
        verdict: v.sentence.clone(),
        adequacy: a.adequacy.clone(),
        candidates: a.evidence.clone(),
        selection_path: a
            .path
            .iter()
            .map(|(k, b)| PathStep {
                effect: k.name(),
                delta_bic: *b,
            })
            .collect(),
        baseline: Baseline {
            rmse_t2_run_mu_n: (a.null.rss / n).sqrt(),
            ..baseline
        },
        extended: Extended {
            rmse_t2_n: extended_rmse,
            rmse_t2_run_mu_n: (a.fit.rss / n).sqrt(),
        },
        elapsed_s: t0.elapsed().as_secs_f64(),
        not_testable: a.not_testable.clone(),
        design: DesignSummary {
            rows: des.n(),
            cords: des.cords.len(),
            runs: des.units.len(),
            wraps_deg: des.wraps(),
            diameters_mm: des.diameters(),
            drive_v: des.voltages(),
            columns: des.columns,
            both_directions: des.has_both_directions(),
            replicated_cells: des.replicated_cells(),
        },
        scatter: a.scatter.clone(),
        rows_used: a.rows_used.clone(),
        thresholds: Thresholds {
            within_run: -opts.within_threshold,
            between: -opts.between_threshold,
        },
        kind,
        value,
    }
}

/// The population fits through [`crate::fit`]: one mu, and one mu with the found effects at their
/// sizes.
fn population(a: &Assessment, found: &[&evidence::Evidence]) -> (Baseline, f64) {
    let obs = &a.design.obs;
    let runs = obs.all_runs();
    let mu0 = stats::mean(&a.null.mu);
    let ee = ModelSpec::new("ee", Model::euler_eytelwein(mu0)).free(Param::Mu);
    let base_fit = fit_fixed(&ee, obs, &runs, None);
    let mu_pop = base_fit.model(None).law.mu;
    let mut model = Model::euler_eytelwein(mu_pop);
    for e in found {
        let value = match e.kind.entry().population.floor {
            Some(floor) => e.value.max(floor),
            None => e.value,
        };
        Effect {
            kind: e.kind,
            value,
        }
        .apply(&mut model);
    }
    for e in found {
        (e.kind.entry().prepare)(&mut model);
    }
    // One mu with the effects at the sizes the engine found (refitting them all on the
    // population scale is the analysis's job, `capstan analyze`).
    let spec = ModelSpec::new("found", model).free(Param::Mu);
    let ext = if found.is_empty() {
        base_fit.rmse()
    } else {
        fit_fixed(&spec, obs, &runs, None).rmse()
    };
    (
        Baseline {
            mu: mu_pop,
            rmse_t2_n: base_fit.rmse(),
            rmse_t2_run_mu_n: f64::NAN,
        },
        ext,
    )
}

#[cfg(test)]
mod tests;
