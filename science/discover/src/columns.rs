//! The catalogue fit linearised: every row's sensitivity to its run's mu (a), to the selected
//! catalogue parameters (B), to the T1 that reaches the capstan, and each library term's
//! column x = ∂T2m/∂θ at θ = 0.
//!
//! A term's column is exact to first order in θ:
//! * mu → mu·(1 + θg): x = a·mu_run·g. The load memory of the catalogue's contact heating
//!   lasts a fraction of a second against steps of seconds, so a row's mu moves its own T2 only.
//! * T1c = T1m + θg: x = (∂T2m/∂T1m)·g, the derivative by a forward difference of the model.
//! * T2m = T2 + o2 + θg(T2): x = gain·g(T2) at the model's true T2.
//! * adhesion: ∂T2/∂a at a = 0 is (R/mu)(e^{mu β} − 1) = (∂T2/∂T1c)·(R/mu)(1 − e^{−mu β}), with
//!   mu the row's effective ln(T2/T1c)/β.

use crate::library::{Form, Row, Term};
use capstan_engine::evidence::candidates::run_model;
use capstan_engine::evidence::design::Design;
use capstan_engine::evidence::within::WithinFit;
use capstan_engine::fit::predict::{predict_run, Hint, RunRows};
use capstan_physics::Model;

/// The linearised catalogue fit.
pub struct Base<'a> {
    /// The data as laid out.
    pub d: &'a Design,
    /// Weights of the fit.
    pub w: Vec<f64>,
    /// Residuals T2 − fitted, N.
    pub e: Vec<f64>,
    /// ∂T2m/∂mu_run per row.
    pub a: Vec<f64>,
    /// ∂T2m/∂θ_catalogue, one column per selected within-run effect.
    pub b: Vec<Vec<f64>>,
    /// ∂T2m/∂T1m per row.
    pub dt1: Vec<f64>,
    /// Per row: the quantities the library's terms read.
    pub rows: Vec<Row>,
    /// Per row: the run's mu.
    pub mu_row: Vec<f64>,
    /// Per row: the T2 gain of the run's model.
    pub gain: Vec<f64>,
    /// Per row: its run.
    pub run_of_row: Vec<usize>,
    /// Per row: its cord.
    pub cord_of_row: Vec<usize>,
}

/// Predict every row with the run models `models`, T1 (and its shape points) as given.
fn predict_all(
    d: &Design,
    models: &[Model],
    (t1, t1_shape): (&[f64], &[f64]),
    hint: Option<Hint<'_>>,
    out: &mut [f64],
    slopes: Option<&mut [f64]>,
) {
    let mut slopes = slopes;
    for (u, m) in models.iter().enumerate() {
        let rr = RunRows {
            t1_n: t1,
            t1_shape_n: Some(t1_shape),
            op: &d.op,
            timing: &d.timing,
            rows: &d.units[u],
        };
        predict_run(m, rr, d.timed, hint, out, slopes.as_deref_mut());
    }
}

/// Every run's model at its mu (as `mu_of` moves it) and the within-run parameters `theta`.
fn run_models(fit: &WithinFit, mu_of: impl Fn(f64) -> f64, theta: &[f64]) -> Vec<Model> {
    fit.mu
        .iter()
        .map(|&mu| run_model(&fit.maps, mu_of(mu), theta))
        .collect()
}

/// The catalogue fit and its prediction `f0`, which every derivative is taken from.
struct Fitted<'f> {
    d: &'f Design,
    fit: &'f WithinFit,
    /// Every run's model.
    models: &'f [Model],
    /// The fitted T2m per row.
    f0: &'f [f64],
    /// `f0` and its slopes, to start the moved predictions from.
    hint: Option<Hint<'f>>,
}

impl Fitted<'_> {
    /// a: ∂T2m/∂mu_run per row (forward difference, mu·(1 + 10⁻⁶)), and each row's run.
    fn d_mu(&self, scratch: &mut [f64]) -> (Vec<f64>, Vec<usize>) {
        let (d, fit, n) = (self.d, self.fit, self.f0.len());
        let bumped = run_models(fit, |mu| mu * (1.0 + 1e-6), &fit.theta);
        predict_all(d, &bumped, (&d.t1, &d.t1_shape), self.hint, scratch, None);
        let mut run_of_row = vec![0; n];
        let mut a = vec![0.0; n];
        for (u, rows) in d.units.iter().enumerate() {
            for &i in rows {
                run_of_row[i] = u;
                a[i] = (scratch[i] - self.f0[i]) / (fit.mu[u] * 1e-6);
            }
        }
        (a, run_of_row)
    }

    /// B: ∂T2m/∂θ for each of the catalogue's within-run parameters (a step inside its map).
    fn d_theta(&self, scratch: &mut [f64]) -> Vec<Vec<f64>> {
        let (d, fit, n) = (self.d, self.fit, self.f0.len());
        let mut b = Vec::with_capacity(fit.k());
        for j in 0..fit.k() {
            let map = fit.maps[j];
            let step = map.step();
            let hb = if fit.theta[j] + step > map.hi {
                -step
            } else {
                step
            };
            let mut th = fit.theta.clone();
            th[j] += hb;
            let ms = run_models(fit, |mu| mu, &th);
            predict_all(d, &ms, (&d.t1, &d.t1_shape), self.hint, scratch, None);
            b.push((0..n).map(|i| (scratch[i] - self.f0[i]) / hb).collect());
        }
        b
    }

    /// ∂T2m/∂T1m: the whole T1 (and its shape point) moved by h.
    fn d_t1(&self, scratch: &mut [f64]) -> Vec<f64> {
        let (d, n) = (self.d, self.f0.len());
        let h = 1e-5;
        let t1p: Vec<f64> = d.t1.iter().map(|t| t + h).collect();
        let t1sp: Vec<f64> = d.t1_shape.iter().map(|t| t + h).collect();
        predict_all(d, self.models, (&t1p, &t1sp), self.hint, scratch, None);
        (0..n).map(|i| (scratch[i] - self.f0[i]) / h).collect()
    }

    /// Per row: its run's mu and T2 gain, and the model's true T2 and T1.
    fn per_row(&self) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
        let (d, n) = (self.d, self.f0.len());
        let mut mu_row = vec![0.0; n];
        let mut gain = vec![1.0; n];
        let mut t2_true = vec![0.0; n];
        let mut t1_true = vec![0.0; n];
        for (u, rows) in d.units.iter().enumerate() {
            let s = self.models[u].sensors;
            for &i in rows {
                mu_row[i] = self.fit.mu[u];
                gain[i] = s.t2_gain;
                t2_true[i] = (self.f0[i] - s.t2_offset_n) / s.t2_gain;
                t1_true[i] = s.true_t1_n(d.t1[i]);
            }
        }
        (mu_row, gain, t2_true, t1_true)
    }
}

impl<'a> Base<'a> {
    /// Linearise `fit` (weights `w`) on `d`.
    pub fn new(d: &'a Design, fit: &WithinFit, w: &[f64]) -> Base<'a> {
        let n = d.n();
        let models = run_models(fit, |mu| mu, &fit.theta);
        let (mut f0, mut slope) = (vec![0.0; n], vec![f64::NAN; n]);
        predict_all(
            d,
            &models,
            (&d.t1, &d.t1_shape),
            None,
            &mut f0,
            Some(&mut slope),
        );
        let at = Fitted {
            d,
            fit,
            models: &models,
            f0: &f0,
            hint: Some(Hint {
                t2: &f0,
                slope: Some(&slope),
            }),
        };
        let mut scratch = vec![0.0; n];
        let (a, run_of_row) = at.d_mu(&mut scratch);
        let b = at.d_theta(&mut scratch);
        let dt1 = at.d_t1(&mut scratch);
        let (mu_row, gain, t2_true, t1_true) = at.per_row();
        let rows = row_quantities(d, &t1_true, &t2_true);
        let cord_of_row = run_of_row.iter().map(|&u| d.unit_cord[u]).collect();
        Base {
            d,
            w: w.to_vec(),
            e: (0..n).map(|i| d.t2[i] - f0[i]).collect(),
            a,
            b,
            dt1,
            rows,
            mu_row,
            gain,
            run_of_row,
            cord_of_row,
        }
    }

    /// The term's column x = ∂T2m/∂θ at θ = 0.
    pub fn column(&self, t: &Term) -> Vec<f64> {
        self.column_at(t, None)
    }

    /// The term's column with its centre in T1 at `t1_ref` (N) instead of the design's
    /// geometric-mean T1 (None: that), for a term that reads it ([`crate::library::centred`]).
    pub fn column_at(&self, t: &Term, t1_ref: Option<f64>) -> Vec<f64> {
        let n = self.d.n();
        (0..n)
            .map(|i| {
                let r = &Row {
                    t1_ref: t1_ref.unwrap_or(self.rows[i].t1_ref),
                    ..self.rows[i]
                };
                let v = match t.form {
                    Form::Mu(g) => self.a[i] * self.mu_row[i] * g(r),
                    Form::T1(g) => self.dt1[i] * g(r),
                    Form::T2(g) => self.gain[i] * g(r),
                    Form::Adhesion => {
                        let t1c = r.t1.max(1e-3);
                        let mu = ((r.t2.max(t1c) / t1c).ln() / r.wrap).max(1e-3);
                        let radius = 0.5 * r.diameter;
                        self.dt1[i] * radius / mu * (1.0 - (-mu * r.wrap).exp())
                    }
                };
                if v.is_finite() {
                    v
                } else {
                    0.0
                }
            })
            .collect()
    }
}

/// The library's row quantities from the model's true tensions.
fn row_quantities(d: &Design, t1_true: &[f64], t2_true: &[f64]) -> Vec<Row> {
    let n = d.n();
    let nc = d.cords.len().max(1) as f64;
    let wrap_mean = d.cords.iter().map(|c| c.wrap_deg.to_radians()).sum::<f64>() / nc;
    let diameter_mean = d.cords.iter().map(|c| c.diameter_mm).sum::<f64>() / nc;
    let drive_v_mean = d.cords.iter().map(|c| c.drive_v).sum::<f64>() / nc;
    let (ln_sum, ln_n) =
        d.t1.iter()
            .filter(|t| t.is_finite() && **t > 0.0)
            .fold((0.0, 0.0), |(s, n), t| (s + t.ln(), n + 1.0));
    let t1_ref = if ln_n > 0.0 {
        (ln_sum / ln_n).exp()
    } else {
        1.0
    };
    let mut rows = vec![Row::default(); n];
    for (u, idx) in d.units.iter().enumerate() {
        let t_first = idx.first().map_or(0.0, |&i| d.timing[i].centre_s);
        let mut work = 0.0;
        let mut prev_load = 0.0;
        for (k, &i) in idx.iter().enumerate() {
            let op = &d.op[i];
            let load = (t2_true[i] - t1_true[i]).max(0.0);
            let dt = if d.timed {
                (d.timing[i].end_s - d.timing[i].change_s).max(0.0)
            } else {
                10.0
            };
            rows[i] = Row {
                t1: d.t1[i],
                t2: t2_true[i],
                load,
                wrap: op.wrap_rad,
                wrap_mean,
                diameter: op.diameter_mm,
                diameter_mean,
                time_in_run: if d.timed {
                    d.timing[i].centre_s - t_first
                } else {
                    10.0 * k as f64
                },
                run: d.unit_run[u],
                falling: d.falling[i].unwrap_or(false),
                drive_v: op.drive_v,
                drive_v_mean,
                work_before_kns: work,
                load_prev: prev_load,
                t1_ref,
            };
            work += load * dt / 1000.0;
            prev_load = load;
        }
    }
    rows
}
