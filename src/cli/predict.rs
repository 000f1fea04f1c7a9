//! `capstan predict --from DIR/metrics.json --wrap-deg W --diameter-mm D --t1-n LIST`: T2 and
//! amplification from the fitted population-averaged model, with a 95 % confidence interval
//! (the mean curve) and a 95 % prediction interval (a new measurement on a new cord); with
//! `--t2-n LIST` instead, the T1 a wanted T2 needs ([`reverse`]). Each is checked against the
//! rig's limits ([`limits`]). The model is read and checked by
//! [`capstan_report::read_and_validate`]; see [`capstan_engine::analysis::prediction`].

pub mod limits;
mod reverse;

use anyhow::bail;
use capstan_data::ranges::shown;
use capstan_engine::analysis::prediction::{self, PredictionModel, Query, DEFAULT_DRIVE_V};
use limits::RigLimits;
use serde_json::{json, Value};
use std::path::PathBuf;

/// Arguments of `capstan predict`.
#[derive(clap::Args, Debug)]
#[command(group(clap::ArgGroup::new("given").required(true).args(["t1_n", "t2_n"])))]
pub struct Args {
    /// The `metrics.json` that `capstan analyze` wrote (or the directory holding it).
    #[arg(long, value_name = "METRICS_JSON|DIR")]
    pub from: PathBuf,
    /// Wrap angle, degrees (a negative number is taken as a value and refused by range).
    #[arg(long, allow_negative_numbers = true)]
    pub wrap_deg: f64,
    /// Capstan diameter, mm.
    #[arg(long, allow_negative_numbers = true)]
    pub diameter_mm: f64,
    /// T1 values, N: a comma list (2,5,10) or a range A:B:STEP (1:20:1, B included). Gives T2.
    #[arg(long, allow_hyphen_values = true)]
    pub t1_n: Option<String>,
    /// Wanted T2 values, N (a list or range as for --t1-n). Gives the T1 each needs, its 95 %
    /// interval and the T1 at which a new cord reaches it with probability --sure.
    #[arg(long, allow_hyphen_values = true)]
    pub t2_n: Option<String>,
    /// With --t2-n: the probability that a new cord reaches the wanted T2 (0 < P < 1).
    #[arg(long, default_value_t = 0.975, allow_negative_numbers = true)]
    pub sure: f64,
    /// Drive voltage, V (default: the thesis rig's 10 V; at most the rig's 13.2 V).
    #[arg(long, allow_negative_numbers = true)]
    pub drive_v: Option<f64>,
    /// Include the fitted sensor terms (offsets, gain): what the rig's sensors would read,
    /// T1 being a reading too. Without it, the physical tensions.
    #[arg(long)]
    pub as_measured: bool,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// The most T1 values one call predicts.
pub const MAX_POINTS: usize = 100_000;

/// Parse "2,5,10" or "A:B:STEP" (B included when the steps land on it).
pub fn parse_t1_list(s: &str) -> anyhow::Result<Vec<f64>> {
    parse_tensions("--t1-n", s)
}

/// Parse the tension list of `flag`: "2,5,10" or "A:B:STEP" (B included when the steps land
/// on it).
pub fn parse_tensions(flag: &str, s: &str) -> anyhow::Result<Vec<f64>> {
    let num = |x: &str| -> anyhow::Result<f64> {
        let v: f64 = x
            .trim()
            .parse()
            .map_err(|_| anyhow::anyhow!("{flag} {s}: {x:?} is not a number"))?;
        if !(v.is_finite() && v > 0.0 && v <= capstan_data::MAX_TENSION_N) {
            bail!(
                "{flag} {s}: {} N is not a tension above 0 and up to {} N",
                capstan_data::ranges::shown(v),
                capstan_data::MAX_TENSION_N
            );
        }
        Ok(v)
    };
    let parts: Vec<&str> = s.split(':').collect();
    let vals = match parts.as_slice() {
        [a, b, step] => {
            let (a, b) = (num(a)?, num(b)?);
            let step: f64 = step
                .trim()
                .parse()
                .map_err(|_| anyhow::anyhow!("{flag} {s}: the step {step:?} is not a number"))?;
            if !(step.is_finite() && step > 0.0) || b < a {
                bail!("{flag} {s}: A:B:STEP needs A ≤ B and a step above 0");
            }
            // Counted in f64 first: a tiny step would overflow an integer count. B counts as
            // landed on within a relative 1e-9 of the ratio (1:1.0001:1e-9 is 100,001 values,
            // B included, not 100,000 that stop short of it).
            let ratio = (b - a) / step;
            let count = (ratio * (1.0 + 1e-9) + 1e-9).floor() + 1.0;
            if count.is_nan() || count > MAX_POINTS as f64 {
                bail!(
                    "{flag} {s}: {} values (at most {MAX_POINTS})",
                    shown((ratio + 1.0).round())
                );
            }
            let n = count as usize;
            (0..n).map(|k| a + step * k as f64).collect()
        }
        [_] => s
            .split(',')
            .map(num)
            .collect::<anyhow::Result<Vec<f64>>>()?,
        _ => bail!("{flag} {s}: give a comma list (2,5,10) or A:B:STEP (1:20:1)"),
    };
    if vals.len() > MAX_POINTS {
        bail!("{flag}: {} values (at most {MAX_POINTS})", vals.len());
    }
    Ok(vals)
}

/// The query every T1 shares: the wrap, diameter and drive voltage, checked.
pub struct Setting {
    /// Drive voltage, V.
    pub drive_v: f64,
    /// The rig's limits.
    pub limits: RigLimits,
    /// Why the intervals cannot be given here (`None`: they can).
    pub unidentified: Option<String>,
}

impl Setting {
    /// The query at `t1_n`.
    pub fn query(&self, args: &Args, t1_n: f64) -> Query {
        Query {
            wrap_deg: args.wrap_deg,
            diameter_mm: args.diameter_mm,
            drive_v: self.drive_v,
            t1_n,
            as_measured: args.as_measured,
        }
    }
}

/// The wrap, diameter and drive voltage of `args` (checked by `run`) with the rig's limits and
/// whether the model's intervals are identified there.
fn setting(args: &Args, pm: &PredictionModel) -> anyhow::Result<Setting> {
    let drive_v = args.drive_v.unwrap_or(DEFAULT_DRIVE_V);
    let limits = RigLimits::firmware_defaults();
    let unidentified = pm.unidentified(&Query {
        wrap_deg: args.wrap_deg,
        diameter_mm: args.diameter_mm,
        drive_v,
        t1_n: 1.0,
        as_measured: args.as_measured,
    });
    Ok(Setting {
        drive_v,
        limits,
        unidentified,
    })
}

/// Run `capstan predict`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let drive_v = args.drive_v.unwrap_or(DEFAULT_DRIVE_V);
    for (flag, v, r) in [
        ("--wrap-deg", args.wrap_deg, capstan_data::ranges::WRAP_DEG),
        (
            "--diameter-mm",
            args.diameter_mm,
            capstan_data::ranges::DIAMETER_MM,
        ),
    ] {
        r.option(flag, v)?;
    }
    capstan_data::ranges::DRIVE_V.option("--drive-v", drive_v)?;
    if !(drive_v.is_finite() && drive_v > 0.0) {
        bail!(
            "--drive-v {drive_v}: must be above 0 V (the model is of a capstan driven forwards; \
             the thesis rig's drive is {DEFAULT_DRIVE_V} V)"
        );
    }
    RigLimits::firmware_defaults().check_drive(drive_v)?;
    let from = metrics_file(&args.from)?;
    if let Some(t2) = &args.t2_n {
        if !(args.sure > 0.0 && args.sure < 1.0) {
            bail!(
                "--sure {}: a probability above 0 and below 1 (0.975: a new cord reaches the \
                 wanted T2 at least 97.5 times in 100)",
                shown(args.sure)
            );
        }
        let wanted = parse_tensions("--t2-n", t2)?;
        let pm = capstan_report::read_and_validate(&from)?.prediction_model;
        let set = setting(&args, &pm)?;
        return reverse::run(&args, &pm, &set, &wanted);
    }
    let t1 = parse_t1_list(args.t1_n.as_deref().unwrap_or_default())?;
    let pm = capstan_report::read_and_validate(&from)?.prediction_model;
    let set = setting(&args, &pm)?;
    let queries: Vec<Query> = t1.iter().map(|t| set.query(&args, *t)).collect();
    // One warning per quantity, with the range of the values outside: never one per value.
    let mut warnings = extrapolation_warnings(&pm, &queries);
    let preds: Vec<_> = (queries.iter())
        .map(|q| prediction::predict(&pm, q))
        .collect();
    if let Some(why) = preds.iter().find_map(|p| unusable(p, args.as_measured)) {
        bail!(
            "{}: prediction_model: {why}: its values are not ones an analysis writes (edited?); \
             run capstan analyze again",
            args.from.display()
        );
    }
    let top = preds.iter().map(|p| p.t2_n.max(p.t1_n)).fold(0.0, f64::max);
    warnings.extend(limits::rig_warnings(&set.limits, (top, "T2")));
    if args.json {
        let extrapolating = !pm.extrapolation(&queries).is_empty();
        print_json(&args, &set, &pm, &preds, (&warnings, extrapolating))?;
    } else {
        print_table(&args, &set, &pm, &preds, &warnings);
    }
    Ok(())
}

/// `--from`: the file, or `DIR/metrics.json` for an analysis's directory.
fn metrics_file(from: &std::path::Path) -> anyhow::Result<PathBuf> {
    if !from.is_dir() {
        return Ok(from.to_path_buf());
    }
    let inside = from.join("metrics.json");
    if inside.is_file() {
        return Ok(inside);
    }
    bail!(
        "--from {}: a directory without metrics.json; give the metrics.json capstan analyze \
         wrote (analyze --out DIR writes DIR/metrics.json)",
        from.display()
    )
}

/// T2/T1 as the amplification, or `None` where it is none: as measured, a reading of T2 at
/// or below zero (the fitted T2 zero offset beyond the tension) over a T1 reading.
fn amplification(p: &prediction::Prediction) -> Option<f64> {
    (p.t1_n > 0.0 && p.t2_n > 0.0 && p.amplification.is_finite()).then_some(p.amplification)
}

/// Why a prediction cannot be printed, if it cannot: a T2 or an interval end that is not a
/// finite number, or a physical T2 below T1 (a capstan not driven backwards does not lose
/// tension; the law's parameters are then outside physics).
fn unusable(p: &prediction::Prediction, as_measured: bool) -> Option<String> {
    let at = format!("at T1 = {} N", capstan_data::ranges::shown(p.t1_n));
    let ends = [
        p.t2_n,
        p.t2_ci95.lo,
        p.t2_ci95.hi,
        p.t2_pi95.lo,
        p.t2_pi95.hi,
    ];
    if ends.iter().any(|v| !v.is_finite()) {
        return Some(format!(
            "it gives T2 or an interval without a finite value {at}"
        ));
    }
    (!as_measured && p.t2_n < p.t1_n * (1.0 - 1e-9)).then(|| {
        format!(
            "it gives a physical T2 of {} N below T1 {at}",
            capstan_data::ranges::shown(p.t2_n)
        )
    })
}

/// When the query's wrap lies outside the fitted wraps, the wrap-extrapolation error's SD, N,
/// at that distance (`Some(None)`: not measured), else `None`.
fn wrap_error(args: &Args, pm: &PredictionModel) -> Option<Option<f64>> {
    pm.extrapolates_in_wrap(args.wrap_deg)
        .then(|| pm.wrap_extrapolation_sd(args.wrap_deg))
}

/// The flags every prediction's JSON and the whole answer carry.
fn all_flags(per: &[Vec<&'static str>]) -> Vec<&'static str> {
    let mut all: Vec<&'static str> = per.iter().flatten().copied().collect();
    all.sort_unstable();
    all.dedup();
    all
}

/// The predictions as one JSON object (the contract, plus the query and the model's
/// note). Where the intervals are not identified they are `null`, and `not_identified` says
/// why.
fn print_json(
    args: &Args,
    set: &Setting,
    pm: &PredictionModel,
    preds: &[prediction::Prediction],
    (warnings, extrapolating): (&[String], bool),
) -> anyhow::Result<()> {
    let mut per = Vec::new();
    let mut rows = Vec::new();
    for p in preds {
        let mut f = limits::flags(
            &set.limits,
            pm.fitted_range.t1_n,
            p.t1_n,
            p.t2_n.max(p.t1_n),
        );
        let mut v = serde_json::to_value(p)?;
        // As measured, a T2 reading at or below zero over a T1 reading is no amplification: null.
        if amplification(p).is_none() {
            v["amplification"] = Value::Null;
        }
        if set.unidentified.is_some() {
            f.push(limits::NOT_IDENTIFIED);
            v["t2_ci95"] = Value::Null;
            v["t2_pi95"] = Value::Null;
        }
        v["flags"] = json!(f);
        per.push(f);
        rows.push(v);
    }
    let out = json!({
        "predictions": rows,
        "flags": all_flags(&per),
        "not_identified": set.unidentified,
        "beyond_rig": per.iter().flatten().any(|f| *f == limits::OVER_FORCE || *f == limits::SENSOR_RANGE),
        "extrapolating": extrapolating,
        "warnings": warnings,
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
        "wrap_extrapolation_error_sd_n": wrap_error(args, pm).flatten(),
        "wrap_extrapolation_measured": pm.wrap_extrapolation_error.rows > 0,
        "from": args.from.display().to_string(),
        "note": pm.note,
        "provenance": crate::provenance::of_input(Some(&metrics_file(&args.from)?))?,
    });
    crate::outln!("{}", serde_json::to_string_pretty(&out)?);
    Ok(())
}

/// What the intervals hold, in words, on stdout (a new cord's error; the wrap's extrapolation
/// error; or why they are not identified).
fn interval_words(args: &Args, set: &Setting, pm: &PredictionModel, what: &str) {
    if let Some(why) = &set.unidentified {
        crate::outln!("intervals {why}");
        return;
    }
    let e = &pm.new_cord_error;
    crate::outln!(
        "{what} holds a new cord's error, SD √({:.3}² + ({:.4}·T2)²) N, from the held-out residuals of {} cords (each predicted by the causes chosen and fitted without it; Student t, {} degree{} of freedom)",
        e.abs_n,
        e.rel,
        e.cords,
        e.dof,
        if e.dof == 1 { "" } else { "s" }
    );
    if let Some(Some(sd)) = wrap_error(args, pm) {
        crate::outln!(
            "and, the wrap lying outside the fitted wraps, what extrapolating in wrap cost on the fitted data, scaled to this distance: SD {sd:.3} N"
        );
    }
}

/// The warnings on stderr, the predictions as a table.
fn print_table(
    args: &Args,
    set: &Setting,
    pm: &PredictionModel,
    preds: &[prediction::Prediction],
    warnings: &[String],
) {
    for w in warnings {
        crate::errln!("warning: {w}");
    }
    if let Some(p) = preds.iter().find(|p| amplification(p).is_none()) {
        crate::errln!(
            "warning: as measured, T2 reads {:.3} N at T1 = {} N (the fitted T2 zero offset is \
             larger than the tension there): a ratio of such readings is no amplification, \
             shown as —",
            p.t2_n,
            capstan_data::ranges::shown(p.t1_n)
        );
    }
    crate::outln!(
        "{} T2 at {}° wrap, D = {} mm, {} V (95 % CI: mean curve; 95 % PI: a new measurement on a new cord)",
        if args.as_measured { "as measured:" } else { "physical:" },
        args.wrap_deg,
        args.diameter_mm,
        set.drive_v
    );
    interval_words(args, set, pm, "the PI");
    crate::outln!(
        "{:>9} {:>10} {:>8} {:>21} {:>21}",
        "T1 (N)",
        "T2 (N)",
        "T2/T1",
        "95 % CI (N)",
        "95 % PI (N)"
    );
    for p in preds {
        if set.unidentified.is_some() {
            crate::outln!(
                "{:>9.3} {:>10.3} {:>8.3} {:>21} {:>21}",
                p.t1_n,
                p.t2_n,
                p.amplification,
                "not identified",
                "not identified"
            );
            continue;
        }
        crate::outln!(
            "{:>9.3} {:>10.3} {:>8} {:>10.3} – {:<8.3} {:>10.3} – {:<8.3}",
            p.t1_n,
            p.t2_n,
            amplification(p).map_or("—".to_string(), |a| format!("{a:.3}")),
            p.t2_ci95.lo,
            p.t2_ci95.hi,
            p.t2_pi95.lo,
            p.t2_pi95.hi
        );
    }
}

/// The extrapolation warnings of `queries`, one per quantity, each saying it extrapolates.
pub fn extrapolation_warnings(pm: &PredictionModel, queries: &[Query]) -> Vec<String> {
    (pm.extrapolation(queries).into_iter())
        .map(|w| format!("extrapolating: {w}"))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::parse_t1_list;

    #[test]
    fn t1_lists_and_ranges() {
        assert_eq!(parse_t1_list("2,5,10").unwrap(), vec![2.0, 5.0, 10.0]);
        assert_eq!(
            parse_t1_list("1:3:0.5").unwrap(),
            vec![1.0, 1.5, 2.0, 2.5, 3.0]
        );
        assert_eq!(parse_t1_list("1:2.9:1").unwrap(), vec![1.0, 2.0]);
        for bad in [
            "",
            "a",
            "0",
            "-1",
            "3:1:1",
            "1:2:0",
            "1:2",
            "1:1e9:1e-9",
            "1:10:1e-19",
            "1:10:1e-300",
        ] {
            assert!(parse_t1_list(bad).is_err(), "{bad}");
        }
    }
}
