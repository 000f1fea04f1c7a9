//! `capstan simulate`'s arguments against the physical ranges (`data::ranges`), before any
//! work: what a campaign writes must read back, and no time, delay or count may wrap around
//! when the simulator turns it into an integer (a fault at 1e14 s once broke every run at its
//! trigger; a delay of 4294967295 ms once acted as none). And the files it will write, so that
//! the output directory is checked before the campaign runs.

use super::Args;
use capstan_data::ranges;
use capstan_sim::campaign::{CampaignConfig, CordKey, FaultSpec};

/// Check every numeric argument against its range.
pub(super) fn check_ranges(args: &Args) -> anyhow::Result<()> {
    for (flag, list, r) in [
        ("--diameters", &args.diameters, &ranges::DIAMETER_MM),
        ("--wraps", &args.wraps, &ranges::WRAP_DEG),
    ] {
        for &v in list.iter().flatten() {
            r.option(flag, v)?;
        }
        // The two-control rig's wraps are its channels' (two may be alike).
        if !args.two_control {
            no_repeats(flag, list.iter().flatten())?;
        }
    }
    // The rig's drive range (as `predict`, `condition` and `log` judge it), not the data's
    // ±1000 V: a simulated campaign runs the firmware, which cannot command more.
    let limits = crate::cli::predict::limits::RigLimits::firmware_defaults();
    for &v in &args.drive_v {
        limits.check_drive_for(v, "the simulated firmware could not command it")?;
    }
    no_repeats("--drive-v", &args.drive_v)?;
    if let Some(n) = args.runs {
        ranges::RUNS_PER_CORD.option("--runs", n.into())?;
    }
    if let Some(n) = args.threads {
        ranges::THREADS.option("--threads", n as f64)?;
    }
    for (flag, v) in [
        ("--dwell-ms", args.dwell_ms),
        ("--window-after-ms", args.window_after_ms),
        ("--window-before-ms", args.window_before_ms),
    ] {
        if let Some(v) = v {
            ranges::PROTOCOL_MS.option(flag, v.into())?;
        }
    }
    for &d in args.delays_ms.iter().flatten() {
        ranges::DELAY_MS.option("--delays-ms", d.into())?;
    }
    Ok(())
}

/// A value given twice in a list would make two cords of one key, whose runs every reader
/// refuses as the same run again ("cord D12.7/270deg run 1 step 1 again").
fn no_repeats<'a>(flag: &str, list: impl IntoIterator<Item = &'a f64>) -> anyhow::Result<()> {
    let mut seen: Vec<f64> = Vec::new();
    for &v in list {
        if seen.contains(&v) {
            anyhow::bail!("{flag} {v} is given twice: each value makes its own cords");
        }
        seen.push(v);
    }
    Ok(())
}

/// A `--fault` argument, its time within [`ranges::FAULT_AT_S`].
pub(super) fn fault(arg: &str) -> anyhow::Result<FaultSpec> {
    let f: FaultSpec = arg.parse().map_err(|e| anyhow::anyhow!("--fault {e}"))?;
    ranges::FAULT_AT_S
        .check(f.at_s)
        .map_err(|why| anyhow::anyhow!("--fault {arg}: the time {}", why))?;
    Ok(f)
}

/// Whether a campaign of `cfg` writes `rel` (`raw/<cord>_run<k>.csv`), for the output
/// directory's check of the user's files before any work.
pub(super) fn writes_raw(cfg: &CampaignConfig, rel: &str) -> bool {
    let Some(name) = rel
        .strip_prefix("raw/")
        .and_then(|r| r.strip_suffix(".csv"))
    else {
        return false;
    };
    let Some((label, run)) = name.rsplit_once("_run") else {
        return false;
    };
    let run_ok = run
        .parse::<u32>()
        .is_ok_and(|k| (1..=cfg.runs).contains(&k));
    run_ok
        && cfg.diameters_mm.iter().any(|&d| {
            cfg.wraps_deg.iter().any(|&w| {
                cfg.drive_vs.iter().any(|&v| {
                    CordKey {
                        diameter_mm: d,
                        wrap_deg: w,
                        drive_v: v,
                    }
                    .label()
                        == label
                })
            })
        })
}
