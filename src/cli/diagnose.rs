//! `capstan diagnose DATA.csv [--json]`: which single catalogue effect (if any) makes a data
//! set depart from Euler-Eytelwein, and its size. See [`crate::diagnose`].

use crate::data::{load_pairs, thesis_dataset};
use crate::diagnose::{self, Diagnosis, Level, Options};
use std::fmt::Write as _;
use std::path::PathBuf;

/// Arguments of `capstan diagnose`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Pairs CSV (`wrap_deg,t1_n,t2_n` required; `capstan_diameter_mm,drive_v,run,step,time_s`
    /// optional). Without it, the bundled thesis data.
    pub data: Option<PathBuf>,
    /// Print one JSON object instead of the summary.
    #[arg(long)]
    pub json: bool,
    /// Without a `time_s` column, take the times from `step` with the thesis protocol (10 s
    /// steps), so that `thermal_drift` can be tested.
    #[arg(long)]
    pub protocol_times: bool,
    /// A within-run (shape) effect is reported when its ΔBIC is below minus this.
    #[arg(long, default_value_t = diagnose::WITHIN_THRESHOLD)]
    pub within_threshold: f64,
    /// A between-run or between-cord effect is reported when its ΔBIC is below minus this.
    #[arg(long, default_value_t = diagnose::BETWEEN_THRESHOLD)]
    pub between_threshold: f64,
}

/// Run `capstan diagnose`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let data = match &args.data {
        Some(p) => load_pairs(p)?,
        None => thesis_dataset(),
    };
    let opts = Options {
        within_threshold: args.within_threshold,
        between_threshold: args.between_threshold,
        protocol_times: args.protocol_times,
    };
    let d = diagnose::diagnose_with(&data, &opts);
    if args.json {
        println!("{}", d.to_json());
    } else {
        print!("{}", summary(&d, &data.source));
    }
    Ok(())
}

fn level_name(l: Level) -> &'static str {
    match l {
        Level::WithinRun => "shape within runs",
        Level::BetweenCord => "between cords",
        Level::BetweenRun => "between runs",
    }
}

/// The human summary: the call, the evidence, what could not be tested.
pub fn summary(d: &Diagnosis, source: &str) -> String {
    let mut s = String::new();
    let g = &d.design;
    let _ = writeln!(
        s,
        "{source}: {} rows, {} cords, {} runs; wraps {:?} deg, diameters {:?} mm, drive {:?} V",
        g.rows, g.cords, g.runs, g.wraps_deg, g.diameters_mm, g.drive_v
    );
    match d.parameters.iter().next() {
        Some((name, v)) => {
            let c = d
                .candidate(d.kind)
                .expect("the chosen effect is a candidate");
            let _ = writeln!(
                s,
                "diagnosis: {} ({name} = {v:.4e} ± {:.1e}), ΔBIC {:.1} against Euler-Eytelwein ({})",
                d.effect,
                c.parameter_se,
                c.delta_bic,
                level_name(c.level)
            );
        }
        None => {
            let _ = writeln!(
                s,
                "diagnosis: none (no effect reaches ΔBIC {:.0} within runs or {:.0} between runs/cords)",
                d.thresholds.within_run, d.thresholds.between
            );
        }
    }
    let _ = writeln!(
        s,
        "Euler-Eytelwein: mu = {:.4}, RMSE(T2) {:.3} N with one mu, {:.4} N with every run's own mu",
        d.baseline.mu, d.baseline.rmse_t2_n, d.baseline.rmse_t2_run_mu_n
    );
    if d.effect != "none" {
        let _ = writeln!(
            s,
            "with {}: RMSE(T2) {:.3} N with one mu, {:.4} N with every run's own mu",
            d.effect, d.extended.rmse_t2_n, d.extended.rmse_t2_run_mu_n
        );
    }
    let _ = writeln!(
        s,
        "scatter of mu: {:.2} % cord to cord, {:.2} % run to run; overdispersion of within-run evidence {:.1}",
        d.scatter.cord_pct, d.scatter.run_pct, d.scatter.overdispersion
    );
    let _ = writeln!(
        s,
        "candidates (ΔBIC against none; supported if below the threshold of its level):"
    );
    for c in &d.candidates {
        let (name, v) = c
            .parameters
            .iter()
            .next()
            .map_or(("-", f64::NAN), |(k, v)| (*k, *v));
        let _ = writeln!(
            s,
            "  {:<20} {:>10.1}  {name} = {v:.4e} ± {:.1e}  [{}]{}",
            c.effect,
            c.delta_bic,
            c.parameter_se,
            level_name(c.level),
            if c.supported { "  supported" } else { "" }
        );
    }
    for n in &d.not_testable {
        let _ = writeln!(s, "  {:<20} not testable: {}", n.effect, n.reason);
    }
    let _ = writeln!(s, "({:.3} s)", d.elapsed_s);
    s
}
