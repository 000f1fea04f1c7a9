//! Predicting measured T2 for a spec, with the contact's load memory carried along each run,
//! and the sensitivities (Jacobian) of every prediction with respect to θ.
//!
//! Every T2 comes from [`capstan_physics::FrictionLaw::t2_n`] and the model's
//! [`capstan_physics::SensorArtefacts`] exactly as in `Model::predict_t2_n` — at the row's own
//! T1, or (the evidence engine's within-run fits, [`RunRows::t1_shape_n`]) with the law read at
//! a shape point and its amplification applied to the row's T1; the load memory H
//! comes from [`LoadMemory::advance`] over the step timing. Within a step the load
//! L = T2 − T1 (true tensions) is held constant, so the window-centre memory depends on the
//! step's own T2: T2 = t2_n(T1, H(T2)) is solved as a scalar fixed point (bracketed
//! regula falsi). Sensitivities are propagated forward through the run: the law's partial
//! derivatives come from central differences of `t2_n` itself, the memory recursion and the
//! sensor artefacts are differentiated analytically, and the implicit step equation by the
//! implicit-function rule.

use super::obs::Observations;
use super::params::{ModelSpec, Param, Role};
use capstan_physics::{Model, Operating};

mod step;

use step::{memory_step, solve_step, solve_step_from, t2_at, Decay};

/// Predictions (and optionally the Jacobian) for a set of runs.
#[derive(Clone, Debug, Default)]
pub struct Evaluation {
    /// Predicted measured T2 per row (NaN for rows outside the evaluated runs), N.
    pub t2_n: Vec<f64>,
    /// Load memory H at each row's window centre, N s.
    pub load_memory_ns: Vec<f64>,
    /// d T2 / d θ per row (row-major, `n_free` columns; empty if not asked for).
    pub d_theta: Vec<f64>,
    /// Number of free parameters (columns of `d_theta`).
    pub n_free: usize,
}

impl Evaluation {
    /// The sensitivity row of row `i`.
    pub fn grad(&self, i: usize) -> &[f64] {
        &self.d_theta[i * self.n_free..(i + 1) * self.n_free]
    }
}

/// Predict every row of `runs` with θ and per-group offsets `u` (indexed by group; ignored
/// without a random effect). `jacobian` asks for d T2/d θ (the random-effect column of a
/// group's rows equals the θ column of the random-effect parameter).
pub fn evaluate(
    spec: &ModelSpec,
    theta: &[f64],
    u: &[f64],
    obs: &Observations,
    runs: &[usize],
    jacobian: bool,
) -> Evaluation {
    let n = obs.rows.len();
    let nf = spec.free.len();
    if jacobian && spec.tie.is_some() {
        return evaluate_by_differences(spec, theta, u, obs, runs);
    }
    let mut ev = Evaluation {
        t2_n: vec![f64::NAN; n],
        load_memory_ns: vec![0.0; n],
        d_theta: if jacobian {
            vec![0.0; n * nf]
        } else {
            Vec::new()
        },
        n_free: nf,
    };
    for &r in runs {
        let rows = &obs.runs[r];
        let g = obs.rows[rows[0]].group;
        let ug = if spec.random.is_some() {
            u.get(g).copied().unwrap_or(0.0)
        } else {
            0.0
        };
        let model = spec.model(theta, ug);
        let dvalue = spec.derivatives(theta, ug);
        run_one(spec, &model, &dvalue, obs, rows, jacobian, &mut ev);
    }
    ev
}

/// The Jacobian by central differences in θ (for specs with a tie).
fn evaluate_by_differences(
    spec: &ModelSpec,
    theta: &[f64],
    u: &[f64],
    obs: &Observations,
    runs: &[usize],
) -> Evaluation {
    let nf = spec.free.len();
    let mut ev = evaluate(spec, theta, u, obs, runs, false);
    ev.d_theta = vec![0.0; obs.rows.len() * nf];
    let rows = obs.rows_of(runs);
    for j in 0..nf {
        let s = 1e-6 * theta[j].abs().max(1e-2);
        let (mut up, mut dn) = (theta.to_vec(), theta.to_vec());
        up[j] += s;
        dn[j] -= s;
        let a = evaluate(spec, &up, u, obs, runs, false);
        let b = evaluate(spec, &dn, u, obs, runs, false);
        for &i in &rows {
            ev.d_theta[i * nf + j] = (a.t2_n[i] - b.t2_n[i]) / (2.0 * s);
        }
    }
    ev
}

/// Predict with a plain model (no spec) over every run: the population or group model as the
/// simulator would use it. Returns (T2, H) per row.
pub fn predict_model(model: &Model, obs: &Observations) -> (Vec<f64>, Vec<f64>) {
    let spec = ModelSpec::new("model", *model);
    let ev = evaluate(&spec, &[], &[], obs, &obs.all_runs(), false);
    (ev.t2_n, ev.load_memory_ns)
}

/// Predicted measured T2 of one run's rows (`rows`, in time order) with `model`, written to
/// `out[i]`. With contact heating (h ≠ 0) the load memory is carried from step to step when
/// `carry` (the run's step timing is known); otherwise each row starts from a cold contact at
/// its step change. Without heating and shape points every row is `model.predict_t2_n`.
///
/// `hint`, if given, holds predictions for nearby parameters (measured T2 per row, and maybe
/// the step equation's slope there): the step equation is then polished by Newton's method
/// from there, one or two law evaluations instead of a bracketed search. With heating,
/// `slopes` (if given) receives each row's slope for later hints.
pub fn predict_run(
    model: &Model,
    rows: RunRows<'_>,
    carry: bool,
    hint: Option<Hint<'_>>,
    out: &mut [f64],
    mut slopes: Option<&mut [f64]>,
) {
    let RunRows {
        t1_n,
        t1_shape_n,
        op,
        timing,
        rows,
    } = rows;
    let law = &model.law;
    let shape = |i: usize, x: f64| shape_point(model, x, t1_shape_n.map(|s| s[i]));
    if law.heat_per_ns == 0.0 {
        for &i in rows {
            let x = model.sensors.true_t1_n(t1_n[i]);
            let xs = shape(i, x);
            out[i] = if xs == x {
                model.predict_t2_n(t1_n[i], &op[i])
            } else {
                model.sensors.measured_t2_n(law.t2_n(xs, &op[i]) * (x / xs))
            };
        }
        return;
    }
    let tau = law.heat_tau_s;
    let mut decay = Decay::new(tau);
    let mut h_acc = 0.0;
    let mut prev_end: Option<f64> = None;
    for &i in rows {
        let tm = timing[i];
        match prev_end {
            Some(end) if carry && tm.change_s > end => {
                h_acc = decay.after(h_acc, tm.change_s - end, 0.0);
            }
            Some(_) if carry => {}
            _ => h_acc = 0.0,
        }
        // The step is solved at the shape point (its load is what the contact remembers) and
        // its amplification applied to the row's own T1.
        let x_row = model.sensors.true_t1_n(t1_n[i]);
        let x = shape(i, x_row);
        let scale = if x == x_row { 1.0 } else { x_row / x };
        let dt_c = tm.centre_s - tm.change_s;
        let near = hint.map(|h| {
            let y0 = (h.t2[i] - model.sensors.t2_offset_n) / model.sensors.t2_gain;
            (y0 / scale, h.slope.map_or(f64::NAN, |s| s[i]))
        });
        let (y, slope) = match near {
            Some((y0, s0)) => {
                let a_c = decay.factor(dt_c);
                solve_step_from(law, x, &op[i], (h_acc, dt_c, a_c), (y0, s0))
            }
            None => (solve_step(law, x, &op[i], h_acc, dt_c).0, f64::NAN),
        };
        if let Some(s) = slopes.as_deref_mut() {
            s[i] = slope;
        }
        out[i] = model.sensors.measured_t2_n(y * scale);
        h_acc = decay.after(h_acc, tm.end_s - tm.change_s, y - x);
        prev_end = Some(tm.end_s);
    }
}

/// The true T1 at which a row's law is read: the true T1 of its shape reading (see
/// [`RunRows::t1_shape_n`]; NaN: none) where both that and the row's own `x` are above zero,
/// else `x`; the law's amplification there is then applied to `x`.
pub fn shape_point(model: &Model, x: f64, t1_shape_n: Option<f64>) -> f64 {
    let Some(t) = t1_shape_n.filter(|t| t.is_finite()) else {
        return x;
    };
    let xs = model.sensors.true_t1_n(t);
    if x > 0.0 && xs > 0.0 {
        xs
    } else {
        x
    }
}

/// Nearby predictions for [`predict_run`]: measured T2 per row, and the step equation's
/// slope per row where known (NaN or `None`: computed afresh).
#[derive(Clone, Copy)]
pub struct Hint<'a> {
    /// Measured T2 per row, N.
    pub t2: &'a [f64],
    /// d(G(y) − y)/dy of the step equation per row.
    pub slope: Option<&'a [f64]>,
}

/// The rows of one run and what predicting them needs, by row index.
#[derive(Clone, Copy)]
pub struct RunRows<'a> {
    /// Measured T1 per row, N.
    pub t1_n: &'a [f64],
    /// Measured T1 per row at which the law's shape (its dependence on tension and the load
    /// the contact remembers) is read, NaN where the row's own: the evidence engine's
    /// (`evidence::design::Design::t1_shape`). `None` (the population fits of `capstan
    /// analyze`, which predict new cords): every row at its own T1.
    pub t1_shape_n: Option<&'a [f64]>,
    /// Operating point per row.
    pub op: &'a [Operating],
    /// Step timing per row.
    pub timing: &'a [super::obs::StepTiming],
    /// The run's rows, in time order.
    pub rows: &'a [usize],
}

fn run_one(
    spec: &ModelSpec,
    model: &Model,
    dvalue: &[f64],
    obs: &Observations,
    rows: &[usize],
    jacobian: bool,
    ev: &mut Evaluation,
) {
    let law = &model.law;
    let sensors = &model.sensors;
    let tau = law.heat_tau_s;
    let nf = spec.free.len();
    let mut h_acc = 0.0;
    let mut dh_acc = vec![0.0; nf];
    let mut t_prev_end: Option<f64> = None;
    let mut scratch = (vec![0.0; nf], vec![0.0; nf]);
    // Without step times a run's rows carry no memory from one to the next.
    let carry = obs.timing != super::obs::TimingSource::None;
    for &i in rows {
        let row = &obs.rows[i];
        let tm = row.timing;
        if !carry {
            h_acc = 0.0;
            dh_acc.fill(0.0);
            t_prev_end = None;
        }
        // Idle gap since the previous step (no load): the memory decays.
        if let Some(t_end) = t_prev_end {
            let gap = tm.change_s - t_end;
            if gap > 0.0 {
                let (h, a, _, dtau) = memory_step(h_acc, gap, 0.0, tau);
                h_acc = h;
                if jacobian {
                    decay_gradient(spec, dvalue, (a, dtau), &mut dh_acc);
                }
            }
        }
        let x = sensors.true_t1_n(row.t1_n);
        let dt_c = tm.centre_s - tm.change_s;
        let (y, h_c) = solve_step(law, x, &row.op, h_acc, dt_c);
        let load = y - x;
        let (_, a_c, b_c, dtau_c) = memory_step(h_acc, dt_c, load, tau);
        let dt_s = tm.end_s - tm.change_s;
        let (h_next, a_s, b_s, dtau_s) = memory_step(h_acc, dt_s, load, tau);
        ev.t2_n[i] = sensors.measured_t2_n(y);
        ev.load_memory_ns[i] = h_c;
        if jacobian && y.is_finite() {
            let pt = StepPoint {
                x,
                y,
                h_c,
                load,
                centre: (a_c, b_c, dtau_c),
                end: (a_s, b_s, dtau_s),
            };
            let grad = &mut ev.d_theta[i * nf..(i + 1) * nf];
            step_gradient(
                (spec, model, dvalue),
                row,
                &pt,
                &mut dh_acc,
                &mut scratch,
                grad,
            );
        }
        h_acc = h_next;
        t_prev_end = Some(tm.end_s);
    }
}

/// The memory's gradient over an idle gap: decayed by `a`, plus the gap's own dependence on τ
/// (`dtau`) for a τ parameter.
fn decay_gradient(spec: &ModelSpec, dvalue: &[f64], (a, dtau): (f64, f64), dh_acc: &mut [f64]) {
    for (j, f) in spec.free.iter().enumerate() {
        dh_acc[j] *= a;
        if f.param.role() == Role::Tau {
            dh_acc[j] += dtau * dvalue[j];
        }
    }
}

/// One step's solution for the gradient: the true T1 `x`, true T2 `y`, the memory at the
/// window centre `h_c`, the load y − x, and the memory's (decay, gain, dτ) to the centre and
/// to the step's end.
struct StepPoint {
    x: f64,
    y: f64,
    h_c: f64,
    load: f64,
    centre: (f64, f64, f64),
    end: (f64, f64, f64),
}

/// The measured T2's gradient in the free values at one step (into `grad`), through the
/// step equation's implicit derivative, and the memory's gradient carried to the step's end
/// (`dh_acc`). `scratch` holds dx/dθ and dy/dθ.
fn step_gradient(
    (spec, model, dvalue): (&ModelSpec, &Model, &[f64]),
    row: &super::obs::Row,
    pt: &StepPoint,
    dh_acc: &mut [f64],
    (dx, dy): &mut (Vec<f64>, Vec<f64>),
    grad: &mut [f64],
) {
    let (law, sensors, op) = (&model.law, &model.sensors, &row.op);
    let (x, h_c) = (pt.x, pt.h_c);
    let (a_c, b_c, dtau_c) = pt.centre;
    // Central differences of the law in T1, H and each law parameter.
    let sx = 1e-6 * x.abs().max(1e-3);
    let f_x = (t2_at(law, x + sx, op, h_c) - t2_at(law, x - sx, op, h_c)) / (2.0 * sx);
    let sh = 1e-6 * h_c.abs().max(1.0);
    let f_h = (t2_at(law, x, op, h_c + sh) - t2_at(law, x, op, h_c - sh)) / (2.0 * sh);
    let ind = if pt.load > 0.0 { 1.0 } else { 0.0 };
    let denom = 1.0 - f_h * b_c * ind;
    for (j, f) in spec.free.iter().enumerate() {
        dx[j] = if f.param.role() == Role::T1Offset {
            d_true_t1_d_offset(sensors, row.t1_n) * dvalue[j]
        } else {
            0.0
        };
        let direct = if f.param.role() == Role::Law {
            d_law(model, f.param, x, op, h_c) * dvalue[j]
        } else {
            0.0
        };
        let tau_c = if f.param.role() == Role::Tau {
            dtau_c * dvalue[j]
        } else {
            0.0
        };
        let hc_known = a_c * dh_acc[j] + tau_c;
        dy[j] = (f_x * dx[j] + f_h * (hc_known - b_c * ind * dx[j]) + direct) / denom;
    }
    let (a_s, b_s, dtau_s) = pt.end;
    let g = sensors.t2_gain;
    for (j, f) in spec.free.iter().enumerate() {
        grad[j] = g * dy[j]
            + match f.param.role() {
                Role::T2Gain => pt.y * dvalue[j],
                Role::T2Offset => dvalue[j],
                _ => 0.0,
            };
        // Memory at the end of the step.
        let tau_s = if f.param.role() == Role::Tau {
            dtau_s * dvalue[j]
        } else {
            0.0
        };
        dh_acc[j] = a_s * dh_acc[j] + tau_s + b_s * (dy[j] - dx[j]);
    }
}

/// d(true T1)/d(T1 offset) at the reading `t1_n`, by a central difference.
fn d_true_t1_d_offset(sensors: &capstan_physics::SensorArtefacts, t1_n: f64) -> f64 {
    let off = sensors.t1_offset_n;
    let s = 1e-7;
    let at = |o: f64| {
        capstan_physics::SensorArtefacts {
            t1_offset_n: o,
            ..*sensors
        }
        .true_t1_n(t1_n)
    };
    (at(off + s) - at(off - s)) / (2.0 * s)
}

/// ∂T2/∂p of the law in parameter `p` at (x, H), by a central difference.
fn d_law(model: &Model, p: Param, x: f64, op: &Operating, h_c: f64) -> f64 {
    let v = p.get(model);
    let s = 1e-6 * v.abs().max(p.scale());
    let mut up = *model;
    let mut dn = *model;
    p.set(&mut up, v + s);
    p.set(&mut dn, v - s);
    (t2_at(&up.law, x, op, h_c) - t2_at(&dn.law, x, op, h_c)) / (2.0 * s)
}

/// The parameter list of a spec, for messages.
pub fn param_names(spec: &ModelSpec) -> Vec<&'static str> {
    spec.free.iter().map(|f| Param::name(f.param)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use capstan_physics::LoadMemory;

    #[test]
    fn the_law_is_read_at_the_shape_point_where_one_is_given() {
        let m = Model::euler_eytelwein(0.1);
        // A shape reading: its true T1 (with the model's T1 offset).
        assert_eq!(shape_point(&m, 9.0, Some(10.0)), 10.0);
        let mut o = m;
        o.sensors.t1_offset_n = 0.5;
        assert_eq!(shape_point(&o, 9.0, Some(10.0)), 9.5);
        // None, NaN (the design's "own"), or either side not above zero: the row's own.
        assert_eq!(shape_point(&m, 9.0, None), 9.0);
        assert_eq!(shape_point(&m, 9.0, Some(f64::NAN)), 9.0);
        assert_eq!(shape_point(&m, 0.0, Some(10.0)), 0.0);
        assert_eq!(shape_point(&m, 9.0, Some(-1.0)), 9.0);
        // Euler-Eytelwein has no shape in tension: the prediction does not change.
        let op = [Operating::from_wrap_deg(540.0)];
        let tm = [super::super::obs::StepTiming {
            change_s: 0.0,
            centre_s: 2.0,
            end_s: 3.5,
        }];
        let mut a = [0.0];
        let mut b = [0.0];
        let rows = |shape: Option<&'static [f64]>| RunRows {
            t1_n: &[9.0],
            t1_shape_n: shape,
            op: &op,
            timing: &tm,
            rows: &[0],
        };
        predict_run(&m, rows(None), true, None, &mut a, None);
        predict_run(&m, rows(Some(&[12.0])), true, None, &mut b, None);
        assert!((a[0] - b[0]).abs() <= 1e-12 * a[0], "{} {}", a[0], b[0]);
        // A power law is read at the shape point: T2 = x·A(x_s).
        let mut p = m;
        p.law.tension_exponent = 0.8;
        predict_run(&p, rows(Some(&[12.0])), true, None, &mut b, None);
        let want = 9.0 * p.law.t2_n(12.0, &op[0]) / 12.0;
        assert!((b[0] - want).abs() <= 1e-12 * want, "{} {want}", b[0]);
    }
    use crate::fit::params::Transform;
    use capstan_data::thesis_dataset;

    fn model_a() -> ModelSpec {
        let mut base = Model::euler_eytelwein(0.1417);
        base.law.heat_per_ns = 0.00128;
        base.law.heat_tau_s = 6.8;
        base.law.mu_log_slope_per_rad = 0.0148;
        base.sensors.t1_offset_n = 0.2;
        ModelSpec::new("A", base)
            .free(Param::Mu)
            .free(Param::HeatPerNs)
            .free(Param::HeatTauS)
            .free(Param::T1Offset)
            .free(Param::MuLogSlopePerRad)
            .free_with(Param::T2Gain, Transform::Log)
            .free(Param::T2Offset)
            .free(Param::TensionExponent)
            .free(Param::MuChangePer100s)
            .random_effect_on(Param::Mu)
    }

    #[test]
    fn steps_are_self_consistent_and_go_through_the_model() {
        let obs = Observations::from_dataset(&thesis_dataset());
        let spec = model_a();
        let th = spec.start();
        let ev = evaluate(&spec, &th, &[0.0; 10], &obs, &obs.all_runs(), false);
        let m = spec.model(&th, 0.0);
        // Replay one run by hand with LoadMemory and Model::predict_t2_n.
        let mut mem = LoadMemory::default();
        for &i in &obs.runs[7] {
            let r = &obs.rows[i];
            let t2 = ev.t2_n[i];
            let load = m.sensors.true_t1_n(r.t1_n);
            let load = t2 - load;
            let mut c = mem;
            c.advance(5.5, load, m.law.heat_tau_s);
            assert!((c.h_ns - ev.load_memory_ns[i]).abs() < 1e-9);
            let op = Operating {
                load_memory_ns: c.h_ns,
                ..r.op
            };
            assert!((m.predict_t2_n(r.t1_n, &op) - t2).abs() < 1e-9 * t2.max(1.0));
            mem.advance(10.0, load, m.law.heat_tau_s);
        }
    }

    #[test]
    fn one_run_predicts_as_the_whole_evaluation() {
        let obs = Observations::from_dataset(&thesis_dataset());
        let spec = model_a();
        let th = spec.start();
        let ev = evaluate(&spec, &th, &[0.0; 10], &obs, &obs.all_runs(), false);
        let m = spec.model(&th, 0.0);
        let t1: Vec<f64> = obs.rows.iter().map(|r| r.t1_n).collect();
        let op: Vec<Operating> = obs.rows.iter().map(|r| r.op).collect();
        let tm: Vec<_> = obs.rows.iter().map(|r| r.timing).collect();
        let mut out = vec![f64::NAN; obs.len()];
        let mut near = vec![f64::NAN; obs.len()];
        for run in &obs.runs {
            let rows = RunRows {
                t1_n: &t1,
                t1_shape_n: None,
                op: &op,
                timing: &tm,
                rows: run,
            };
            predict_run(&m, rows, true, None, &mut out, None);
            // From a nearby solution, Newton's method finds the same one.
            let hint: Vec<f64> = out.iter().map(|y| y * 1.001).collect();
            let h = Hint {
                t2: &hint,
                slope: None,
            };
            predict_run(&m, rows, true, Some(h), &mut near, None);
        }
        for i in 0..obs.len() {
            assert!((out[i] - ev.t2_n[i]).abs() <= 1e-12 * ev.t2_n[i].abs().max(1.0));
            assert!((near[i] - out[i]).abs() <= 1e-10 * out[i].abs().max(1.0));
        }
    }

    #[test]
    fn jacobian_matches_central_differences() {
        let obs = Observations::from_dataset(&thesis_dataset());
        let spec = model_a();
        let mut th = spec.start();
        th[7] = 0.4; // n away from 1
        th[8] = 0.02;
        let u = [0.05, -0.02, 0.0, 0.01, 0.0, -0.07, 0.0, 0.0, 0.01, 0.03];
        let runs: Vec<usize> = vec![0, 5, 13, 31, 59];
        let ev = evaluate(&spec, &th, &u, &obs, &runs, true);
        for j in 0..th.len() {
            let s = 1e-5;
            let mut up = th.clone();
            up[j] += s;
            let mut dn = th.clone();
            dn[j] -= s;
            let a = evaluate(&spec, &up, &u, &obs, &runs, false);
            let b = evaluate(&spec, &dn, &u, &obs, &runs, false);
            for i in obs.rows_of(&runs) {
                let num = (a.t2_n[i] - b.t2_n[i]) / (2.0 * s);
                let ana = ev.grad(i)[j];
                assert!(
                    (num - ana).abs() <= 1e-5 * (1.0 + num.abs()),
                    "param {} row {i}: {ana} vs {num}",
                    spec.free[j].param
                );
            }
        }
    }
}
