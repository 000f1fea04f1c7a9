//! The evidence engine: which effects of the catalogue a data set holds, how sure that is on
//! data that are clustered (cords, runs) and serially correlated inside a run, and whether
//! anything is left that no catalogue effect explains. `capstan diagnose` reports it;
//! `capstan analyze` names its causes from it. One place turns fits into evidence.
//!
//! # The statistics
//! Rows are not independent: every cord has its own mu, every run a further scatter of mu and
//! its own tare, and inside a run the contact's state wanders from step to step. So:
//!
//! 1. **Within runs** ([`within`], [`select`]): every run gets its own mu (the within
//!    estimator: run effects far larger than the noise condition out everything between runs),
//!    and effects that change the shape of T2 against T1, time and wrap share their parameters
//!    across runs. Weighted least squares in T2, with the weights of a variance function
//!    σ_a² + σ_r²·T2² fitted to the residuals (an absolute part: zero errors and sensor noise;
//!    a proportional part: the wander and scatter of mu). Effects enter by forward selection;
//!    each one's evidence is a quasi-likelihood ratio: the likelihood ratio divided by its
//!    parameter's overdispersion ĉ (cluster-robust over model-based variance, runs as
//!    clusters, so any correlation inside a run is accounted for), referred to F(1, G − 1)
//!    (ĉ comes from G runs) and put on the χ²₁ scale: ΔBIC = −χ² + ln n.
//! 2. **Between runs and cords** ([`between`]): the runs' mu of the final within fit against
//!    the covariates that vary only between cords (gain: 1/β, diameter, voltage: the cords'
//!    means, t with G − p degrees of freedom, named at p < [`between::CORD_ALPHA`]) or between
//!    runs of a cord (wear: t with R − G − 1 degrees of freedom). A covariate that varies
//!    between cords has as many independent observations as cords, not runs or rows: every
//!    question between cords takes the cords as its units ([`cords`]: which parameters scatter
//!    from cord to cord, and whether any cord summary follows wrap or diameter).
//! 3. **Adequacy** ([`adequacy`]): the residuals of the final fit against the replicate runs'
//!    pure error, and against T1, time, step direction, wrap and diameter. Significant and
//!    large structure left is reported as unexplained, with the pattern, rather than forced
//!    onto the nearest name.
//!
//! A candidate is named when its ΔBIC is below its level's threshold and its size is outside
//! the region of practical equivalence with no effect ([`candidates::practically_relevant`]).
//! The thresholds are calibrated on generated data sets (`docs/README-diagnose.md`).

pub mod adequacy;
pub mod between;
pub mod candidates;
pub mod cords;
pub mod design;
pub mod rivals;
pub mod select;
pub mod within;

pub use adequacy::{Adequacy, AdequacyRule};
pub use candidates::Level;
pub use design::{Columns, Cord, Design};
pub use rivals::{Rival, RIVAL_GAP};

use crate::fit::stats;
use capstan_data::Dataset;
use capstan_physics::EffectKind;
use serde::Serialize;
use std::collections::BTreeMap;
use within::{Weights, WithinFit};

/// Within-run (shape) effects are named when ΔBIC < −this.
pub const WITHIN_THRESHOLD: f64 = 6.0;
/// Between-run and between-cord effects are named when ΔBIC < −this.
pub const BETWEEN_THRESHOLD: f64 = 6.0;

/// How to assess.
#[derive(Clone, Copy, Debug)]
pub struct Options {
    /// Without `time_s`, take the window times from `step` with the thesis protocol.
    pub protocol_times: bool,
    /// Within-run threshold (ΔBIC below −this).
    pub within_threshold: f64,
    /// Between-run and between-cord threshold.
    pub between_threshold: f64,
    /// The adequacy rule.
    pub adequacy: AdequacyRule,
    /// Threads for the candidate fits of one selection step.
    pub threads: usize,
    /// A found within-run effect's rival: a candidate whose set in its place is within this
    /// many BIC units ([`rivals`]).
    pub rival_gap: f64,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            protocol_times: false,
            within_threshold: WITHIN_THRESHOLD,
            between_threshold: BETWEEN_THRESHOLD,
            adequacy: AdequacyRule::default(),
            threads: std::thread::available_parallelism().map_or(1, |n| n.get().min(4)),
            rival_gap: RIVAL_GAP,
        }
    }
}

/// One candidate's evidence, given the final set of effects: a selected effect against the set
/// without it, any other against the set with it added.
#[derive(Clone, Debug, Serialize)]
pub struct Evidence {
    /// Catalogue name.
    pub effect: &'static str,
    /// Where its evidence comes from.
    pub level: Level,
    /// The fitted catalogue parameter.
    pub parameters: BTreeMap<&'static str, f64>,
    /// Its standard error (cluster-robust within runs; from the cord or run regression
    /// between them). NaN (null) where none is defined: from one run, or at an edge of the
    /// parameter's range.
    pub parameter_se: f64,
    /// At an edge of its range (within runs, two runs or more): its 95 % interval, from θ's
    /// cluster-robust interval (the value's own SE is not defined there).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub edge_interval: Option<(f64, f64)>,
    /// ΔBIC given the other selected effects (negative: the data want it).
    pub delta_bic: f64,
    /// The evidence on the χ²₁ scale.
    pub chi2: f64,
    /// Its p: the χ²₁ upper tail of `chi2` (between cords: the two-sided p of the cords'
    /// t test, cords as units).
    pub p: f64,
    /// Degrees of freedom of its small-sample reference (runs − 1, or the regression's).
    pub df: f64,
    /// Overdispersion ĉ of its parameter (within runs; 1 between).
    pub overdispersion: f64,
    /// Its size is outside the region of practical equivalence with no effect.
    pub relevant: bool,
    /// ΔBIC below its level's threshold and relevant.
    pub supported: bool,
    /// In the final set.
    pub selected: bool,
    /// The effect.
    #[serde(skip)]
    pub kind: EffectKind,
    /// Its catalogue value.
    #[serde(skip)]
    pub value: f64,
}

impl Evidence {
    /// Evidence with its numbers; the flags start false.
    pub fn new(kind: EffectKind, value: f64, se: f64, delta_bic: f64, chi2: f64, df: f64) -> Self {
        let mut parameters = BTreeMap::new();
        if let Some(name) = kind.parameter() {
            parameters.insert(name, value);
        }
        Evidence {
            effect: kind.name(),
            level: candidates::level(kind),
            parameters,
            parameter_se: se,
            edge_interval: None,
            delta_bic,
            chi2,
            p: stats::chi2_p_upper(chi2, 1.0),
            df,
            overdispersion: 1.0,
            relevant: false,
            supported: false,
            selected: false,
            kind,
            value,
        }
    }
}

/// An effect that could not be tested on this data set.
#[derive(Clone, Debug, Serialize)]
pub struct NotTestable {
    /// Catalogue name.
    pub effect: &'static str,
    /// Why.
    pub reason: String,
}

/// The data's scatter and noise, as the final model leaves them.
#[derive(Clone, Debug, Serialize)]
pub struct Scatter {
    /// Cord-to-cord standard deviation of mu, % of mu.
    pub cord_pct: f64,
    /// Run-to-run standard deviation of mu within cords, % of mu.
    pub run_pct: f64,
    /// RMS of the T2 residuals with every run's own mu and the selected effects, N.
    pub within_run_rms_n: f64,
    /// Absolute part of the noise's variance function, N.
    pub noise_abs_n: f64,
    /// Proportional part of the noise's variance function (fraction of T2).
    pub noise_rel: f64,
    /// Lag-1 autocorrelation of the standardised residuals inside runs (time order).
    pub lag1_autocorrelation: f64,
}

/// How many rows each part of the assessment used.
#[derive(Clone, Debug, Serialize)]
pub struct RowsUsed {
    /// Every row: the fits in T2, the offsets and gains, the adequacy tests.
    pub t2_fits: usize,
    /// Rows with T1 and T2 above zero: the start values of mu (ln(T2/T1)/β) and the
    /// per-cord logarithmic summaries.
    pub logarithms: usize,
}

/// What the engine found.
#[derive(Clone, Debug)]
pub struct Assessment {
    /// The data as laid out.
    pub design: Design,
    /// The weights of the final fit.
    pub weights: Weights,
    /// Every run's own mu, no effect.
    pub null: WithinFit,
    /// Every run's own mu with the selected within-run effects.
    pub fit: WithinFit,
    /// The selected effects: within-run ones in the order they came in, then between ones.
    pub selected: Vec<EffectKind>,
    /// Every testable candidate's evidence, the selected first, then by ΔBIC.
    pub evidence: Vec<Evidence>,
    /// Effects that could not be tested.
    pub not_testable: Vec<NotTestable>,
    /// The within-run selection path: (effect, ΔBIC when it came in).
    pub path: Vec<(EffectKind, f64)>,
    /// Every testable candidate's evidence alone (no other effect in).
    pub alone: Vec<Evidence>,
    /// Candidates that, in place of a found within-run effect, explain the data almost as well.
    pub rivals: Vec<Rival>,
    /// What is left.
    pub adequacy: Adequacy,
    /// Scatter and noise.
    pub scatter: Scatter,
    /// Rows used.
    pub rows_used: RowsUsed,
}

impl Assessment {
    /// The evidence of `kind`, if it was tested.
    pub fn evidence_of(&self, kind: EffectKind) -> Option<&Evidence> {
        self.evidence.iter().find(|e| e.kind == kind)
    }

    /// The selected effects' evidence, strongest (lowest ΔBIC) first.
    pub fn selected_evidence(&self) -> Vec<&Evidence> {
        let mut v: Vec<&Evidence> = self.evidence.iter().filter(|e| e.selected).collect();
        v.sort_by(|a, b| a.delta_bic.total_cmp(&b.delta_bic));
        v
    }
}

/// Assess `data`.
pub fn assess(data: &Dataset, opts: &Options) -> Assessment {
    let d = Design::new(data, opts.protocol_times);
    let (testable, mut not_testable) = testable(&d);
    let within_cands: Vec<EffectKind> = candidates::at_level(Level::WithinRun)
        .into_iter()
        .filter(|k| testable.contains(k))
        .collect();
    // The noise's variance function from the pure error of the replicate runs: what effects
    // the data hold move a cell's runs alike, so what is left is noise.
    let clock = std::time::Instant::now();
    let cold = within::fit(&d, &[], &[], &within::start_mu(&d), &Weights::equal(d.n()));
    let w0 = Weights::from_pure_error(&d, &cold);
    let null = within::fit(&d, &[], &[], &cold.mu, &w0);
    let sel = select::forward(
        &d,
        null.clone(),
        &within_cands,
        &w0,
        opts.within_threshold,
        opts.threads,
    );
    lap(clock, "selection");
    let fit = sel.fit;
    let rivals = rivals::rivals(&d, &fit, &sel.swaps, &sel.alone, opts.rival_gap);
    let w = w0;
    lap(clock, "final fit");
    let bt = between::between_tests(&d, &fit.mu, &testable, opts.between_threshold);
    let mut selected: Vec<EffectKind> = fit.maps.iter().map(|m| m.kind).collect();
    selected.extend(bt.selected.iter().copied());
    let (mut evidence, mut alone) = (sel.evidence, sel.alone);
    add_between(&mut evidence, &mut alone, bt, &d, opts);
    drop_unidentified(&mut evidence, &mut alone, &mut not_testable);
    evidence.sort_by(|a, b| {
        b.selected
            .cmp(&a.selected)
            .then(a.delta_bic.total_cmp(&b.delta_bic))
    });
    lap(clock, "between");
    let adequacy = adequacy::assess(&d, &fit, &w, opts.adequacy);
    lap(clock, "adequacy");
    let scatter = scatter(&d, &fit, &w);
    let rows_used = RowsUsed {
        t2_fits: d.n(),
        logarithms: d.positive_rows(),
    };
    Assessment {
        design: d,
        weights: w,
        null,
        fit,
        selected,
        evidence,
        not_testable,
        path: sel.path,
        alone,
        rivals,
        adequacy,
        scatter,
        rows_used,
    }
}

/// The catalogue's effects (the base model aside) the design can test, and why each other
/// cannot be.
fn testable(d: &Design) -> (Vec<EffectKind>, Vec<NotTestable>) {
    let mut not_testable = Vec::new();
    let mut testable = Vec::new();
    for kind in EffectKind::ALL.into_iter().skip(1) {
        match candidates::untestable(kind, d) {
            Some(reason) => not_testable.push(NotTestable {
                effect: kind.name(),
                reason,
            }),
            None => testable.push(kind),
        }
    }
    (testable, not_testable)
}

/// With `CAPSTAN_LAPS` set, the time since `clock` at `what` on the trace.
fn lap(clock: std::time::Instant, what: &str) {
    if std::env::var("CAPSTAN_LAPS").is_ok() {
        crate::trace::line(format_args!(
            "{what}: {:.1} ms",
            clock.elapsed().as_secs_f64() * 1e3
        ));
    }
}

/// The between-run tests' evidence after the within-run ones, each judged for practical
/// relevance and support, and their evidence alone after the within-run ones'.
fn add_between(
    evidence: &mut Vec<Evidence>,
    alone: &mut Vec<Evidence>,
    bt: between::BetweenTests,
    d: &Design,
    opts: &Options,
) {
    for mut e in bt.evidence {
        e.relevant = candidates::practically_relevant(e.kind, e.value, d);
        e.supported = between::supported(&e, d, opts.between_threshold);
        e.selected = bt.selected.contains(&e.kind);
        evidence.push(e);
    }
    alone.extend(bt.alone);
}

/// A candidate whose size or evidence could not be computed (a fit that ran off to infinity,
/// a regression on no spread) is not identified: said so among the untestable (unless
/// selected), never shown as inf.
fn drop_unidentified(
    evidence: &mut Vec<Evidence>,
    alone: &mut Vec<Evidence>,
    not_testable: &mut Vec<NotTestable>,
) {
    let unidentified = |e: &Evidence| !(e.value.is_finite() && e.delta_bic.is_finite());
    for e in evidence.iter().filter(|e| unidentified(e) && !e.selected) {
        not_testable.push(NotTestable {
            effect: e.effect,
            reason: not_identified_reason(e),
        });
    }
    evidence.retain(|e| e.selected || !unidentified(e));
    alone.retain(|e| !unidentified(e));
}

/// Why a candidate's numbers could not be computed.
fn not_identified_reason(e: &Evidence) -> String {
    let what = if e.value.is_finite() {
        "its evidence (the fit with it) could not be computed"
    } else {
        "its size runs off to the edge of what can be computed"
    };
    format!("not identified on these data: {what} (too few rows, runs or spread in T1 for it)")
}

/// Scatter of mu (random-intercept model of the runs' mu) and the residuals' noise.
fn scatter(d: &Design, fit: &WithinFit, w: &Weights) -> Scatter {
    let y = &fit.mu;
    let ones: Vec<Vec<f64>> = y.iter().map(|_| vec![1.0]).collect();
    let lmm = between::fit_lmm(y, &ones, &d.unit_cord, d.cords.len());
    let mu_bar = stats::mean(y);
    let z: Vec<f64> = (0..d.n())
        .map(|i| (d.t2[i] - fit.fitted[i]) * w.w[i].sqrt())
        .collect();
    let (mut lag, mut sq) = (0.0, 0.0);
    for rows in &d.units {
        let m = rows.iter().map(|&i| z[i]).sum::<f64>() / rows.len() as f64;
        for (k, &i) in rows.iter().enumerate() {
            sq += (z[i] - m).powi(2);
            if k > 0 {
                lag += (z[i] - m) * (z[rows[k - 1]] - m);
            }
        }
    }
    // A spread needs two of what spreads: with one cord there is no cord-to-cord scatter to
    // estimate, and with no cord of two runs none from run to run (the model's variance
    // component then sits at its bound, e.g. 7.5e-148 %): not estimable (NaN → null, and
    // "not estimable" in the text), never a measured 0.
    let mut runs_of = vec![0usize; d.cords.len()];
    for &c in &d.unit_cord {
        runs_of[c] += 1;
    }
    let estimable = |ok: bool, v: f64| if ok { v } else { f64::NAN };
    Scatter {
        cord_pct: estimable(
            d.cords.len() >= 2,
            lmm.as_ref()
                .map_or(f64::NAN, |m| 100.0 * m.sigma2_c.sqrt() / mu_bar),
        ),
        run_pct: estimable(
            runs_of.iter().any(|&n| n >= 2),
            lmm.as_ref()
                .map_or(f64::NAN, |m| 100.0 * m.sigma2_e.sqrt() / mu_bar),
        ),
        within_run_rms_n: (fit.rss / d.n() as f64).sqrt(),
        noise_abs_n: w.sd_abs_n,
        noise_rel: w.sd_rel,
        lag1_autocorrelation: if d.timed && sq > 0.0 {
            lag / sq
        } else {
            f64::NAN
        },
    }
}
