//! `capstan simulate --two-control --mode force`: N force-controlled channels on one drive.
//! Each channel's tracking (`tracking.csv`), the cross-talk when one channel's target steps
//! (`crosstalk.csv`: the holding channels' true T2 before, after and at its largest excursion,
//! the capstan speed and the drive current), `pairs_ch<k>.csv` with `t2_target_n`.

use capstan_outdir::Staged;
use capstan_sim::force::trace_of;
use capstan_sim::two_control::{TwoControlConfig, TwoControlResult, TRACKING_WINDOW};
use capstan_tracking::{steps, StepResponse};
use serde_json::json;
use std::io::Write;

/// Each channel's steps.
fn tracking(r: &TwoControlResult) -> Vec<Vec<StepResponse>> {
    r.channels
        .iter()
        .map(|ch| steps(&trace_of(&ch.log), TRACKING_WINDOW))
        .collect()
}

fn worst(st: &[StepResponse]) -> (f64, f64) {
    st.iter().fold((0.0f64, 0.0f64), |(a, b), s| {
        (a.max(s.ss_error_pct.abs()), b.max(s.overshoot_pct))
    })
}

/// The largest excursion of a holding channel's T2 and its largest change after settling, as
/// fractions of its T2 before, and the largest capstan speed change.
pub fn worst_crosstalk(r: &TwoControlResult) -> (f64, f64, f64) {
    let fin = |x: f64| if x.is_finite() { x.abs() } else { 0.0 };
    r.force_crosstalk
        .iter()
        .fold((0.0, 0.0, 0.0), |(a, b, c), x| {
            let after = x.observer_t2_after_n / x.observer_t2_before_n - 1.0;
            (
                f64::max(a, fin(x.peak_dev_rel())),
                f64::max(b, fin(after)),
                f64::max(c, fin(x.d_rpm_rel())),
            )
        })
}

pub(super) fn add_json(v: &mut serde_json::Value, r: &TwoControlResult) {
    let (peak, after, rpm) = worst_crosstalk(r);
    v["mode"] = json!("force");
    v["crosstalk_events"] = json!(r.force_crosstalk.len());
    v["worst_t2_crosstalk_peak_rel"] = json!(peak);
    v["worst_t2_crosstalk_after_rel"] = json!(after);
    v["worst_speed_crosstalk_rel"] = json!(rpm);
    v["tracking"] = tracking(r)
        .iter()
        .enumerate()
        .map(|(k, st)| {
            let (ss, os) = worst(st);
            json!({"channel": k + 1, "worst_ss_error_pct": ss, "worst_overshoot_pct": os, "steps": st})
        })
        .collect();
}

pub(super) fn say(r: &TwoControlResult) {
    for (k, st) in tracking(r).iter().enumerate() {
        let (ss, os) = worst(st);
        let targets: Vec<String> = st.iter().map(|s| format!("{}", s.target_n)).collect();
        crate::outln!(
            "channel {}: steps to {} N: worst steady-state error {ss:.2} % of the target, worst \
             overshoot {os:.1} %",
            k + 1,
            targets.join(", ")
        );
    }
    let (peak, after, rpm) = worst_crosstalk(r);
    crate::outln!(
        "cross-talk over {} target steps: a holding channel's T2 moved at most {:.2} % and \
         ended within {:.2} % of where it was; capstan speed changed at most {:.1} %",
        r.force_crosstalk.len(),
        peak * 100.0,
        after * 100.0,
        rpm * 100.0
    );
}

pub(super) fn write(
    set: &mut Staged,
    cfg: &TwoControlConfig,
    r: &TwoControlResult,
) -> anyhow::Result<()> {
    let mut w = set.create("crosstalk.csv")?;
    writeln!(
        w,
        "t_s,stepping_channel,from_n,to_n,observer_channel,observer_target_n,\
         observer_t2_before_n,observer_t2_after_n,observer_peak_dev_n,rpm_before,rpm_after,\
         current_before_a,current_after_a"
    )?;
    for c in &r.force_crosstalk {
        writeln!(
            w,
            "{},{},{},{},{},{},{},{},{},{},{},{},{}",
            c.t_s,
            c.stepping + 1,
            c.from_n,
            c.to_n,
            c.observer + 1,
            c.observer_target_n,
            c.observer_t2_before_n,
            c.observer_t2_after_n,
            c.observer_peak_dev_n,
            c.rpm_before,
            c.rpm_after,
            c.current_before_a,
            c.current_after_a
        )?;
    }
    w.flush()?;
    let mut w = set.create("tracking.csv")?;
    writeln!(
        w,
        "channel,t_s,from_n,target_n,steady_n,ss_error_pct,overshoot_pct,rise_s,settling_s"
    )?;
    let cell = |v: Option<f64>| v.map_or(String::new(), |x| x.to_string());
    for (k, st) in tracking(r).iter().enumerate() {
        for s in st {
            writeln!(
                w,
                "{},{},{},{},{},{},{},{},{}",
                k + 1,
                s.t_s,
                s.from_target_n,
                s.target_n,
                s.steady_n,
                s.ss_error_pct,
                s.overshoot_pct,
                cell(s.rise_s),
                cell(s.settling_s)
            )?;
        }
    }
    w.flush()?;
    for (k, ch) in r.channels.iter().enumerate() {
        let mut w = set.create(&format!("pairs_ch{}.csv", k + 1))?;
        writeln!(
            w,
            "capstan_diameter_mm,wrap_deg,drive_v,run,step,time_s,t1_n,t2_n,t2_target_n"
        )?;
        for p in &ch.log.pairs {
            writeln!(
                w,
                "{},{},{},1,{},{},{},{},{}",
                cfg.diameter_mm,
                cfg.channels[k].wrap_deg,
                cfg.drive_v,
                p.step,
                p.t_mid_ms as f64 / 1000.0,
                p.t1.mean_n,
                p.t2.mean_n,
                p.t2_target_n
            )?;
        }
        w.flush()?;
    }
    Ok(())
}
