//! `capstan analyze`: the measured pairs against Euler-Eytelwein, the thesis's Table 3 and the
//! extended model; what the simulator gets wrong, why, and by how much the extension helps.
//!
//! Every number here is computed from the data by [`run`]; the only typed-in numbers are the
//! thesis's published Table 3 constants ([`thesis::TABLE3`]).

pub mod closed_loop;
pub mod mechanisms;
pub mod models;
pub mod residuals;
pub mod thesis;

use crate::data::Dataset;
use crate::fit::solve::{fit_fixed, fit_mixed, fit_mixed_from, loco, Fit, Loco, MixedOptions};
use crate::fit::Observations;
use serde::Serialize;
use std::time::Instant;

/// How to run the analysis.
#[derive(Clone, Copy, Debug)]
pub struct Options {
    /// Threads for the independent fits (LOCO folds, mechanism variants).
    pub threads: usize,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            threads: std::thread::available_parallelism().map_or(2, |n| n.get().min(4)),
        }
    }
}

/// Per-row predictions of every model (N), NaN where a model has no prediction.
#[derive(Clone, Debug, Default)]
pub struct Predictions {
    /// Euler-Eytelwein, one global mu.
    pub baseline: Vec<f64>,
    /// Euler-Eytelwein, one mu per cord.
    pub baseline_per_cord: Vec<f64>,
    /// Thesis Table 3, amp(T1)·T1 per angle.
    pub thesis: Vec<f64>,
    /// Extended model with the cord effects (in-sample).
    pub extended: Vec<f64>,
    /// Extended model, population values (cord effect 0).
    pub extended_population: Vec<f64>,
    /// Baseline, leave-one-cord-out.
    pub baseline_loco: Vec<f64>,
    /// Baseline per cord, leave-one-cord-out (mean log-mu of the other cords).
    pub baseline_per_cord_loco: Vec<f64>,
    /// Extended, leave-one-cord-out (population values of a fit on the other cords).
    pub extended_loco: Vec<f64>,
    /// Load memory H of the extended model at each window centre, N s.
    pub extended_load_memory_ns: Vec<f64>,
}

/// Parameter counts, spelled out.
#[derive(Clone, Debug, Serialize)]
pub struct ParamCount {
    /// Fixed (population) values.
    pub fixed: usize,
    /// Variance components (1 with per-cord random effects).
    pub variance_components: usize,
    /// Effective degrees of freedom of the per-cord effects (0 without them).
    pub edf_random: f64,
    /// Values set per group without shrinkage (per-cord mu, Table 3's per-angle numbers).
    pub per_group_values: usize,
    /// Which count `n_params` uses.
    pub rule: &'static str,
}

/// R² of amplification of one cord.
#[derive(Clone, Debug, Serialize)]
pub struct CordR2 {
    /// Cord label.
    pub cord: String,
    /// 1 − SS_res/SS_tot on T2/T1 over the cord's rows.
    pub r2: f64,
}

/// One row of the gain table.
#[derive(Clone, Debug, Serialize)]
pub struct ModelMetrics {
    /// `baseline`, `baseline_per_cord`, `thesis`, `extended`, ...
    pub name: String,
    /// What it is.
    pub description: String,
    /// Number of fitted values under `n_params_detail.rule`.
    pub n_params: f64,
    /// The count spelled out.
    pub n_params_detail: ParamCount,
    /// Strict count: fixed + effective dof of the random effects (+ per-group values).
    pub n_params_strict: f64,
    /// In-sample RMSE of T2, N.
    pub rmse_t2_n: f64,
    /// In-sample RMSE of ln(T2/T1) (predicted T2 floored at 1 mN).
    pub rmse_ln_amp: f64,
    /// Leave-one-cord-out RMSE of T2, N (None if the model cannot be refitted).
    pub loco_rmse_t2_n: Option<f64>,
    /// AIC with `n_params`.
    pub aic: f64,
    /// BIC with `n_params`.
    pub bic: f64,
    /// AIC with the strict count.
    pub aic_strict: f64,
    /// BIC with the strict count.
    pub bic_strict: f64,
    /// Per-cord R² of amplification.
    pub per_cord_r2_amp: Vec<CordR2>,
    /// Median of `per_cord_r2_amp`.
    pub per_cord_r2_amp_median: f64,
    /// Fitted values (population), by name.
    pub values: Vec<(String, f64)>,
}

/// The thesis's per-angle R² of amplification, recomputed.
#[derive(Clone, Debug, Serialize)]
pub struct AngleR2 {
    /// Wrap angle, deg.
    pub wrap_deg: f64,
    /// R² (pooled over diameters).
    pub r2: f64,
    /// Rows.
    pub rows: usize,
}

/// The extended fit in detail.
#[derive(Clone, Debug, Serialize)]
pub struct ExtendedDetail {
    /// Fitted population values.
    pub values: Vec<(String, f64)>,
    /// Gauss-Newton standard errors of the values.
    pub standard_errors: Vec<(String, f64)>,
    /// Jackknife standard errors over the leave-one-cord-out refits.
    pub jackknife_se: Vec<(String, f64)>,
    /// Per-cord log-mu offsets (BLUPs).
    pub cord_log_mu: Vec<(String, f64)>,
    /// SD of the cord log-mu offsets.
    pub sigma_u: f64,
    /// λ = σ²/σ_u².
    pub lambda: f64,
    /// Effective dof of the cord offsets.
    pub edf_random: f64,
    /// RMSE of T2 with population values only (cord offsets 0), N.
    pub rmse_population_t2_n: f64,
    /// Steady-state mu factor at a friction load T2 − T1 = 40 N: exp(−h·τ·40).
    pub mu_factor_at_40n_load: f64,
    /// h·τ, 1/N: steady-state ln-mu loss per newton of friction load.
    pub heat_per_n_steady: f64,
    /// How the extended fit stopped.
    pub termination: String,
    /// The strict-count variant: cord effects shrunk so that fixed + edf ≤ 12.
    pub strict12: StrictVariant,
}

/// The extended model with its cord effects shrunk to a strict budget.
#[derive(Clone, Debug, Serialize)]
pub struct StrictVariant {
    /// Fixed + edf of the cord effects.
    pub n_params_strict: f64,
    /// In-sample RMSE of T2, N.
    pub rmse_t2_n: f64,
    /// λ used.
    pub lambda: f64,
}

/// Wall-clock times, s.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Elapsed {
    /// Baseline, per-cord and extended fits.
    pub fits_s: f64,
    /// Leave-one-cord-out refits.
    pub loco_s: f64,
    /// Mechanism variants and tests.
    pub mechanisms_s: f64,
    /// Closed-loop simulation.
    pub closed_loop_s: f64,
    /// Writing the report (filled by the CLI).
    pub report_s: f64,
    /// Everything (filled by the CLI).
    pub total_s: f64,
}

/// Everything `capstan analyze` computed.
#[derive(Clone, Debug)]
pub struct Analysis {
    /// The data as fitted.
    pub obs: Observations,
    /// Where the data came from.
    pub source: String,
    /// Predictions per row.
    pub pred: Predictions,
    /// The gain table.
    pub models: Vec<ModelMetrics>,
    /// The thesis's per-angle R².
    pub thesis_per_angle_r2: Vec<AngleR2>,
    /// The extended fit in detail.
    pub extended: ExtendedDetail,
    /// Residual patterns of the baseline and the extended model.
    pub residual_patterns: Vec<residuals::Pattern>,
    /// Mechanism tests.
    pub mechanisms: mechanisms::Mechanisms,
    /// The fitted extended model (for the closed loop).
    pub extended_fit: Fit,
    /// The fitted baseline.
    pub baseline_fit: Fit,
    /// Timing.
    pub elapsed: Elapsed,
}

/// Run `f` over `items` on up to `threads` threads, keeping the order.
pub fn par_map<T: Sync, R: Send>(
    items: &[T],
    threads: usize,
    f: impl Fn(&T) -> R + Sync,
) -> Vec<R> {
    let threads = threads.clamp(1, items.len().max(1));
    let mut out: Vec<Option<R>> = (0..items.len()).map(|_| None).collect();
    std::thread::scope(|s| {
        let f = &f;
        let handles: Vec<_> = (0..threads)
            .map(|t| {
                s.spawn(move || {
                    (t..items.len())
                        .step_by(threads)
                        .map(|i| (i, f(&items[i])))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        for h in handles {
            for (i, r) in h.join().expect("worker panicked") {
                out[i] = Some(r);
            }
        }
    });
    out.into_iter()
        .map(|r| r.expect("every item mapped"))
        .collect()
}

/// RMSE of `pred` against measured T2 over the rows where `pred` is finite.
pub fn rmse_t2(obs: &Observations, pred: &[f64]) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for (r, p) in obs.rows.iter().zip(pred) {
        if p.is_finite() {
            s += (p - r.t2_n).powi(2);
            n += 1;
        }
    }
    (s / n as f64).sqrt()
}

/// ln(max(T2, 1 mN)/T1): the log amplification used for log metrics.
pub fn ln_amp(t2_n: f64, t1_n: f64) -> f64 {
    (t2_n.max(1e-3) / t1_n).ln()
}

/// RMSE of ln(T2/T1), predicted against measured (both floored at 1 mN).
pub fn rmse_ln_amp(obs: &Observations, pred: &[f64]) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for (r, p) in obs.rows.iter().zip(pred) {
        if p.is_finite() {
            s += (ln_amp(*p, r.t1_n) - ln_amp(r.t2_n, r.t1_n)).powi(2);
            n += 1;
        }
    }
    (s / n as f64).sqrt()
}

/// Per-cord R² of amplification.
pub fn per_cord_r2(obs: &Observations, pred: &[f64]) -> Vec<CordR2> {
    obs.groups
        .iter()
        .enumerate()
        .map(|(g, grp)| {
            let idx: Vec<usize> = (0..obs.len()).filter(|&i| obs.rows[i].group == g).collect();
            let m: Vec<f64> = idx
                .iter()
                .map(|&i| obs.rows[i].t2_n / obs.rows[i].t1_n)
                .collect();
            let p: Vec<f64> = idx.iter().map(|&i| pred[i] / obs.rows[i].t1_n).collect();
            CordR2 {
                cord: grp.label.clone(),
                r2: thesis::r_squared(&m, &p),
            }
        })
        .collect()
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        return f64::NAN;
    }
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

#[allow(clippy::too_many_arguments)]
fn metrics(
    obs: &Observations,
    name: &str,
    description: &str,
    pred: &[f64],
    loco: Option<f64>,
    count: ParamCount,
    n_params: f64,
    n_strict: f64,
    values: Vec<(String, f64)>,
) -> ModelMetrics {
    let rss: f64 = obs
        .rows
        .iter()
        .zip(pred)
        .map(|(r, p)| (p - r.t2_n).powi(2))
        .sum();
    let (aic, bic) = crate::fit::solve::information_criteria(rss, obs.len(), n_params);
    let (aic_s, bic_s) = crate::fit::solve::information_criteria(rss, obs.len(), n_strict);
    let per_cord = per_cord_r2(obs, pred);
    let mut r2s: Vec<f64> = per_cord.iter().map(|c| c.r2).collect();
    ModelMetrics {
        name: name.into(),
        description: description.into(),
        n_params,
        n_params_detail: count,
        n_params_strict: n_strict,
        rmse_t2_n: rmse_t2(obs, pred),
        rmse_ln_amp: rmse_ln_amp(obs, pred),
        loco_rmse_t2_n: loco,
        aic,
        bic,
        aic_strict: aic_s,
        bic_strict: bic_s,
        per_cord_r2_amp: per_cord,
        per_cord_r2_amp_median: median(&mut r2s),
        values,
    }
}

fn named(values: Vec<(&'static str, f64)>) -> Vec<(String, f64)> {
    values
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect()
}

/// Fit every model to `ds` and run every test.
pub fn run(ds: &Dataset, opts: Options) -> anyhow::Result<Analysis> {
    let obs = Observations::from_dataset(ds);
    if obs.len() < 10 {
        anyhow::bail!(
            "{}: {} rows is too few to analyse (need at least 10)",
            ds.source,
            obs.len()
        );
    }
    let threads = opts.threads;
    let all = obs.all_runs();
    let t0 = Instant::now();

    // 1. Baseline: one global mu, and one mu per cord.
    let base_spec = models::baseline();
    let baseline_fit = fit_fixed(&base_spec, &obs, &all, None);
    let per_cord_fits: Vec<Fit> =
        par_map(&(0..obs.groups.len()).collect::<Vec<_>>(), threads, |&g| {
            let runs: Vec<usize> = all
                .iter()
                .copied()
                .filter(|&r| obs.rows[obs.runs[r][0]].group == g)
                .collect();
            fit_fixed(&base_spec, &obs, &runs, None)
        });
    let mut per_cord_pred = vec![f64::NAN; obs.len()];
    for f in &per_cord_fits {
        for i in obs.rows_of(&f.runs) {
            per_cord_pred[i] = f.t2_n[i];
        }
    }
    let cord_mu: Vec<f64> = per_cord_fits.iter().map(|f| f.model(None).law.mu).collect();

    // The thesis's Table 3.
    let thesis_pred: Vec<f64> = obs
        .rows
        .iter()
        .map(|r| {
            thesis::thesis_amp(r.op.wrap_rad.to_degrees().round(), r.t1_n)
                .map_or(f64::NAN, |a| a * r.t1_n)
        })
        .collect();
    let thesis_ok = thesis_pred.iter().all(|p| p.is_finite());

    // The extended model (mixed: per-cord random log-mu).
    let ext_spec = models::extended();
    let ext_fit = fit_mixed(&ext_spec, &obs, &all, None, MixedOptions::default());
    let ext_pop = ext_fit.predict(&obs, &all, false);
    let ext_eval =
        crate::fit::predict::evaluate(&ext_fit.spec, &ext_fit.theta, &ext_fit.u, &obs, &all, false);
    let strict_budget = 12.0;
    let strict_fit = fit_mixed(
        &ext_spec,
        &obs,
        &all,
        Some(&ext_fit.theta),
        MixedOptions {
            edf_cap: Some(strict_budget),
            ..MixedOptions::default()
        },
    );
    let fits_s = t0.elapsed().as_secs_f64();

    // Leave one cord out.
    let t1 = Instant::now();
    let (base_loco, ext_loco): (Loco, Loco) = {
        let th = ext_fit.theta.clone();
        let b = loco(&obs, 1, |train| fit_fixed(&base_spec, &obs, train, None));
        let (u0, l0) = (ext_fit.u.clone(), ext_fit.lambda.unwrap_or(200.0));
        let e = loco(&obs, threads, |train| {
            let opts = MixedOptions {
                lambda0: l0,
                ..MixedOptions::default()
            };
            fit_mixed_from(&ext_spec, &obs, train, th.clone(), u0.clone(), opts)
        });
        (b, e)
    };
    // Per-cord baseline on a new cord: the mean log-mu of the other cords.
    let mut per_cord_loco = vec![f64::NAN; obs.len()];
    for g in 0..obs.groups.len() {
        let others: Vec<f64> = (0..obs.groups.len())
            .filter(|&k| k != g)
            .map(|k| cord_mu[k].ln())
            .collect();
        let mu = (others.iter().sum::<f64>() / others.len() as f64).exp();
        let m = capstan_friction::Model::euler_eytelwein(mu);
        for (i, r) in obs.rows.iter().enumerate() {
            if r.group == g {
                per_cord_loco[i] = m.predict_t2_n(r.t1_n, &r.op);
            }
        }
    }
    let per_cord_loco_rmse = rmse_t2(&obs, &per_cord_loco);
    let loco_s = t1.elapsed().as_secs_f64();

    let pred = Predictions {
        baseline: baseline_fit.t2_n.clone(),
        baseline_per_cord: per_cord_pred,
        thesis: thesis_pred,
        extended: ext_fit.t2_n.clone(),
        extended_population: ext_pop,
        baseline_loco: base_loco.t2_n.clone(),
        baseline_per_cord_loco: per_cord_loco,
        extended_loco: ext_loco.t2_n.clone(),
        extended_load_memory_ns: ext_eval.load_memory_ns.clone(),
    };

    // The gain table.
    let n_groups = obs.groups.len();
    let mut table = vec![
        metrics(
            &obs,
            "baseline",
            "Euler-Eytelwein T2 = T1·exp(mu·β), one global mu (least squares on T2)",
            &pred.baseline,
            Some(base_loco.rmse),
            ParamCount {
                fixed: 1,
                variance_components: 0,
                edf_random: 0.0,
                per_group_values: 0,
                rule: "fixed values",
            },
            1.0,
            1.0,
            named(baseline_fit.values()),
        ),
        metrics(
            &obs,
            "baseline_per_cord",
            "Euler-Eytelwein with one mu per cord (a new cord is predicted with the mean log-mu of the others)",
            &pred.baseline_per_cord,
            Some(per_cord_loco_rmse),
            ParamCount {
                fixed: 0,
                variance_components: 0,
                edf_random: 0.0,
                per_group_values: n_groups,
                rule: "one value per cord",
            },
            n_groups as f64,
            n_groups as f64,
            obs.groups
                .iter()
                .zip(&cord_mu)
                .map(|(g, m)| (format!("mu {}", g.label), *m))
                .collect(),
        ),
    ];
    if thesis_ok {
        table.push(metrics(
            &obs,
            "thesis",
            "Thesis Table 3: amp(T1) = −Nd·exp(−ld·T1) + N0·exp(−l·T1) + SS per angle (published constants, set by eye; not refittable per cord)",
            &pred.thesis,
            None,
            ParamCount {
                fixed: 0,
                variance_components: 0,
                edf_random: 0.0,
                per_group_values: thesis::TABLE3_N_VALUES,
                rule: "5 published numbers per angle",
            },
            thesis::TABLE3_N_VALUES as f64,
            thesis::TABLE3_N_VALUES as f64,
            Vec::new(),
        ));
    }
    let nf = ext_fit.n_fixed();
    table.push(metrics(
        &obs,
        "extended",
        "Euler-Eytelwein + T1-path loss e1 + wrap slope of ln mu + contact heating (mu·exp(−h·H), H the friction-load memory) + per-cord random log-mu (mixed model)",
        &pred.extended,
        Some(ext_loco.rmse),
        ParamCount {
            fixed: nf,
            variance_components: 1,
            edf_random: ext_fit.edf_random,
            per_group_values: 0,
            rule: "mixed-model convention: fixed effects + variance components (the cord effects are predicted, not free)",
        },
        ext_fit.n_params_mixed() as f64,
        ext_fit.n_params_edf(),
        named(ext_fit.values()),
    ));
    let se = ext_fit.standard_errors(&obs);
    let m_pop = ext_fit.model(None);
    let h_tau = m_pop.law.heat_per_ns * m_pop.law.heat_tau_s;
    let extended = ExtendedDetail {
        values: named(ext_fit.values()),
        standard_errors: ext_fit
            .spec
            .free
            .iter()
            .zip(se)
            .map(|(f, s)| (f.param.name().to_string(), s))
            .collect(),
        jackknife_se: {
            let mut v = named(ext_loco.jackknife_se());
            let prods: Vec<f64> = ext_loco
                .fold_values
                .iter()
                .map(|f| {
                    let get = |k: &str| f.iter().find(|x| x.0 == k).map_or(f64::NAN, |x| x.1);
                    get("heat_per_ns") * get("heat_tau_s")
                })
                .collect();
            let g = prods.len() as f64;
            let m = prods.iter().sum::<f64>() / g;
            let ss: f64 = prods.iter().map(|p| (p - m).powi(2)).sum();
            v.push(("heat_per_ns*heat_tau_s".into(), ((g - 1.0) / g * ss).sqrt()));
            v
        },
        cord_log_mu: obs
            .groups
            .iter()
            .zip(&ext_fit.u)
            .map(|(g, u)| (g.label.clone(), *u))
            .collect(),
        sigma_u: ext_fit.sigma_u.unwrap_or(f64::NAN),
        lambda: ext_fit.lambda.unwrap_or(f64::NAN),
        edf_random: ext_fit.edf_random,
        rmse_population_t2_n: rmse_t2(&obs, &pred.extended_population),
        mu_factor_at_40n_load: (-h_tau * 40.0).exp(),
        heat_per_n_steady: h_tau,
        termination: ext_fit.termination.clone(),
        strict12: StrictVariant {
            n_params_strict: strict_fit.n_params_edf(),
            rmse_t2_n: strict_fit.rmse(),
            lambda: strict_fit.lambda.unwrap_or(f64::NAN),
        },
    };

    let wraps: Vec<f64> = obs
        .rows
        .iter()
        .map(|r| r.op.wrap_rad.to_degrees())
        .collect();
    let t1s: Vec<f64> = obs.rows.iter().map(|r| r.t1_n).collect();
    let t2s: Vec<f64> = obs.rows.iter().map(|r| r.t2_n).collect();
    let thesis_per_angle_r2 = thesis::per_angle_r2(&wraps, &t1s, &t2s)
        .into_iter()
        .map(|(w, r2, rows)| AngleR2 {
            wrap_deg: w,
            r2,
            rows,
        })
        .collect();

    let t2 = Instant::now();
    let residual_patterns = residuals::patterns(ds, &obs, &pred);
    let mechanisms = mechanisms::run(&obs, &baseline_fit, &ext_fit, &ext_loco, &cord_mu, threads);
    let mechanisms_s = t2.elapsed().as_secs_f64();

    Ok(Analysis {
        source: ds.source.clone(),
        obs,
        pred,
        models: table,
        thesis_per_angle_r2,
        extended,
        residual_patterns,
        mechanisms,
        extended_fit: ext_fit,
        baseline_fit,
        elapsed: Elapsed {
            fits_s,
            loco_s,
            mechanisms_s,
            ..Elapsed::default()
        },
    })
}
