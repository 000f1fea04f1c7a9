//! `capstan discover DATA.csv [--json] [--out DIR]`: after the catalogue, search a library of
//! physically meaningful terms for what is left; propose a term only when it earns its
//! evidence (with the search paid for), is stable over whole-cord resamples, helps held-out
//! cords and resolves the lack of fit. See [`capstan_discover`] and docs/README-discover.md.

use capstan_discover::{discover, Discovery, Options};
use capstan_engine::evidence::adequacy;
use std::fmt::Write as _;
use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// Arguments of `capstan discover`.
#[derive(clap::Args, Debug)]
#[command(after_help = capstan_data::COLUMNS_HELP)]
pub struct Args {
    /// The pairs.
    #[command(flatten)]
    pub input: super::input::DataArgs,
    /// Print one JSON object instead of the summary.
    #[arg(long)]
    pub json: bool,
    /// Also write the JSON to DIR/discover.json (the directory is locked and written whole).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// How the steps are timed.
    #[command(flatten)]
    pub timing: super::input::TimingArgs,
}

/// Run `capstan discover`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let data = args.input.load()?;
    let data_warnings = super::check_data(&data)?;
    // What analyze refuses, discover refuses too (a search needs the analysis's data).
    capstan_engine::analysis::enough_rows(&data)?;
    // Lock the output directory before the work, not after it.
    let mut set = match &args.out {
        Some(dir) => Some(crate::outputs::open_out(dir, "discover", &["discover.json"])?.stage()?),
        None => None,
    };
    let mut opts = Options::default();
    opts.engine.protocol_times = args.timing.protocol_times;
    let bar = Progress::new(!args.json && std::io::stderr().is_terminal());
    let mut d = discover(&data, &opts, &mut |stage, f| bar.tick(stage, f));
    bar.finish();
    // Where the answer came from (program, commit, the input's SHA-256, the command line), as
    // every output carries it, and what the data checks warned about.
    d.provenance = Some(args.input.provenance()?);
    d.data.warnings = Some(data_warnings);
    let json = d.to_json();
    if let Some(set) = set.as_mut() {
        set.keep_on_failure(crate::outputs::say_kept);
        set.write("discover.json", json.as_bytes())?;
    }
    if let Some(set) = set {
        set.commit()?;
    }
    if args.json {
        crate::outln!("{json}");
    } else {
        crate::out!("{}", summary(&d));
    }
    Ok(())
}

/// A progress bar on a terminal, shown once the search has run for a second.
struct Progress {
    on: bool,
    t0: Instant,
    bar: std::cell::OnceCell<indicatif::ProgressBar>,
}

impl Progress {
    fn new(on: bool) -> Self {
        Progress {
            on,
            t0: Instant::now(),
            bar: std::cell::OnceCell::new(),
        }
    }

    fn tick(&self, stage: &str, fraction: f64) {
        if !self.on || self.t0.elapsed() < Duration::from_secs(1) {
            return;
        }
        let pb = self.bar.get_or_init(|| {
            let pb = indicatif::ProgressBar::new(100);
            if let Ok(style) =
                indicatif::ProgressStyle::with_template("discover {bar:40} {msg} [{elapsed}]")
            {
                pb.set_style(style);
            }
            pb
        });
        pb.set_position((100.0 * fraction.clamp(0.0, 1.0)) as u64);
        pb.set_message(stage.to_string());
    }

    fn finish(&self) {
        if let Some(pb) = self.bar.get() {
            pb.finish_and_clear();
        }
    }
}

/// The human summary.
pub fn summary(d: &Discovery) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "{}: {} rows", d.data.source, d.data.rows);
    let _ = writeln!(s, "{}", d.data.structure.statement);
    let _ = writeln!(
        s,
        "catalogue effects: {}",
        if d.catalogue_effects.is_empty() {
            "none".to_string()
        } else {
            d.catalogue_effects.join(" + ")
        }
    );
    let _ = writeln!(s, "{}", d.verdict);
    for t in &d.terms {
        let _ = writeln!(s, "  {}  [{:?} → {}]", t.name, t.acts_on, t.formula);
        let _ = writeln!(s, "    {}", t.words);
    }
    s += &search_line(&d.search);
    let _ = writeln!(s, "strongest candidates (ΔBIC given the catalogue):");
    for r in d.search.screen.iter().take(5) {
        let _ = writeln!(
            s,
            "  {:<20} {:>7.1}  θ = {:.4}{}{}{}",
            r.name,
            r.delta_bic,
            r.theta,
            r.se.map_or(
                " (SE n/a: fewer than 3 runs, no run-clustered error)".to_string(),
                |se| format!(" ± {se:.4}")
            ),
            if r.sign_ok {
                ""
            } else {
                "  (wrong physical sign)"
            },
            if r.r2_model > 0.99 {
                "  (not separable from the catalogue)"
            } else {
                ""
            }
        );
    }
    for x in &d.declined {
        let _ = writeln!(s, "  not proposed: {}: {}", x.name, x.reason);
    }
    if let Some(l) = &d.lack_of_fit_before {
        let _ = writeln!(
            s,
            "lack of fit the catalogue leaves: F = {}, p {}, systematic part {:.2}× the noise",
            adequacy::f_shown(l.f, 2),
            adequacy::lof_p_equals(l.p),
            l.systematic_ratio
        );
    }
    for n in &d.not_testable {
        let _ = writeln!(s, "  not testable: {}: {}", n.name, n.reason);
    }
    let _ = writeln!(s, "({:.3} s)", d.elapsed_s);
    s
}

/// The search's size and bar, in one line: what a reader needs to weigh a proposed term.
fn search_line(sr: &capstan_discover::Search) -> String {
    let checks = match (sr.resamples, &sr.cord_checks) {
        (Some(b), None) => format!(
            "stability ≥ {:.0} % over {b} cord resamples",
            100.0 * sr.min_stability
        ),
        (_, Some(why)) => format!("{why}, so nothing can be proposed"),
        (None, None) => "no stability computed".to_string(),
    };
    let how = match sr.displaceable.len() {
        0 => "each added to the catalogue (it has no within-run effect to take the place of)"
            .to_string(),
        1 => "each added to the catalogue or in the place of its within-run effect".to_string(),
        k => format!(
            "each added to the catalogue or in the place of one of its {k} within-run effects"
        ),
    };
    // A term tried at several places (the mu bump's centres) counts once per place.
    let plain = (sr.tried * (1 + sr.displaceable.len())) as f64;
    let models = if sr.models_per_step > plain {
        format!(
            "{:.0} models, the mu bump once per centre tried",
            sr.models_per_step
        )
    } else {
        format!("{:.0} models", sr.models_per_step)
    };
    format!(
        "searched {} of {} library terms, {how} ({models}); bar for the first: ΔBIC < {:.1} (the engine's −{:.0} plus 2γ·ln {:.0} for the search); {checks}\n",
        sr.tried,
        sr.library_size,
        sr.first_bar,
        sr.threshold,
        sr.models_per_step,
    )
}
