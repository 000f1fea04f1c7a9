//! `capstan plan DATA.csv [--json] [--out DIR] [--hours H]`: the experiment that decides
//! between the hypotheses a data set leaves open. See [`capstan_plan`].

use capstan_plan::{plan, Options, Plan, Scored};
use std::fmt::Write as _;
use std::io::{IsTerminal, Write as _};
use std::path::PathBuf;

/// Arguments of `capstan plan`.
#[derive(clap::Args, Debug)]
#[command(after_help = capstan_data::COLUMNS_HELP)]
pub struct Args {
    /// The pairs.
    #[command(flatten)]
    pub input: super::input::DataArgs,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Also write `plan.json` and `plan.txt` into this directory.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Rig hours available: longer protocols are ranked but not recommended.
    #[arg(long, value_name = "H")]
    pub hours: Option<f64>,
    /// Simulated campaigns per hypothesis and protocol (more: a finer chance, longer).
    #[arg(long, default_value_t = 8)]
    pub reps: usize,
    /// Master seed of the simulated campaigns.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The board the printed `capstan rig` commands address, as `capstan rig` takes it
    /// (e.g. "--chip RP2040 --elf fw.elf" or "--sim DIR"); without it they carry a
    /// placeholder to replace.
    #[arg(long, value_name = "RIG_OPTIONS", allow_hyphen_values = true)]
    pub board: Option<String>,
}

/// Run `capstan plan`.
pub fn run(args: Args) -> anyhow::Result<()> {
    if let Some(h) = args.hours.filter(|h| !(h.is_finite() && *h > 0.0)) {
        anyhow::bail!("--hours {h}: must be a number of hours above 0");
    }
    if !(1..=1000).contains(&args.reps) {
        anyhow::bail!("--reps {}: must be 1 to 1000", args.reps);
    }
    if let Some(b) = &args.board {
        board_words(b)?;
    }
    let data = args.input.load()?;
    let data_warnings = super::check_data(&data)?;
    // A plan is built on the analysis of these data: what analyze refuses, plan refuses too.
    capstan_engine::analysis::enough_rows(&data)?;
    // The output directory is locked and checked before the planning (minutes), not after it.
    let out = match &args.out {
        Some(dir) => Some(crate::outputs::open_out(
            dir,
            "plan",
            &["plan.json", "plan.txt"],
        )?),
        None => None,
    };
    let mut p = match planned(&data, &args) {
        Ok(p) => p,
        Err(e) => {
            // Nothing was written: the directory is left as it was found.
            if let Some(out) = out {
                out.abandon();
            }
            return Err(e);
        }
    };
    let board = args
        .board
        .as_deref()
        .unwrap_or(capstan_plan::commands::PLACEHOLDER);
    capstan_plan::commands::with_board(&mut p, board);
    // How the data were read and where they came from, as diagnose and analyze say it.
    let structure = data.structure.summary();
    let answer = Answer {
        plan: &p,
        data: DataRead {
            source: &data.source,
            structure: &structure,
            warnings: &data_warnings,
        },
        seed: args.seed,
        provenance: args.input.provenance()?,
    };
    // Keys sorted at every level, as the plan's JSON has always been written.
    let json = serde_json::to_string_pretty(&serde_json::to_value(&answer)?)?;
    let text = words(&p, &data.source, &structure.statement);
    if let Some(out) = out {
        let mut set = out.stage()?;
        set.create("plan.json")?.write_all(json.as_bytes())?;
        set.create("plan.txt")?.write_all(text.as_bytes())?;
        set.commit()?;
    }
    if args.json {
        crate::outln!("{json}");
    } else {
        crate::out!("{text}");
    }
    Ok(())
}

/// `capstan plan --json` and `plan.json`: the plan (its `reps`, the campaigns per hypothesis
/// and protocol, among it), how the data were read and where they came from (as diagnose and
/// analyze say it), and the simulated campaigns' master seed: the same seed, data and program
/// give the same plan.
#[derive(serde::Serialize)]
struct Answer<'a> {
    #[serde(flatten)]
    plan: &'a Plan,
    data: DataRead<'a>,
    seed: u64,
    provenance: capstan_data::Provenance,
}

/// The data a plan was made from.
#[derive(serde::Serialize)]
struct DataRead<'a> {
    source: &'a str,
    structure: &'a capstan_data::structure::StructureSummary,
    warnings: &'a [String],
}

/// How long a stopped plan may take to return before it exits anyway (it stops within one
/// simulated campaign; the analysis of large data, or a cords set, can take longer).
const PLAN_GRACE: std::time::Duration = std::time::Duration::from_secs(3);

/// The plan of `data`, with a progress bar on a terminal; Ctrl-C or SIGTERM stops within one
/// simulated campaign, or exits after [`PLAN_GRACE`] (nothing is written, and DIR stays as
/// it was).
fn planned(data: &capstan_data::Dataset, args: &Args) -> anyhow::Result<Plan> {
    let opts = Options {
        reps: args.reps,
        seed: args.seed,
        max_hours: args.hours,
        stop: Some(super::signal::stop_flag("plan")),
        ..Options::default()
    };
    let bar = std::io::stderr().is_terminal().then(|| {
        let pb = indicatif::ProgressBar::new(0);
        pb.set_style(
            indicatif::ProgressStyle::with_template(
                "planning {bar:40} {pos}/{len} protocols [{elapsed_precise}]",
            )
            .expect("a valid template"),
        );
        pb
    });
    let stop = super::signal::stop_flag("plan");
    super::signal::exit_if_still_running_after("plan", PLAN_GRACE);
    let mut progress = |done: usize, total: usize| {
        if let Some(pb) = &bar {
            pb.set_length(total as u64);
            pb.set_position(done as u64);
        }
        !stop.load(std::sync::atomic::Ordering::SeqCst)
    };
    let p = plan(data, &opts, &mut progress);
    if let Some(pb) = bar {
        pb.finish_and_clear();
    }
    match p {
        Ok(p) => Ok(p),
        Err(capstan_plan::PlanError::Stopped) => Err(stopped_plan(args.out.as_deref())),
        Err(e) => anyhow::bail!("{e}"),
    }
}

/// The plan in words: what is open, the protocols ranked, the recommendation.
pub fn words(p: &Plan, source: &str, structure: &str) -> String {
    let mut s = String::new();
    let labels: Vec<String> = p.hypotheses.iter().map(|h| h.label()).collect();
    let _ = writeln!(s, "{source}: {structure}");
    let _ = writeln!(s, "open hypotheses: {}", labels.join(" | "));
    for h in p.hypotheses.iter().filter(|h| h.origin != "named") {
        let _ = writeln!(s, "  {}: {}", h.label(), h.origin);
    }
    for n in &p.not_simulated {
        let _ = writeln!(s, "  also open, not simulated: {}: {}", n.what, n.why);
    }
    for a in &p.assumed {
        let _ = writeln!(s, "  assumed: {a}");
    }
    let _ = writeln!(
        s,
        "\n{:<44} {:>9} {:>12}  per hypothesis",
        "protocol", "rig hours", "worst chance"
    );
    for c in &p.candidates {
        let per: Vec<String> = (c.per_hypothesis.iter())
            .map(|r| match &r.not_simulated {
                Some(_) => format!("{} not simulated", r.hypothesis),
                None => format!("{} {}/{}", r.hypothesis, r.decided, r.campaigns),
            })
            .collect();
        // A protocol with no campaign simulated has no chance to show, not 0 %.
        let worst = if c.per_hypothesis.iter().all(|r| r.not_simulated.is_some()) {
            "not simulated".to_string()
        } else {
            format!("{:.0} %", 100.0 * c.p_decide_worst)
        };
        let _ = writeln!(
            s,
            "{:<44} {:>9.1} {:>13}  {}",
            c.candidate.name,
            c.rig_hours,
            worst,
            per.join(", ")
        );
    }
    let _ = writeln!(s);
    if p.first.which == "cords" {
        cords_words(&mut s, p);
        let _ = writeln!(s, "Then, for the hypotheses above:");
        recommendation(&mut s, p, &p.recommended);
    } else {
        recommendation(&mut s, p, &p.recommended);
        cords_words(&mut s, p);
    }
    let _ = writeln!(s, "first: {} ({})", p.first.which, p.first.why);
    let _ = writeln!(s, "method: {} ({:.1} s)", p.method, p.elapsed_s);
    s
}

/// How many cords each open question between cords needs.
fn cords_words(s: &mut String, p: &Plan) {
    let Some(c) = &p.cords else {
        return;
    };
    if c.questions.is_empty() {
        let _ = writeln!(s, "How many cords: no question between cords is open.");
        return;
    }
    if let Some((q, t)) = p.cords_first().filter(|_| p.first.which == "cords") {
        let _ = writeln!(
            s,
            "Recommended first: {} new cords ({} runs on each, {:.1} rig hours) to establish {} ({} of {} simulated campaigns do); {}.",
            t.cords, t.runs_per_cord, t.rig_hours, q.question, t.established, t.campaigns, p.first.why
        );
    }
    let _ = writeln!(
        s,
        "How many cords (80 % of simulated campaigns establishing it):"
    );
    for q in &c.questions {
        let tried: Vec<String> = (q.trials.iter())
            .map(|t| {
                format!(
                    "{} cords × {} runs {}/{}",
                    t.cords, t.runs_per_cord, t.established, t.campaigns
                )
            })
            .collect();
        let mut answer = match &q.needed {
            Some(t) => format!(
                "{} cords with {} runs each ({:.1} rig hours)",
                t.cords, t.runs_per_cord, t.rig_hours
            ),
            None => "more cords than tried".to_string(),
        };
        answer += &at_observed_spread(q);
        let _ = writeln!(
            s,
            "  {}: {answer}; observed {}; its answer moves T2 at these rows by {:.2} N (RMS); tried {}",
            q.question,
            q.observed,
            q.stake_n,
            tried.join(", ")
        );
    }
    let _ = writeln!(s, "  method: {}", c.method);
}

/// The held-out gain's second answer: the simulated world's median gain beside the data's, and
/// the cords the analysis's resampling of the data's own cords needs (the gain at its observed
/// spread from cord to cord). Empty for the other questions.
fn at_observed_spread(q: &capstan_plan::cords::Question) -> String {
    let Some(n) = &q.at_observed_spread else {
        return String::new();
    };
    let median = q
        .needed
        .as_ref()
        .or(q.trials.last())
        .and_then(|t| t.median_ratio);
    let world = median.map_or(String::new(), |m| {
        format!(" in the simulated world, whose sets' median held-out ratio is {m:.2}")
    });
    let resampled = match n.cords {
        Some(k) => format!("about {k} cords"),
        None => format!("more than {} cords", n.tried_up_to),
    };
    format!(
        "{world}; {resampled} at the data's own spread of the gain from cord to cord (resampling the cords' held-out errors, as `analyze` says)"
    )
}

fn recommendation(s: &mut String, p: &Plan, r: &Scored) {
    if !p.within_hours {
        let _ = writeln!(
            s,
            "No candidate protocol fits in the hours given; the shortest ({:.1} h) follows.",
            r.rig_hours
        );
    }
    if let Some(b) = &p.better_beyond_hours {
        let _ = writeln!(
            s,
            "Within the hours given no protocol does better than {:.0} %: {} reaches {:.0} % (worst case) but needs {:.1} rig hours.",
            100.0 * r.p_decide_worst,
            b.name,
            100.0 * b.p_decide_worst,
            b.rig_hours
        );
    }
    if !p.any_decides && p.any_named {
        let _ = writeln!(
            s,
            "No candidate protocol named every hypothesis alone: each left at least one \
             never named in its campaigns (0 % worst case), so none of these decides; more \
             runs, cords or a different rig are needed."
        );
    } else if !p.any_decides {
        let _ = writeln!(
            s,
            "No candidate protocol named the true hypothesis alone in any simulated campaign: \
             none of these decides; more runs, cords or a different rig are needed."
        );
    }
    if p.current_decides {
        let _ = writeln!(
            s,
            "The current design already decides between the simulated hypotheses ({:.0} % \
             worst case): run it again as it is.",
            100.0 * p.current_design.p_decide_worst
        );
        if !p.not_simulated.is_empty() {
            let _ = writeln!(
                s,
                "  ({} more open question(s) above were not simulated: this says nothing about \
                 them.)",
                p.not_simulated.len()
            );
        }
    } else if r.p_decide_worst == 0.0 {
        let named: usize = r.per_hypothesis.iter().map(|h| h.decided).sum();
        let of: usize = r.per_hypothesis.iter().map(|h| h.campaigns).sum();
        let _ =
            writeln!(
            s,
            "No design {}reaches a decision (0 % worst case): no recommendation. {} ({:.1} rig \
             hours) named its truth alone most often ({named} of {of} campaigns) and follows \
             only as a place to start.",
            if p.any_decides { "within the hours " } else { "" },
            r.candidate.name,
            r.rig_hours
        );
    } else {
        let _ = writeln!(
            s,
            "Recommended: {} — {:.0} % worst-case chance of naming the true hypothesis alone \
             ({:.1} rig hours), against {:.0} % for the current design ({:.1} h).",
            r.candidate.name,
            100.0 * r.p_decide_worst,
            r.rig_hours,
            100.0 * p.current_design.p_decide_worst,
            p.current_design.rig_hours
        );
    }
    for c in &r.candidate.physical_changes {
        let _ = writeln!(s, "  by hand: {c}");
    }
    if r.candidate
        .rig_commands
        .iter()
        .any(|c| c.contains(capstan_plan::commands::PLACEHOLDER))
    {
        let _ = writeln!(
            s,
            "  (replace `{}` by your board: the firmware ELF it runs, or --sim DIR; `capstan \
             plan --board \"...\"` prints it in)",
            capstan_plan::commands::PLACEHOLDER
        );
    }
    for c in &r.candidate.rig_commands {
        let _ = writeln!(s, "  {c}");
    }
    for c in &r.candidate.procedure {
        let _ = writeln!(s, "  then: {c}");
    }
    let _ = writeln!(
        s,
        "  check it: capstan simulate --out DIR {}",
        r.simulate_args.join(" ")
    );
}

/// The error of a plan stopped by a signal: what was (not) written.
pub(super) fn stopped_plan(out: Option<&std::path::Path>) -> anyhow::Error {
    let kept = out.map_or(String::new(), |d| format!("; {} is as it was", d.display()));
    anyhow::Error::new(super::signal::Interrupted(format!(
        "stopped ({}): the plan was not finished, nothing was written{kept}",
        super::signal::stop_reason().unwrap_or("Ctrl-C")
    )))
}

/// `--board`: `capstan rig` options the printed commands carry, to be pasted into a shell.
/// Empty, or a character a shell reads as more than a word (`;`, `|`, `&`, `$`, quotes,
/// redirections, a line break), is refused: a command to copy must not carry another.
fn board_words(b: &str) -> anyhow::Result<()> {
    if b.trim().is_empty() {
        anyhow::bail!("--board \"\": give the board's options, e.g. --board \"--chip RP2040 --elf target/thumbv6m-none-eabi/release/capstan-board\" or --board \"--sim DIR\"");
    }
    if let Some(c) = b.chars().find(|c| ";|&$`<>(){}\\\"'*?!#~\n\r".contains(*c)) {
        anyhow::bail!(
            "--board {b:?}: {c:?} is not part of a board's options (they are pasted into the \
             printed `capstan rig` commands, and a shell would read it): give options and paths \
             only, e.g. --chip RP2040 --elf FILE or --sim DIR"
        );
    }
    Ok(())
}
