//! A campaign's output: `pairs.csv` is written by the caller through `capstan::data`; here the
//! raw logs, `faults.csv`, the JSON object and the printed summary.

use anyhow::Context;
use host_sim::campaign::{CampaignResult, RunResult};
use serde_json::json;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

pub(super) fn create(path: &Path) -> anyhow::Result<BufWriter<File>> {
    let f = File::create(path).with_context(|| format!("cannot write {}", path.display()))?;
    Ok(BufWriter::new(f))
}

fn raw_name(r: &RunResult) -> String {
    format!("{}_run{}.csv", r.cord.label(), r.run)
}

pub(super) fn write_raw_logs(dir: &Path, runs: &[RunResult]) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    // Raw logs of an earlier simulation into the same directory would mix with these.
    if let Ok(entries) = std::fs::read_dir(dir) {
        for e in entries.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            let ours = name.starts_with('d') && name.contains("_run") && name.ends_with(".csv");
            if ours && !runs.iter().any(|r| raw_name(r) == name) {
                let _ = std::fs::remove_file(e.path());
            }
        }
    }
    for r in runs {
        let path = dir.join(raw_name(r));
        let mut w = create(&path)?;
        writeln!(w, "t_s,t1_counts,t2_counts,t1_n,t2_n")?;
        for s in &r.log.raw {
            writeln!(
                w,
                "{},{},{},{},{}",
                s.t_us as f64 / 1e6,
                s.counts[0],
                s.counts[1],
                s.force_n[0],
                s.force_n[1]
            )?;
        }
        w.flush()
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    Ok(())
}

fn opt<T: ToString>(v: Option<T>) -> String {
    v.map_or(String::new(), |x| x.to_string())
}

pub(super) fn write_faults(path: &Path, r: &CampaignResult) -> anyhow::Result<()> {
    let mut w = create(path)?;
    writeln!(
        w,
        "run,capstan_diameter_mm,wrap_deg,drive_v,repeat,injected,fault,at_s,detected_s,safe_after_ms,pairs_kept"
    )?;
    for f in &r.faults {
        writeln!(
            w,
            "{},{},{},{},{},{},{},{},{},{},{}",
            f.run,
            f.cord.diameter_mm,
            f.cord.wrap_deg,
            f.cord.drive_v,
            f.repeat,
            opt(f.injected.map(|k| k.name())),
            opt(f.fault.map(|k| k.name())),
            f.at_s,
            opt(f.detected_s),
            opt(f.safe_after_ms),
            f.pairs_kept
        )?;
    }
    w.flush()?;
    Ok(())
}

pub(super) fn campaign_json(r: &CampaignResult) -> serde_json::Value {
    let faults: Vec<_> = r
        .faults
        .iter()
        .map(|f| {
            json!({
                "run": f.run,
                "fault": f.fault.map(|k| k.name()),
                "at_s": f.at_s,
                "safe_after_ms": f.safe_after_ms,
                "pairs_kept": f.pairs_kept,
            })
        })
        .collect();
    json!({
        "runs": r.runs.len(),
        "pairs": r.rows.len(),
        "simulated_s": r.simulated_s,
        "wall_s": r.wall_s,
        "realtime_factor": r.realtime_factor(),
        "faults": faults,
    })
}

pub(super) fn print_summary(out: &Path, r: &CampaignResult, raw: bool) {
    println!(
        "{} runs, {:.0} s of rig time simulated in {:.2} s on {} threads ({:.0}x real time)",
        r.runs.len(),
        r.simulated_s,
        r.wall_s,
        r.threads,
        r.realtime_factor()
    );
    println!(
        "{} pairs -> {}",
        r.rows.len(),
        out.join("pairs.csv").display()
    );
    if raw {
        println!("raw logs -> {}", out.join("raw").display());
    }
    for f in &r.faults {
        let injected = f.injected.map_or("-".into(), |k| k.name().to_string());
        let seen = f
            .fault
            .map_or("NOT DETECTED".into(), |k| k.name().to_string());
        let safe = f
            .safe_after_ms
            .map_or("never".into(), |ms| format!("{ms} ms"));
        println!(
            "run {} ({} run {}): injected {injected} at {} s, firmware: {seen}, safe after \
             {safe}, {} pairs kept",
            f.run,
            f.cord.label(),
            f.repeat,
            f.at_s,
            f.pairs_kept
        );
    }
    if !r.faults.is_empty() {
        println!("faults -> {}", out.join("faults.csv").display());
    }
}
