//! `capstan analyze` on a force-control session (pairs with a `t2_target_n` above 0): the
//! tracking report (`capstan_report::tracking`) from the session's raw time series, which lie
//! beside its `pairs.csv`: `raw.csv` (`capstan log`: runs in a `run` column) or
//! `raw/*.csv` (`capstan simulate --mode force`: one file a run). Every file read is named in
//! the errors, with its line and column.

use anyhow::{bail, Context};
use capstan_report::tracking::{tracking_html, tracking_metrics, TrackedRun};
use capstan_tracking::{SteadyWindow, Trace};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// True when the pairs carry a force-control target (a `t2_target_n` column with a value above
/// 0).
pub fn is_force_session(ds: &capstan_data::Dataset) -> bool {
    let Some(k) = ds.extra_columns.iter().position(|c| c == "t2_target_n") else {
        return false;
    };
    ds.pairs
        .iter()
        .any(|p| p.extra.get(k).is_some_and(|&v| v > 0.0))
}

/// The most raw samples read from one session (a day at 100 Hz): beyond it, refused.
const MAX_SAMPLES: usize = 10_000_000;

/// The columns a raw file must have, by name.
struct Columns {
    run: Option<usize>,
    time: usize,
    t2: usize,
    target: usize,
}

fn columns(path: &Path, header: &str) -> anyhow::Result<Columns> {
    let names: Vec<&str> = header
        .trim_start_matches('\u{feff}')
        .split(',')
        .map(str::trim)
        .collect();
    let find = |n: &str| names.iter().position(|x| *x == n);
    let need = |alts: &[&str]| {
        alts.iter().find_map(|n| find(n)).ok_or_else(|| {
            anyhow::anyhow!(
                "{}:1: no column {} (the header has {})",
                path.display(),
                alts.join(" or "),
                names.join(", ")
            )
        })
    };
    Ok(Columns {
        run: find("run"),
        time: need(&["time_s", "t_s"])?,
        t2: need(&["t2_n"])?,
        target: need(&["t2_target_n"])?,
    })
}

/// The runs of one raw file: (label, trace), in file order.
fn read_raw(path: &Path, label: &str, total: &mut usize) -> anyhow::Result<Vec<(String, Trace)>> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let mut lines = text.lines();
    let header = lines
        .next()
        .ok_or_else(|| anyhow::anyhow!("{}: empty file", path.display()))?;
    let c = columns(path, header)?;
    let mut runs: Vec<(String, Trace)> = Vec::new();
    for (i, line) in lines.enumerate() {
        let n = i + 2;
        if line.trim().is_empty() {
            continue;
        }
        let cells: Vec<&str> = line.split(',').collect();
        let cell = |k: usize| -> anyhow::Result<f64> {
            let v = cells.get(k).map(|s| s.trim()).unwrap_or("");
            let col: usize = cells.iter().take(k).map(|s| s.len() + 1).sum::<usize>() + 1;
            v.parse::<f64>()
                .map_err(|_| anyhow::anyhow!("{}:{n}:{col}: `{v}` is not a number", path.display()))
        };
        let run = match c.run {
            Some(k) => format!("{label}run {}", cells.get(k).map_or("", |s| s.trim())),
            None => label.to_string(),
        };
        if runs.last().is_none_or(|(l, _)| *l != run) {
            runs.push((run, Trace::default()));
        }
        let (t, y, x) = (cell(c.time)?, cell(c.t2)?, cell(c.target)?);
        runs.last_mut().expect("pushed").1.push(t, x, y);
        *total += 1;
        if *total > MAX_SAMPLES {
            bail!(
                "{}:{n}: more than {MAX_SAMPLES} raw samples in the session: analyse it in parts",
                path.display()
            );
        }
    }
    Ok(runs)
}

/// The raw files of the session whose pairs are `pairs`.
fn raw_files(pairs: &Path) -> anyhow::Result<Vec<(PathBuf, String)>> {
    let dir = pairs.parent().unwrap_or(Path::new("."));
    let dir = if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    };
    let log = dir.join("raw.csv");
    if log.is_file() {
        return Ok(vec![(log, String::new())]);
    }
    let sim = dir.join("raw");
    if sim.is_dir() {
        let mut files: Vec<PathBuf> = std::fs::read_dir(&sim)
            .with_context(|| format!("cannot read {}", sim.display()))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "csv"))
            .collect();
        files.sort();
        if !files.is_empty() {
            return Ok(files
                .into_iter()
                .map(|p| {
                    let stem = p
                        .file_stem()
                        .map_or(String::new(), |s| s.to_string_lossy().into_owned());
                    (p, stem)
                })
                .collect());
        }
    }
    bail!(
        "{} is a force-control session (its pairs carry t2_target_n), and its tracking is read \
         from the raw time series beside it: no {} (capstan log) nor {}/*.csv (capstan simulate \
         --mode force)",
        pairs.display(),
        dir.join("raw.csv").display(),
        sim.display()
    )
}

/// The tracking report of the force session `pairs`, into `args.out`.
pub fn run(args: &super::Args, pairs: &Path, ctx: &capstan_report::Context) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let files = raw_files(pairs)?;
    let window = SteadyWindow::default();
    let mut total = 0;
    let mut runs = Vec::new();
    for (path, stem) in &files {
        let label = if stem.is_empty() {
            String::new()
        } else {
            format!("{stem}: ")
        };
        for (name, trace) in read_raw(path, &label, &mut total)? {
            if trace.target_n.iter().any(|&x| x > 0.0) {
                runs.push(TrackedRun::new(
                    name.trim_end_matches(": ").to_string(),
                    trace,
                    window,
                ));
            }
        }
    }
    if runs.is_empty() {
        bail!(
            "{}: no raw sample with a T2 target above 0",
            files[0].0.display()
        );
    }
    let names = ["report.html", "metrics.json"];
    let ours = |rel: &str| rel.starts_with("figures/figure-");
    let out =
        capstan_outdir::OutputDir::open_with(&args.out, "analyze", &names, &[("figures", &ours)])?;
    crate::outputs::say_recovered(&out);
    let mut set = out.stage()?;
    crate::errln!(
        "{}: a force-control session: the tracking of {} runs ({total} raw samples)",
        pairs.display(),
        runs.len()
    );
    let (html, figs) = tracking_html(&runs, &pairs.display().to_string(), window, ctx)?;
    let figure_files = capstan_report::figure_files(&figs, &ctx.figures)?;
    for f in &figure_files {
        let stamped = capstan_report::stamp::figure(&f.name, f.bytes.clone(), &ctx.provenance);
        set.write(&f.name, &stamped)?;
    }
    let mut metrics = tracking_metrics(&runs, window, ctx);
    metrics.elapsed_s = Some(t0.elapsed().as_secs_f64());
    let metrics = capstan_report::metrics::to_sorted_json(&metrics)?;
    set.write("report.html", html.as_bytes())?;
    set.write("metrics.json", metrics.as_bytes())?;
    set.commit()?;
    let (ss, os) = capstan_report::tracking::worst(&runs);
    crate::errln!(
        "wrote {}/report.html, metrics.json in {:.2} s: worst steady-state error {ss:.2} % of the target, worst overshoot {os:.1} % of the step",
        args.out.display(),
        t0.elapsed().as_secs_f64()
    );
    for r in runs.iter().filter(|r| !r.bode.is_empty()) {
        crate::errln!(
            "{}: {}",
            r.label,
            capstan_report::tracking::bandwidth_words(&r.bandwidth)
        );
    }
    if args.json {
        crate::outln!("{metrics}");
    }
    Ok(())
}
