//! A campaign's output, written as it runs: each finished run's rows go to `pairs.csv` and
//! `faults.csv` and its raw log to `raw/`, in campaign order, flushed run by run into the
//! output set's staging directory; `summary.json` says how many runs were planned and made and
//! whether the campaign was interrupted; the set replaces the previous one when it is closed
//! (`outdir`). Memory holds one run at a time, whatever `--runs` is.

use anyhow::Context;
use capstan_data::PairsWriter;
use capstan_outdir::{OutputDir, Staged};
use capstan_sim::campaign::{pair_rows, CampaignStats, FaultSummary, RunResult};
use serde_json::{json, Value};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

const FAULTS_HEADER: &str = "run,capstan_diameter_mm,wrap_deg,drive_v,repeat,injected,fault,at_s,detected_s,safe_after_ms,pairs_kept";

/// The campaign's files, being written.
pub(super) struct CampaignWriter {
    set: Staged,
    pairs: PairsWriter<BufWriter<File>>,
    faults_csv: BufWriter<File>,
    raw: bool,
    /// Pairs written.
    pub rows: usize,
    /// The first [`FAULTS_KEPT`] fault summaries (every one is in `faults.csv`).
    pub faults: Vec<FaultSummary>,
    /// Fault summaries written to `faults.csv`.
    pub faults_total: usize,
}

/// Fault summaries kept in memory for `summary.json` and the printed summary: a campaign with
/// a fault in each of a million runs stays in bounded memory (`faults.csv` has them all).
pub const FAULTS_KEPT: usize = 1_000;

impl CampaignWriter {
    /// Start the set in `out`.
    pub fn new(out: OutputDir, raw: bool) -> anyhow::Result<Self> {
        let mut set = out.stage()?;
        let pairs = PairsWriter::new(set.create("pairs.csv")?)?;
        let mut faults_csv = set.create("faults.csv")?;
        writeln!(faults_csv, "{FAULTS_HEADER}")?;
        Ok(CampaignWriter {
            set,
            pairs,
            faults_csv,
            raw,
            rows: 0,
            faults: Vec::new(),
            faults_total: 0,
        })
    }

    /// Write one finished run (in campaign order), flushed. From the first run on, the set is
    /// work worth keeping: a late failure keeps it as `incomplete-<id>` and says where.
    pub fn add(&mut self, r: &RunResult) -> anyhow::Result<()> {
        self.set.keep_on_failure(crate::outputs::say_kept);
        for row in pair_rows(r) {
            self.pairs
                .write(&capstan_validation::pairs::to_pairs(&[row])[0])?;
            self.rows += 1;
        }
        if self.raw {
            self.set.write(&raw_name(r), raw_csv(r).as_bytes())?;
        }
        for f in capstan_sim::campaign::summarise_faults(r) {
            write_fault(&mut self.faults_csv, &f)?;
            self.faults_total += 1;
            if self.faults.len() < FAULTS_KEPT {
                self.faults.push(f);
            }
        }
        self.pairs.flush()?;
        self.faults_csv.flush()?;
        warn_about(r);
        Ok(())
    }

    /// Close the set: `summary.json`, then replace the previous results (the writers closed
    /// first: a directory with open files cannot be renamed everywhere) or, with `keep`, put
    /// it beside them as `incomplete-<id>` (returned).
    pub fn finish(mut self, summary: &Value, keep: bool) -> anyhow::Result<Option<PathBuf>> {
        let at = |name: &str| format!("cannot write {}", self.set.target().join(name).display());
        self.pairs.flush().with_context(|| at("pairs.csv"))?;
        self.faults_csv.flush().with_context(|| at("faults.csv"))?;
        let mut set = self.set;
        drop((self.pairs, self.faults_csv));
        let text = serde_json::to_string_pretty(summary)? + "\n";
        set.write("summary.json", text.as_bytes())?;
        let dir = set.target().display().to_string();
        if keep {
            return Ok(Some(set.keep()?));
        }
        set.commit()
            .with_context(|| format!("writing the campaign into {dir}"))?;
        Ok(None)
    }
}

fn raw_name(r: &RunResult) -> String {
    format!("raw/{}_run{}.csv", r.cord.label(), r.run)
}

fn raw_csv(r: &RunResult) -> String {
    use std::fmt::Write as _;
    let mut s = String::from("t_s,t1_counts,t2_counts,t1_n,t2_n\n");
    for x in &r.log.raw {
        let _ = writeln!(
            s,
            "{},{},{},{},{}",
            x.t_us as f64 / 1e6,
            x.counts[0],
            x.counts[1],
            x.force_n[0],
            x.force_n[1]
        );
    }
    s
}

fn opt<T: ToString>(v: Option<T>) -> String {
    v.map_or(String::new(), |x| x.to_string())
}

fn write_fault(w: &mut impl Write, f: &FaultSummary) -> std::io::Result<()> {
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
    )
}

/// A run that did not end, or an injection after its run had ended (it never happened: say
/// so rather than list it).
fn warn_about(r: &RunResult) {
    if let Err(e) = r.end {
        crate::errln!(
            "warning: run {} ({} run {}) did not end: {e:?}",
            r.index,
            r.cord.label(),
            r.run
        );
    }
    for inj in r.injections.iter().filter(|i| i.at_us.is_none()) {
        crate::errln!(
            "warning: run {}: {}@{} s never took effect (the run ended {:.1} s after its trigger)",
            r.index,
            inj.injection.kind.name(),
            inj.injection.after_trigger_us as f64 / 1e6,
            r.log.end.map_or(f64::NAN, |e| e.t_us as f64 / 1e6)
        );
    }
}

/// `summary.json`, and what `--json` prints.
pub(super) fn campaign_json(
    s: &CampaignStats,
    rows: usize,
    faults: &[FaultSummary],
    faults_total: usize,
) -> Value {
    let faults: Vec<_> = faults
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
        "runs": s.done,
        "planned_runs": s.planned,
        "interrupted": s.interrupted,
        "pairs": rows,
        "simulated_s": s.simulated_s,
        "wall_s": s.wall_s,
        "realtime_factor": s.realtime_factor(),
        "threads": s.threads,
        "faults": faults,
        "faults_total": faults_total,
        "faults_note": format!("the first {} faults; faults.csv lists every one", FAULTS_KEPT),
    })
}

pub(super) fn print_summary(
    out: &Path,
    s: &CampaignStats,
    rows: usize,
    faults: &[FaultSummary],
    faults_total: usize,
    raw: bool,
) {
    crate::outln!(
        "{} runs, {:.0} s of rig time simulated in {:.2} s on {} threads ({:.0}x real time)",
        s.done,
        s.simulated_s,
        s.wall_s,
        s.threads,
        s.realtime_factor()
    );
    crate::outln!("{} pairs -> {}", rows, out.join("pairs.csv").display());
    if raw {
        crate::outln!("raw logs -> {}", out.join("raw").display());
    }
    for f in faults {
        let seen = f
            .fault
            .map_or("NOT DETECTED".into(), |k| k.name().to_string());
        let safe = f
            .safe_after_ms
            .map_or("never".into(), |ms| format!("{ms} ms"));
        let what = match f.injected {
            Some(k) => format!(
                "injected {} at {:.3} s, firmware: {seen}, safe after {safe}",
                k.name(),
                f.at_s
            ),
            // The firmware stopped the run on its own reading (planted physics it took for a
            // fault): nothing was injected, so there is no time to safety to measure.
            None => format!("the firmware stopped it at {:.3} s: {seen}", f.at_s),
        };
        crate::outln!(
            "run {} ({} run {}): {what}, {} pairs kept",
            f.run,
            f.cord.label(),
            f.repeat,
            f.pairs_kept
        );
    }
    if faults_total > faults.len() {
        crate::outln!("... and {} more faults", faults_total - faults.len());
    }
    if faults_total > 0 {
        crate::outln!("faults -> {}", out.join("faults.csv").display());
    }
}
