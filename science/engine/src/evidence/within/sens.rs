//! Analytic sensitivities of the within-run predictions: ∂f/∂mu (own run) and ∂f/∂θ for
//! every row in one pass, from the friction law's closed-form partials
//! (`FrictionLaw::partials_at`) and the chain rule through the load memory.
//!
//! Forward differences cost one prediction of every run per parameter (with heating, each
//! solves the step equation again; with bending stiffness each law evaluation solves the
//! lift-off's wrap): with three effects, four predictions per iteration of the fit. Here the
//! derivatives come at about the cost of one. `jacobian_by_differences` stays as their check
//! (tests) and for any effect this file does not know.
//!
//! Along a run, with x the true T1, y the true T2 of a row, H_c the memory at its sample:
//!
//! * y = G(x, k(H_c), n, √B), H_c = a_c·H + τ(1 − a_c)·max(y − x, 0), a_c = e^(−Δt_c/τ);
//! * dy/dp = (G_k·(k_p + k_H·a_c·dH/dp − k_H·b·dx/dp) + G_x·dx/dp + G_p) / (1 − G_k·k_H·b),
//!   b = τ(1 − a_c) while the cord carries load (the step equation's implicit derivative);
//! * the memory carried to the next step: dH/dp ← a_s·dH/dp + τ(1 − a_s)·(dy/dp − dx/dp),
//!   and across an idle gap dH/dp ← a_g·dH/dp;
//! * the measured T2 f = g·y + o₂: ∂f/∂p = g·dy/dp (+ 1 for the T2 offset itself).

use super::{Sens, Strata};
use crate::evidence::candidates::{run_model, ThetaMap};
use crate::evidence::design::Design;
use crate::fit::predict::shape_point;
use capstan_physics::{Operating, HEAT_TAU_S, SLACK_T1_N};

/// What a θ moves, for the chain rule: the law's closed-form partial its entry names.
pub(super) use capstan_physics::entry::Partial as Role;

/// The roles of `maps`, if every one has an analytic sensitivity.
pub(super) fn roles(maps: &[ThetaMap]) -> Option<Vec<Role>> {
    maps.iter().map(|m| m.kind.entry().partial).collect()
}

/// e^(−dt/τ) and τ(1 − e^(−dt/τ)): the memory's decay and its gain per newton of load over
/// `dt` (1 and 0 when nothing passes).
fn decay(dt: f64, tau: f64) -> (f64, f64) {
    if dt <= 0.0 || tau <= 0.0 {
        return (1.0, 0.0);
    }
    let a = (-dt / tau).exp();
    (a, tau * (1.0 - a))
}

/// Fill `s` with the sensitivities at (mu, θ), whose predictions (measured T2) are `f0`.
pub(super) fn jacobian(
    d: &Design,
    (maps, strata): (&[ThetaMap], &Strata),
    (mu, theta): (&[f64], &[f64]),
    f0: &[f64],
    roles: &[Role],
    s: &mut Sens,
) {
    let k = maps.len();
    s.b.iter_mut().for_each(|x| *x = 0.0);
    for (u, rows) in d.units.iter().enumerate() {
        let blk = strata.block(u);
        let model = run_model(&maps[blk.clone()], mu[u], &theta[blk.clone()]);
        let run_roles = &roles[blk.clone()];
        let out = RunOut {
            a: &mut s.a,
            b: &mut s.b,
            k,
            first: blk.start,
        };
        run(d, rows, &model, run_roles, f0, out);
    }
}

/// Where one run's sensitivities go: `a[i]`, and `b[i·k + first + j]` for its θ_j.
struct RunOut<'a> {
    a: &'a mut [f64],
    b: &'a mut [f64],
    k: usize,
    first: usize,
}

/// One run's rows, in time order, carrying the memory and its derivatives.
fn run(
    d: &Design,
    rows: &[usize],
    model: &capstan_physics::Model,
    roles: &[Role],
    f0: &[f64],
    out: RunOut<'_>,
) {
    // The memory matters only with heating in the set (at θ = 0 too: its slope needs H).
    let tau = if roles.contains(&Role::Heating) {
        HEAT_TAU_S
    } else {
        0.0
    };
    let np = roles.len() + 1; // mu, then θ
    let mut h_acc = 0.0;
    let mut dh = vec![0.0; np];
    let mut dy = vec![0.0; np];
    let mut prev_end: Option<f64> = None;
    for &i in rows {
        let tm = d.timing[i];
        carry_gap(d, i, prev_end, tau, (&mut h_acc, &mut dh));
        let row = row_point(d, i, model, f0);
        let (a_c, b_c) = decay(tm.centre_s - tm.change_s, tau);
        let h_c = h_acc * a_c + row.load.max(0.0) * b_c;
        let op = Operating {
            load_memory_ns: h_c,
            ..d.op[i]
        };
        let partials = model.law.partials_at(row.x, row.y, &op);
        let b_c = if row.load > 0.0 { b_c } else { 0.0 };
        let memory = (a_c, b_c, &dh[..]);
        row_sens(&row, partials, memory, roles, &mut dy);
        for (p, df) in row.df(roles, &dy, model.sensors.t2_gain).enumerate() {
            match p {
                0 => out.a[i] = df,
                _ => out.b[i * out.k + out.first + p - 1] = df,
            }
        }
        let (a_s, b_s) = decay(tm.end_s - tm.change_s, tau);
        let b_s_on = if row.load > 0.0 { b_s } else { 0.0 };
        for p in 0..np {
            dh[p] = a_s * dh[p] + b_s_on * (dy[p] - row.dx(roles, p));
        }
        h_acc = h_acc * a_s + row.load.max(0.0) * b_s;
        prev_end = Some(tm.end_s);
    }
}

/// The memory (and its derivatives) at row `i`'s change: decayed over the idle gap since the
/// run's previous step when timed, or 0 at a run's start or without times.
fn carry_gap(
    d: &Design,
    i: usize,
    prev_end: Option<f64>,
    tau: f64,
    (h_acc, dh): (&mut f64, &mut [f64]),
) {
    let tm = d.timing[i];
    match prev_end {
        Some(end) if d.timed && tm.change_s > end => {
            let (a_g, _) = decay(tm.change_s - end, tau);
            *h_acc *= a_g;
            dh.iter_mut().for_each(|x| *x *= a_g);
        }
        Some(_) if d.timed => {}
        _ => {
            *h_acc = 0.0;
            dh.iter_mut().for_each(|x| *x = 0.0);
        }
    }
}

/// One row's point for the chain rule: the law is read at the shape point `x` (both loaded
/// there, so both move with the offset) and its amplification applied to the row's true T1:
/// y_row = x_row·y/x.
struct RowPoint {
    /// The shape point, N (the row's true T1 unless shaped).
    x: f64,
    /// True T2 at the shape point, N.
    y: f64,
    /// x_row/x (1 unless shaped).
    scale: f64,
    shaped: bool,
    /// y − x, N.
    load: f64,
    /// dx/d(T1 offset): 0 for a slack reading, else −1.
    dx_do: f64,
}

impl RowPoint {
    /// dx/dp of parameter `p` (0: mu, then θ): only the T1 offset moves x.
    fn dx(&self, roles: &[Role], p: usize) -> f64 {
        if p > 0 && roles[p - 1] == Role::T1Offset {
            self.dx_do
        } else {
            0.0
        }
    }

    /// ∂f/∂p of the measured T2 f = g·y_row + o₂ from dy/dp, every p in order.
    fn df<'a>(
        &'a self,
        roles: &'a [Role],
        dy: &'a [f64],
        t2_gain: f64,
    ) -> impl Iterator<Item = f64> + 'a {
        dy.iter().enumerate().map(move |(p, &dy_p)| {
            let role = (p > 0).then(|| roles[p - 1]);
            let dx = self.dx(roles, p);
            // d(x_row·y/x), x_row and x moving alike with the offset.
            let dy_row = if self.shaped {
                self.scale * dy_p + (self.y / self.x) * (dx - self.scale * dx)
            } else {
                dy_p
            };
            t2_gain * dy_row
                + if role == Some(Role::T2Offset) {
                    1.0
                } else {
                    0.0
                }
        })
    }
}

/// Row `i`'s point from its reading and the prediction `f0[i]` (measured T2).
fn row_point(d: &Design, i: usize, model: &capstan_physics::Model, f0: &[f64]) -> RowPoint {
    let sensors = &model.sensors;
    let t1m = d.t1[i];
    let x_row = sensors.true_t1_n(t1m);
    // A reading taken for a slack cord does not move with the offset. At an offset of
    // exactly 0 (a start value) the right-hand slope, as the forward difference takes it.
    let slack = sensors.t1_offset_n >= 0.0 && t1m > 0.0 && t1m - sensors.t1_offset_n < SLACK_T1_N;
    let x = shape_point(model, x_row, Some(d.t1_shape[i]));
    let shaped = x != x_row;
    let scale = if shaped { x_row / x } else { 1.0 };
    let y = (f0[i] - sensors.t2_offset_n) / sensors.t2_gain / scale;
    RowPoint {
        x,
        y,
        scale,
        shaped,
        load: y - x,
        dx_do: if slack { 0.0 } else { -1.0 },
    }
}

/// dy/dp at one row for every parameter p (0: mu, then θ), into `dy`: the law's partials
/// through the step equation's implicit derivative, the memory carried in as `dh` (decay
/// `a_c`, gain `b_c` while loaded).
fn row_sens(
    row: &RowPoint,
    (g, m): (capstan_physics::LawPartials, capstan_physics::MuPartials),
    (a_c, b_c, dh): (f64, f64, &[f64]),
    roles: &[Role],
    dy: &mut [f64],
) {
    let k_h = g.d_k * m.d_memory;
    let denom = 1.0 - k_h * b_c;
    for (p, dy_p) in dy.iter_mut().enumerate() {
        let role = (p > 0).then(|| roles[p - 1]);
        let dx = row.dx(roles, p);
        let direct = match role {
            None => g.d_k * m.d_mu,
            Some(Role::Exponent) => g.d_n,
            Some(Role::SqrtB) => g.d_sqrt_b,
            Some(Role::Drift) => g.d_k * m.d_drift,
            Some(Role::Heating) => g.d_k * m.d_heat / HEAT_TAU_S,
            Some(Role::T1Offset | Role::T2Offset) => 0.0,
        };
        *dy_p = (direct + k_h * (a_c * dh[p] - b_c * dx) + g.d_t1 * dx) / denom;
    }
}

#[cfg(test)]
mod tests {
    use super::super::{jacobian_by_differences, predict, Weights};
    use super::*;
    use crate::fit::obs::StepTiming;
    use capstan_data::{read_pairs, write_pairs_to, Pair};
    use capstan_physics::EffectKind;

    /// Three wraps × two runs of 10 steps with times (the memory carries), T1 from slack to
    /// 20 N; T2 does not matter for sensitivities.
    fn design() -> Design {
        let mut pairs = Vec::new();
        for w in [270.0, 450.0, 720.0] {
            for run in 1..=2 {
                for step in 1..=10 {
                    // Run 2 pulls 4 % less T1 from step 5 on (a higher mu): above the
                    // shape point's floor (steps 8-10) its law is read at run 1's T1 and run
                    // 1's at its.
                    let t1 = [-0.1, 0.0, 0.5, 1.0, 2.0, 4.0, 7.0, 11.0, 15.0, 20.0][step - 1]
                        * if run == 2 && step > 4 { 0.96 } else { 1.0 };
                    pairs.push(Pair {
                        capstan_diameter_mm: Some(12.7),
                        wrap_deg: w,
                        drive_v: Some(10.0),
                        run: Some(run as f64),
                        step: Some(step as f64),
                        time_s: Some(6.0 + 4.0 * step as f64),
                        t1_n: t1,
                        t2_n: t1 * 3.0,
                        extra: Vec::new(),
                        labels: Vec::new(),
                    });
                }
            }
        }
        let mut csv = Vec::new();
        write_pairs_to(&mut csv, &pairs).unwrap();
        let mut d = Design::new(&read_pairs(csv.as_slice(), "sens").unwrap(), false);
        assert!(d.t1_shape.iter().filter(|t| t.is_finite()).count() >= 18);
        // Steps of 0.2 s (the rig's are ≥ 1 s): the memory (τ = 0.25 s) then carries from
        // step to step, and its chain rule shows.
        for rows in &d.units {
            for (s, &i) in rows.iter().enumerate() {
                let change = 0.2 * s as f64;
                d.timing[i] = StepTiming {
                    change_s: change,
                    centre_s: change + 0.12,
                    end_s: change + 0.2,
                };
            }
        }
        d
    }

    /// The analytic sensitivities equal forward differences of the predictions, for every
    /// effect it knows, together, at neutral values and away from them, shared or by strata.
    #[test]
    fn sensitivities_match_forward_differences() {
        let d = design();
        assert!(d.timed, "the memory must carry for this check");
        let kinds = [
            EffectKind::ContactHeating,
            EffectKind::PressureFriction,
            EffectKind::BendingStiffness,
            EffectKind::T1Offset,
            EffectKind::T2Offset,
            EffectKind::ThermalDrift,
        ];
        let maps: Vec<ThetaMap> = kinds.iter().map(|&k| ThetaMap::for_kind(k, &d)).collect();
        let away = [0.02, 0.85, 0.005, 0.2, -0.3, 0.05];
        let neutral: Vec<f64> = maps
            .iter()
            .map(|m| m.theta(m.kind.neutral_value()))
            .collect();
        let two = Strata {
            k: 6,
            of_unit: (0..d.units.len()).map(|u| u % 2).collect(),
        };
        let cases = [
            (maps.clone(), away.to_vec(), Strata::shared(&d, 6)),
            (maps.clone(), neutral.clone(), Strata::shared(&d, 6)),
            (
                [maps.clone(), maps.clone()].concat(),
                [away.to_vec(), neutral].concat(),
                two,
            ),
        ];
        let w = Weights::equal(d.n());
        for (maps, theta, strata) in cases {
            let k = maps.len();
            let mu: Vec<f64> = (0..d.units.len())
                .map(|u| 0.11 + 0.005 * u as f64)
                .collect();
            let (mut f, mut slopes) = (vec![0.0; d.n()], vec![f64::NAN; d.n()]);
            predict(
                &d,
                (&maps, &strata),
                (&mu, &theta),
                &w,
                None,
                (&mut f, &mut slopes),
            );
            let roles = roles(&maps).expect("all known");
            let (mut an, mut num) = (Sens::new(d.n(), k), Sens::new(d.n(), k));
            jacobian(&d, (&maps, &strata), (&mu, &theta), &f, &roles, &mut an);
            jacobian_by_differences(&d, (&maps, &strata), (&mu, &theta), (&f, &slopes), &mut num);
            let close = |a: f64, b: f64| (a - b).abs() <= 1e-4 * a.abs().max(b.abs()).max(1e-2);
            for i in 0..d.n() {
                assert!(
                    close(an.a[i], num.a[i]),
                    "mu, row {i}: {} vs {}",
                    an.a[i],
                    num.a[i]
                );
                for j in 0..k {
                    let (x, y) = (an.b[i * k + j], num.b[i * k + j]);
                    // At n = 1 the difference steps into n < 1, where the law is good to
                    // ~1e-10 only (ln(base)/(1 − n)): the difference is good to ~1e-4 there.
                    let loose = maps[j].kind == EffectKind::PressureFriction && theta[j] == 1.0;
                    let ok = close(x, y) || (loose && (x - y).abs() <= 2e-3 * x.abs());
                    assert!(ok, "{:?} row {i}: {x} vs {y}", maps[j].kind);
                }
            }
        }
    }
}
