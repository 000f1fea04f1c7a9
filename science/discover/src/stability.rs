//! Stability: how often the same term is the search's pick, and passes the bar, when whole
//! cords are resampled (with their runs). Linearised: the per-cord cross-products of the
//! model's and the terms' columns (each projected off its runs' mu, which resampling cords
//! leaves as it is) are summed with the resample's multiplicities and the screen redone;
//! each term keeps its full-data overdispersion ĉ. Between-level terms are retested on the
//! resampled runs. (The spike found this within binomial noise of full refits: mean
//! |difference| 0.04 over 15 sets.)

use crate::library::LIBRARY;
use crate::screen::{between_evidence, off_run_mu, Runs};
use capstan_engine::fit::stats::chi2_of_f;
use capstan_rng::Rng;
use nalgebra::{DMatrix, DVector};

/// A term as the resampled screen sees it.
pub struct Candidate {
    /// Library index.
    pub term: usize,
    /// Within-run column (raw), or None for a between-level term.
    pub column: Option<Vec<f64>>,
    /// Between-level g per run (for between terms).
    pub g_run: Option<Vec<f64>>,
    /// Full-data overdispersion.
    pub c_hat: f64,
    /// Its sign check.
    pub sign_ok: fn(f64) -> bool,
}

/// What the resampled screen needs.
pub struct Problem<'a> {
    /// The linearised fit.
    pub base: &'a crate::columns::Base<'a>,
    /// The model's shared columns (catalogue, and any term already proposed), raw.
    pub shared: &'a [Vec<f64>],
    /// Residuals of the model with them, N (raw).
    pub e: &'a [f64],
    /// The candidates.
    pub candidates: &'a [Candidate],
    /// The runs for the between tests.
    pub runs: &'a Runs,
    /// The selected catalogue between covariates per run.
    pub covs: &'a [Vec<f64>],
    /// ΔBIC bar (negative) including the search penalty.
    pub bar: f64,
}

/// What a resample's pick must be to count for the target.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Hit {
    /// The target itself.
    Term,
    /// A term that depends on the same variables (the claim the answer makes: the dependence,
    /// with the terms of that dependence the data cannot tell apart named as its rivals).
    Dependence,
}

/// Do the library terms `a` and `b` depend on the same variables?
pub fn same_dependence(a: usize, b: usize) -> bool {
    let (x, y) = (LIBRARY[a].depends_on, LIBRARY[b].depends_on);
    x.len() == y.len() && x.iter().all(|v| y.contains(v))
}

/// Share of `b` cord resamples in which `target` (a library index) is the pick and passes
/// (or, with [`Hit::Dependence`], a term of its dependence).
pub fn stability(p: &Problem, target: usize, b: usize, seed: u64, hit: Hit) -> f64 {
    let within: Vec<&Candidate> = p.candidates.iter().filter(|c| c.column.is_some()).collect();
    let cords = PerCord::new(p, &within);
    let mut rng = Rng::new(seed);
    let mut hits = 0usize;
    for _ in 0..b {
        let mult = cords.draw(&mut rng);
        let mut best = Best(None);
        cords.screen_within(&mult, &within, &mut best);
        screen_between(p, &cords.runs_of, &mult, &mut best);
        if let Some((term, dbic)) = best.0 {
            let same = term == target || (hit == Hit::Dependence && same_dependence(term, target));
            if same && dbic < p.bar {
                hits += 1;
            }
        }
    }
    hits as f64 / b.max(1) as f64
}

/// The resample's pick so far: the term with the lowest finite ΔBIC (the first of ties).
struct Best(Option<(usize, f64)>);

impl Best {
    fn consider(&mut self, term: usize, dbic: f64) {
        if dbic.is_finite() && self.0.is_none_or(|(_, v)| dbic < v) {
            self.0 = Some((term, dbic));
        }
    }
}

/// Per cord: the cross-products of the model's columns (first `k0`) and the within-run
/// candidates' columns, each projected off its runs' mu, with the residuals; and the cord's runs.
struct PerCord {
    /// Shared columns in the cross-products.
    k0: usize,
    /// Σ w·x_a·x_b per cord.
    gc: Vec<DMatrix<f64>>,
    /// Σ w·x_a·e per cord.
    hc: Vec<DVector<f64>>,
    /// Σ w·e² per cord.
    ec: Vec<f64>,
    /// Rows per cord.
    nrow: Vec<f64>,
    /// Runs of each cord.
    runs_of: Vec<Vec<usize>>,
}

impl PerCord {
    fn new(p: &Problem, within: &[&Candidate]) -> PerCord {
        let base = p.base;
        let d = base.d;
        let nc = d.cords.len();
        let mut cols: Vec<Vec<f64>> = p.shared.iter().map(|c| off_run_mu(base, c)).collect();
        let k0 = cols.len();
        for c in within {
            cols.push(off_run_mu(base, c.column.as_ref().unwrap()));
        }
        let e = off_run_mu(base, p.e);
        let m = cols.len();
        let mut gc = vec![DMatrix::<f64>::zeros(m, m); nc];
        let mut hc = vec![DVector::<f64>::zeros(m); nc];
        let mut ec = vec![0.0; nc];
        let mut nrow = vec![0.0; nc];
        for i in 0..d.n() {
            let c = base.cord_of_row[i];
            let w = base.w[i];
            nrow[c] += 1.0;
            ec[c] += w * e[i] * e[i];
            for a in 0..m {
                let za = w * cols[a][i];
                hc[c][a] += za * e[i];
                for bb in a..m {
                    gc[c][(a, bb)] += za * cols[bb][i];
                }
            }
        }
        for g in gc.iter_mut() {
            for a in 0..m {
                for bb in 0..a {
                    g[(a, bb)] = g[(bb, a)];
                }
            }
        }
        let mut runs_of = vec![Vec::new(); nc];
        for (u, &c) in p.runs.cord.iter().enumerate() {
            runs_of[c].push(u);
        }
        PerCord {
            k0,
            gc,
            hc,
            ec,
            nrow,
            runs_of,
        }
    }

    /// A resample: how many times each cord is drawn.
    fn draw(&self, rng: &mut Rng) -> Vec<f64> {
        let nc = self.gc.len();
        let mut mult = vec![0.0; nc];
        for _ in 0..nc {
            mult[(rng.uniform() * nc as f64) as usize % nc] += 1.0;
        }
        mult
    }

    /// The within-run candidates' screen on the resample `mult`, into `best`.
    fn screen_within(&self, mult: &[f64], within: &[&Candidate], best: &mut Best) {
        let (k0, nc, m) = (self.k0, self.gc.len(), self.k0 + within.len());
        let mut g = DMatrix::<f64>::zeros(m, m);
        let mut h = DVector::<f64>::zeros(m);
        let (mut ee, mut n) = (0.0, 0.0);
        for (c, &k) in mult.iter().enumerate() {
            if k > 0.0 {
                g += &self.gc[c] * k;
                h += &self.hc[c] * k;
                ee += self.ec[c] * k;
                n += self.nrow[c] * k;
            }
        }
        let n_runs: f64 = (0..nc)
            .map(|c| mult[c] * self.runs_of[c].len() as f64)
            .sum();
        let gbb = g.view((0, 0), (k0, k0)).into_owned();
        let inv = gbb.try_inverse().unwrap_or_else(|| DMatrix::zeros(k0, k0));
        let hb = h.rows(0, k0).into_owned();
        let wrss0 = ee - (hb.transpose() * &inv * &hb)[(0, 0)];
        for (j, cand) in within.iter().enumerate() {
            let col = k0 + j;
            let gjb = g.view((col, 0), (1, k0)).into_owned();
            let s = g[(col, col)] - (&gjb * &inv * gjb.transpose())[(0, 0)];
            let num = h[col] - (&gjb * &inv * &hb)[(0, 0)];
            if !(s > 0.0 && wrss0 > 0.0) {
                continue;
            }
            let theta = num / s;
            if !(cand.sign_ok)(theta) {
                continue;
            }
            let wrss1 = (wrss0 - num * num / s).max(1e-300);
            let lr = (n * (wrss0 / wrss1).ln()).max(0.0);
            let chi2 = chi2_of_f(lr / cand.c_hat, 1.0, (n_runs - 1.0).max(1.0));
            best.consider(cand.term, -chi2 + n.ln());
        }
    }
}

/// The between-level candidates retested on the resampled runs (each copy of a cord is a cord
/// of its own), into `best`.
fn screen_between(p: &Problem, runs_of: &[Vec<usize>], mult: &[f64], best: &mut Best) {
    let mut rs = Runs {
        cord: Vec::new(),
        cords: 0,
        ln_mu: Vec::new(),
    };
    let mut pick: Vec<usize> = Vec::new();
    for (c, runs) in runs_of.iter().enumerate() {
        for _ in 0..mult[c] as usize {
            for &u in runs {
                rs.cord.push(rs.cords);
                rs.ln_mu.push(p.runs.ln_mu[u]);
                pick.push(u);
            }
            rs.cords += 1;
        }
    }
    let covs: Vec<Vec<f64>> = p
        .covs
        .iter()
        .map(|cv| pick.iter().map(|&u| cv[u]).collect())
        .collect();
    for cand in p.candidates.iter().filter(|c| c.column.is_none()) {
        let Some(gr) = &cand.g_run else { continue };
        let g: Vec<f64> = pick.iter().map(|&u| gr[u]).collect();
        if let Some((theta, _, dbic)) = between_evidence(&rs, &g, &covs) {
            if (cand.sign_ok)(theta) {
                best.consider(cand.term, dbic);
            }
        }
    }
}
