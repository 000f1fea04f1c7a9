//! `capstan predict --t2-n LIST`: the T1 each wanted T2 needs at the given wrap, diameter and
//! drive voltage, with its 95 % interval and the T1 at which a new cord reaches it with
//! probability `--sure` ([`capstan_engine::analysis::inverse`]).

use super::{limits, Args, Setting};
use capstan_engine::analysis::inverse::{self, Needed};
use capstan_engine::analysis::prediction::{self, PredictionModel, Query};
use serde_json::{json, Value};

/// The largest T1 a designer would set for `n`: the T1 for the chosen probability when there
/// is one, else the high end of the interval, else the mean curve's T1.
fn t1_top(n: &Needed) -> Option<f64> {
    n.t1_for_sure
        .or(n.t1_ci95.map(|i| i.hi))
        .or(n.t1_n)
        .map(|t| t.max(n.t1_n.unwrap_or(0.0)))
}

/// Answer `--t2-n`.
pub fn run(args: &Args, pm: &PredictionModel, set: &Setting, wanted: &[f64]) -> anyhow::Result<()> {
    let at = set.query(args, 1.0);
    let needs: Vec<Needed> = (wanted.iter())
        .map(|t2| inverse::t1_for(pm, &at, *t2, args.sure))
        .collect();
    // The T1 values solved, as queries: their extrapolation warnings, once per quantity.
    let solved: Vec<Query> = (needs.iter())
        .filter_map(|n| n.t1_n)
        .map(|t| set.query(args, t))
        .collect();
    let mut warnings = super::extrapolation_warnings(pm, &solved);
    // The largest tension each answer puts on the rig, once (a forward prediction each).
    let tops: Vec<f64> = (needs.iter())
        .map(|n| top_tension(args, pm, set, n))
        .collect();
    let top_t2 = tops.iter().copied().fold(0.0, f64::max);
    warnings.extend(limits::rig_warnings(
        &set.limits,
        (top_t2, "T2 (the wanted one, or a new cord's at the T1 set)"),
    ));
    let per: Vec<Vec<&'static str>> = (needs.iter().zip(&tops))
        .map(|(n, top)| flags(set, pm, n, *top))
        .collect();
    let unreached: Vec<f64> = (needs.iter())
        .filter(|n| n.t1_n.is_none())
        .map(|n| n.t2_n)
        .collect();
    if !unreached.is_empty() {
        warnings.push(format!(
            "no T1 from 1e-9 N to 1e4 N gives T2 = {} N at this setting",
            unreached
                .iter()
                .map(|v| capstan_data::ranges::shown(*v))
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    if args.json {
        let rows: Vec<Value> = (needs.iter().zip(&per))
            .map(|(n, f)| {
                let mut v = serde_json::to_value(n).unwrap_or(Value::Null);
                v["flags"] = json!(f);
                v
            })
            .collect();
        let out = json!({
            "predictions": rows,
            "flags": super::all_flags(&per),
            "not_identified": set.unidentified,
            "beyond_rig": per.iter().flatten().any(|f| *f == limits::OVER_FORCE || *f == limits::SENSOR_RANGE),
            "extrapolating": !pm.extrapolation(&solved).is_empty(),
            "warnings": warnings,
            "sure": args.sure,
            "physical": !args.as_measured,
            "wrap_deg": args.wrap_deg,
            "diameter_mm": args.diameter_mm,
            "drive_v": set.drive_v,
            "rig_limits": {
                "over_force_n": set.limits.over_force_n,
                "sensor_top_n": set.limits.sensor_top_n,
                "drive_max_v": set.limits.drive_max_v,
            },
            "new_cord_error": pm.new_cord_error,
            "from": args.from.display().to_string(),
            "note": format!("{} T1 for a wanted T2: the root in T1 of the mean curve (t1_n), of the confidence band's edges (t1_ci95: every T1 whose 95 % CI holds the wanted T2) and of the new cord's lower (1 − sure) quantile, the forward prediction interval's distribution (t1_for_sure: a new cord reaches the wanted T2 with probability sure).", pm.note),
        });
        crate::outln!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        print_table(args, pm, set, &needs, &warnings);
    }
    Ok(())
}

/// The largest tension an answer puts on the rig: the wanted T2, the T1 set, and what a new
/// cord may pull at that T1 (the forward 95 % prediction interval's top, or the mean curve's
/// T2 where the interval is not identified): a T1 chosen to be sure of the target also risks
/// more than it.
fn top_tension(args: &Args, pm: &PredictionModel, set: &Setting, n: &Needed) -> f64 {
    let Some(t1) = t1_top(n) else {
        return n.t2_n;
    };
    let fwd = prediction::predict(pm, &set.query(args, t1));
    let reach = if set.unidentified.is_none() && fwd.t2_pi95.hi.is_finite() {
        fwd.t2_pi95.hi
    } else {
        fwd.t2_n
    };
    [n.t2_n, t1, reach]
        .into_iter()
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max)
}

/// The flags of one answer: the rig's limits on the largest tension it puts on the rig
/// ([`top_tension`]), the T1 set (outside the fitted T1), the intervals not identified.
fn flags(set: &Setting, pm: &PredictionModel, n: &Needed, top: f64) -> Vec<&'static str> {
    let t1 = t1_top(n).unwrap_or(f64::NAN);
    let mut f = limits::flags(&set.limits, pm.fitted_range.t1_n, t1, top);
    if n.t1_n.is_none() {
        f.retain(|x| *x != limits::T1_OUTSIDE);
    }
    if set.unidentified.is_some() {
        f.push(limits::NOT_IDENTIFIED);
    }
    f
}

/// The warnings on stderr, the answers as a table.
fn print_table(
    args: &Args,
    pm: &PredictionModel,
    set: &Setting,
    needs: &[Needed],
    warnings: &[String],
) {
    for w in warnings {
        crate::errln!("warning: {w}");
    }
    let pct = 100.0 * args.sure;
    crate::outln!(
        "{} T1 needed for a wanted T2 at {}° wrap, D = {} mm, {} V (95 % CI: every T1 whose mean-curve 95 % CI holds the wanted T2; {pct} % sure: the T1 at which a new cord reaches it with probability {})",
        if args.as_measured { "as measured:" } else { "physical:" },
        args.wrap_deg,
        args.diameter_mm,
        set.drive_v,
        args.sure
    );
    super::interval_words(args, set, pm, &format!("the T1 for {pct} % sure"));
    let sure_head = format!("T1 {pct} % sure (N)");
    crate::outln!(
        "{:>9} {:>10} {:>21} {:>20}",
        "T2 (N)",
        "T1 (N)",
        "95 % CI of T1 (N)",
        sure_head
    );
    let num = |v: Option<f64>| v.map_or("none".to_string(), |v| format!("{v:.3}"));
    for n in needs {
        let (ci, sure) = match (&set.unidentified, n.t1_n) {
            (_, None) => ("unreachable".to_string(), "unreachable".to_string()),
            (Some(_), _) => ("not identified".to_string(), "not identified".to_string()),
            (None, _) => (
                n.t1_ci95.map_or("none".to_string(), |i| {
                    format!("{:>9.3} – {:<9.3}", i.lo, i.hi)
                }),
                num(n.t1_for_sure),
            ),
        };
        crate::outln!(
            "{:>9.3} {:>10} {:>21} {:>20}",
            n.t2_n,
            num(n.t1_n),
            ci,
            sure
        );
    }
}
