//! `capstan analyze [DATA.csv] --out DIR`: fit the models, test the mechanisms, write the
//! report (`report.html`), `metrics.json` and `predictions.csv`. On a force-control session
//! (pairs with a T2 target): the tracking report instead (`analyze/force.rs`).

mod force;

use anyhow::Context;
use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `capstan analyze`.
#[derive(clap::Args, Debug)]
#[command(after_help = capstan_data::COLUMNS_HELP)]
pub struct Args {
    /// The pairs.
    #[command(flatten)]
    pub input: super::input::DataArgs,
    /// Output directory (created if needed). Analyze always writes its report, so it has a
    /// place by default (the README's main job); the commands whose files are optional
    /// (discover, plan) write only with --out, and those that record (simulate, log,
    /// condition) need it.
    #[arg(long, default_value = "report")]
    pub out: PathBuf,
    /// Print the metrics (including timings) as JSON on stdout.
    #[arg(long)]
    pub json: bool,
    /// How the steps are timed.
    #[command(flatten)]
    pub timing: super::input::TimingArgs,
    /// Threads for independent fits (default: up to 4).
    #[arg(long, allow_negative_numbers = true)]
    pub threads: Option<usize>,
    /// Instead of analysing DATA: validate the cause-naming on 40 data sets with planted truths,
    /// simulated end to end (firmware in the loop, the thesis rig's noise); prints the figures
    /// and every miss, writes DIR/validation.json, and fails if a target is missed.
    #[arg(long)]
    pub validate: bool,
    /// Master seed of the validation's data sets: by default the held-out seed the README's
    /// validation figures come from (the rules were set on seed 99), not the 1 that simulate,
    /// plan and a new simulated board start from.
    #[arg(long, default_value_t = 31_415_926)]
    pub seed: u64,
    /// Also write every figure as a standalone file under DIR/figures/ (figure-N-ID.EXT, N as
    /// in the report): a comma list of svg, png (300 dpi, its resolution in the file), pdf. Each
    /// file is exactly --width-mm wide and at most 225 mm high.
    #[arg(long, value_name = "FORMATS")]
    pub figures: Option<String>,
    /// Width of the figures, mm (85: one journal column; 170: the page). The report's figures
    /// are laid out to it too.
    #[arg(long, default_value_t = 170.0)]
    pub width_mm: f64,
    /// Size of the figures' tick labels, pt (titles and axis labels are a little larger).
    #[arg(long, default_value_t = 8.0)]
    pub font_pt: f64,
    /// Put "Figure N" into each figure file, above its legend (by default the files carry no
    /// number: the journal's caption numbers the figure).
    #[arg(long)]
    pub figure_numbers: bool,
    /// Compare with the thesis's Table 3 even when the data are not the thesis's (by default
    /// only the thesis data, recognised by their SHA-256, are compared with it).
    #[arg(long)]
    pub thesis_comparison: bool,
    /// Also run the planner (`capstan plan`, about a minute) and put its recommendation in the
    /// report's "Next experiment" section; without it the section lists what is open and the
    /// `capstan plan` command to run.
    #[arg(long)]
    pub plan: bool,
}

/// Run `capstan analyze`.
pub fn run(args: Args) -> anyhow::Result<()> {
    if let Some(t) = args.threads {
        capstan_data::ranges::THREADS.option("--threads", t as f64)?;
    }
    if args.validate {
        return validate(&args);
    }
    let t0 = Instant::now();
    let figures = figure_options(&args)?;
    // The data first (a file it refuses leaves no output directory behind), then the output
    // directory, locked and proved writable before the analysis, not after it.
    let ds = args.input.load()?;
    let ctx = report_context(&args, figures)?;
    if let (Some(path), true) = (&args.input.data, force::is_force_session(&ds)) {
        // Force control: how the rig tracked its target, not the law (issue 43).
        return force::run(&args, path, &ctx);
    }
    let data_warnings = super::check_data(&ds)?;
    capstan_engine::analysis::enough_rows(&ds)?;
    let names = ["report.html", "metrics.json", "predictions.csv"];
    let ours = |rel: &str| rel.starts_with("figures/figure-");
    let tables = |rel: &str| {
        ["parameters", "models"]
            .iter()
            .any(|t| rel == format!("tables/{t}.csv") || rel == format!("tables/{t}.tex"))
    };
    let out = capstan_outdir::OutputDir::open_with(
        &args.out,
        "analyze",
        &names,
        &[("figures", &ours), ("tables", &tables)],
    )?;
    crate::outputs::say_recovered(&out);
    let mut set = out.stage()?;
    let mut opts = capstan_engine::analysis::Options::default();
    if let Some(t) = args.threads {
        opts.threads = t.max(1);
    }
    opts.protocol_times = args.timing.protocol_times;
    crate::errln!("analysing {} ({} pairs) ...", ds.source, ds.pairs.len());
    let mut a = capstan_engine::analysis::run(&ds, opts)?;
    crate::errln!("{}", a.evidence.data.structure.statement);
    capstan_report::apply_thesis_choice(&mut a, &ctx.thesis);
    // From here on the set holds work: a late failure keeps it and says where.
    set.keep_on_failure(crate::outputs::say_kept);
    for note in &a.fit_notes {
        crate::errln!("warning: {note}");
    }
    let t_report = Instant::now();
    let closed = closed_loop(&mut a, opts.threads);
    let (disc, disc_s) = discovery(&ds, args.timing.protocol_times)?;
    let next = next_experiment(&args, &ds)?;
    let (html, figs) =
        capstan_report::report_html(&a, closed.curves.as_deref(), &closed.note, &ctx)?;
    let html = with_sections(html, &disc, &next);
    let t_files = Instant::now();
    let files = capstan_report::figure_files(&figs, &ctx.figures)?;
    if !files.is_empty() && !capstan_report::export::have_fonts() {
        crate::errln!("warning: no system fonts found: the PNG and PDF figures have no text (the SVG files do)");
    }
    for f in files.iter() {
        // Each figure file says where it came from, as metrics.json does.
        let stamped = capstan_report::stamp::figure(&f.name, f.bytes.clone(), &ctx.provenance);
        set.write(&f.name, &stamped)?;
    }
    a.elapsed.figure_files_s = t_files.elapsed().as_secs_f64();
    for (name, text) in capstan_report::table_files::table_files(&a, &ctx.provenance.line()) {
        set.write(&name, text.as_bytes())?;
    }
    write_predictions(&mut set, &args, &ds, &a)?;
    a.elapsed.report_s = t_report.elapsed().as_secs_f64();
    a.elapsed.total_s = t0.elapsed().as_secs_f64();
    let metrics = capstan_report::Metrics::new(&a, Some(&closed.outcome), &ctx)
        .with_discovered(capstan_report::discovered::discovered(&disc, disc_s))
        .with_next(&next)
        .with_data_warnings(&data_warnings)
        .to_json()?;
    set.write("report.html", html.as_bytes())?;
    set.write("metrics.json", metrics.as_bytes())?;
    set.commit()?;
    say_written(&args, files.len(), t0);
    if args.json {
        crate::outln!("{metrics}");
    }
    Ok(())
}

/// The figure options, checked (before the data are read, as they always were).
fn figure_options(args: &Args) -> anyhow::Result<capstan_report::FigureOptions> {
    let figures = capstan_report::FigureOptions {
        formats: match &args.figures {
            Some(f) => capstan_report::Format::parse_list(f)?,
            None => Vec::new(),
        },
        width_mm: args.width_mm,
        font_pt: args.font_pt,
        numbers: args.figure_numbers,
    };
    figures.check()?;
    Ok(figures)
}

/// What the report needs besides the analysis: the figure options, provenance (the input's
/// hash: read after the data, so that a file that cannot be read is said as every command that
/// reads pairs says it, [`super::input::DataArgs::load`]), and whether to compare with the
/// thesis's Table 3.
fn report_context(
    args: &Args,
    figures: capstan_report::FigureOptions,
) -> anyhow::Result<capstan_report::Context> {
    let provenance = args.input.provenance()?;
    let thesis = capstan_report::ThesisComparison::decide(
        crate::provenance::is_thesis(&provenance),
        args.thesis_comparison,
    );
    Ok(capstan_report::Context {
        provenance,
        thesis,
        figures,
    })
}

/// The firmware in the loop with the extended model: its curves for the report, its summary
/// for metrics.json, and the sentence that says what was run (or why it failed).
struct ClosedLoop {
    curves: Option<Vec<capstan_engine::analysis::closed_loop::SimCurve>>,
    outcome: capstan_engine::analysis::closed_loop::Outcome,
    note: String,
}

/// Run the closed loop (its time into the analysis's timings).
fn closed_loop(a: &mut capstan_engine::analysis::Analysis, threads: usize) -> ClosedLoop {
    use capstan_engine::analysis::closed_loop::Outcome;
    let t = Instant::now();
    let out = match capstan_validation::closed_loop::run(a, threads) {
        Ok(cl) => ClosedLoop {
            curves: Some(cl.curves),
            outcome: Outcome::Ran(cl.summary),
            note: "The firmware, run in virtual time against the simulated plant (capstan_sim::campaign) with the extended model as its friction law (each cord's fitted mu factor and the named causes), on the thesis campaign: one run per cord, sensor noise off.".to_string(),
        },
        Err(e) => ClosedLoop {
            curves: None,
            outcome: Outcome::Failed {
                error: format!("{e:#}"),
            },
            note: format!("The closed-loop simulation failed: {e:#}"),
        },
    };
    a.elapsed.closed_loop_s = t.elapsed().as_secs_f64();
    out
}

/// Beyond the catalogue (`capstan discover`), kept apart from the catalogue's causes: the
/// search and its time, s.
fn discovery(
    ds: &capstan_data::Dataset,
    protocol_times: bool,
) -> anyhow::Result<(capstan_discover::Discovery, f64)> {
    let t = Instant::now();
    let mut opts = capstan_discover::Options::default();
    opts.engine.protocol_times = protocol_times;
    let disc = capstan_discover::discover(ds, &opts, &mut |_, _| {});
    Ok((disc, t.elapsed().as_secs_f64()))
}

/// The report with its "discovered" and "Next experiment" sections in place.
fn with_sections(
    html: String,
    disc: &capstan_discover::Discovery,
    next: &capstan_report::next::NextExperiment,
) -> String {
    use capstan_report::discovered::{discovered_html, insert_section};
    let html = insert_section(html, &discovered_html(disc));
    insert_section(html, &capstan_report::next::next_html(next))
}

/// predictions.csv into the staged set.
fn write_predictions(
    set: &mut capstan_outdir::Staged,
    args: &Args,
    ds: &capstan_data::Dataset,
    a: &capstan_engine::analysis::Analysis,
) -> anyhow::Result<()> {
    let mut csv = set.create("predictions.csv")?;
    capstan_report::write_predictions_csv(&mut csv, ds, a)
        .and_then(|()| csv.flush())
        .with_context(|| {
            format!(
                "cannot write {}",
                args.out.join("predictions.csv").display()
            )
        })
}

/// The closing line: what was written where, and how long it took.
fn say_written(args: &Args, figure_files: usize, t0: Instant) {
    crate::errln!(
        "wrote {}/report.html, metrics.json, predictions.csv, tables/{{parameters,models}}.{{csv,tex}}, tables/parameters-cords.tex{} in {:.2} s",
        args.out.display(),
        if figure_files == 0 {
            String::new()
        } else {
            format!(" and {figure_files} figure files in figures/")
        },
        t0.elapsed().as_secs_f64()
    );
}

/// The "Next experiment" object: what is open (one diagnosis), and with `--plan` the plan.
fn next_experiment(
    args: &Args,
    ds: &capstan_data::Dataset,
) -> anyhow::Result<capstan_report::next::NextExperiment> {
    let open = capstan_plan::open(ds);
    let plan = if args.plan {
        crate::errln!("planning the next experiment (--plan: about a minute) ...");
        let stop = super::signal::stop_flag("analyze");
        let mut go_on = |_, _| !stop.load(std::sync::atomic::Ordering::SeqCst);
        let p = match capstan_plan::plan(ds, &Default::default(), &mut go_on) {
            Ok(p) => p,
            Err(capstan_plan::PlanError::Stopped) => {
                return Err(super::plan::stopped_plan(Some(args.out.as_path())))
            }
            Err(e) => anyhow::bail!("the planner: {e}"),
        };
        Some(p)
    } else {
        None
    };
    // The data's absolute path, quoted for a shell: the command runs from anywhere.
    let command = match &args.input.data {
        Some(p) => {
            let abs = std::fs::canonicalize(p).unwrap_or_else(|_| p.clone());
            format!("capstan plan {}", shell_quoted(&abs.display().to_string()))
        }
        None => "capstan plan".to_string(),
    };
    Ok(capstan_report::next::next_experiment(
        &open,
        plan.as_ref(),
        &command,
    ))
}

/// `s` as one shell word: as it is when it holds only characters no shell treats specially,
/// else in single quotes (a quote inside written '\'').
fn shell_quoted(s: &str) -> String {
    let plain = |c: char| c.is_ascii_alphanumeric() || "/._-+,:@%=".contains(c);
    if !s.is_empty() && s.chars().all(plain) {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', "'\\''"))
    }
}

/// `capstan analyze --validate`.
fn validate(args: &Args) -> anyhow::Result<()> {
    let threads = args
        .threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    crate::errln!(
        "validating the cause-naming on {} planted data sets (seed {}) ...",
        capstan_validation::validate::cases(args.seed).len(),
        args.seed
    );
    let mut set = crate::outputs::open_out(&args.out, "validate", &["validation.json"])?.stage()?;
    let t0 = Instant::now();
    let v = capstan_validation::validate::validate(args.seed, 1, threads)?;
    set.keep_on_failure(crate::outputs::say_kept);
    let pct = |x: (usize, usize)| 100.0 * x.0 as f64 / x.1.max(1) as f64;
    crate::outln!(
        "causes named exactly (clean, single, heating + T1 loss): {}/{} ({:.0} %, target ≥ 90 %)",
        v.named_exactly.0,
        v.named_exactly.1,
        pct(v.named_exactly)
    );
    crate::outln!(
        "clean sets with a cause named or structure flagged: {}/{} ({:.0} %, target ≤ 5 %)",
        v.clean_alarms.0,
        v.clean_alarms.1,
        pct(v.clean_alarms)
    );
    crate::outln!(
        "outside the catalogue flagged unexplained: {}/{} ({:.0} %, target ≥ 80 %)",
        v.outside_flagged.0,
        v.outside_flagged.1,
        pct(v.outside_flagged)
    );
    for o in v.outcomes.iter().filter(|o| !o.correct) {
        crate::outln!(
            "MISS {} -> named {:?}, unexplained {}",
            o.case,
            o.named,
            o.unexplained
        );
    }
    crate::outln!("({:.1} s)", t0.elapsed().as_secs_f64());
    set.write(
        "validation.json",
        serde_json::to_string_pretty(&v)?.as_bytes(),
    )?;
    set.commit()?;
    let why = v.failures();
    if !why.is_empty() {
        anyhow::bail!("validation missed its targets: {}", why.join("; "));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::shell_quoted;

    #[test]
    fn a_path_is_one_shell_word() {
        assert_eq!(shell_quoted("/data/run1.csv"), "/data/run1.csv");
        assert_eq!(
            shell_quoted("/tmp/my data/run (1).csv"),
            "'/tmp/my data/run (1).csv'"
        );
        assert_eq!(shell_quoted("/tmp/it's.csv"), "'/tmp/it'\\''s.csv'");
        assert_eq!(shell_quoted(""), "''");
    }
}
