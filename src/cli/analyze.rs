//! `capstan analyze [DATA.csv] --out DIR`: fit the models, test the mechanisms, write the
//! report (`report.html`), `metrics.json` and `predictions.csv`.

use crate::data::{load_pairs, thesis_dataset};
use anyhow::Context;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `capstan analyze`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Pairs CSV (default: the bundled thesis data, 720 pairs).
    pub data: Option<PathBuf>,
    /// Output directory (created if needed).
    #[arg(long, default_value = "report")]
    pub out: PathBuf,
    /// Print the metrics (including timings) as JSON on stdout.
    #[arg(long)]
    pub json: bool,
    /// Threads for independent fits (default: up to 4).
    #[arg(long)]
    pub threads: Option<usize>,
}

/// Run `capstan analyze`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let ds = match &args.data {
        Some(p) => load_pairs(p)?,
        None => thesis_dataset(),
    };
    let mut opts = crate::analysis::Options::default();
    if let Some(t) = args.threads {
        opts.threads = t.max(1);
    }
    eprintln!("analysing {} ({} pairs) ...", ds.source, ds.pairs.len());
    let mut a = crate::analysis::run(&ds, opts)?;
    let t_report = Instant::now();
    let t_cl = Instant::now();
    let (curves, closed, note) = match crate::analysis::closed_loop::run(&a, opts.threads) {
        Ok(cl) => (Some(cl.curves), cl.summary, "The firmware, run in virtual time against the simulated plant (host_sim::campaign) with the extended model as its friction law (each cord's fitted mu factor, contact heating, T1-path loss), on the thesis campaign: one run per cord, sensor noise off.".to_string()),
        Err(e) => (None, serde_json::json!({"error": format!("{e:#}")}), format!("The closed-loop simulation failed: {e:#}")),
    };
    a.elapsed.closed_loop_s = t_cl.elapsed().as_secs_f64();
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let html = crate::report::report_html(&a, curves.as_deref(), &note)?;
    let csv = crate::report::predictions_csv(&ds, &a);
    a.elapsed.report_s = t_report.elapsed().as_secs_f64();
    a.elapsed.total_s = t0.elapsed().as_secs_f64();
    let metrics = crate::report::metrics_json(&a, &closed);
    let write = |name: &str, s: &str| -> anyhow::Result<()> {
        let p = args.out.join(name);
        std::fs::write(&p, s).with_context(|| format!("writing {}", p.display()))
    };
    write("report.html", &html)?;
    write("predictions.csv", &csv)?;
    write("metrics.json", &serde_json::to_string_pretty(&metrics)?)?;
    eprintln!(
        "wrote {}/report.html, metrics.json, predictions.csv in {:.2} s",
        args.out.display(),
        t0.elapsed().as_secs_f64()
    );
    if args.json {
        println!("{}", serde_json::to_string_pretty(&metrics)?);
    }
    Ok(())
}
