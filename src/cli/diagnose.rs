//! `capstan diagnose DATA.csv [--json]`: which catalogue effects (if any) make a data set depart
//! from Euler-Eytelwein, their sizes, and what is left unexplained. See [`capstan_engine::diagnose`].

use capstan_engine::diagnose::{self, Diagnosis, Options};
use capstan_engine::verdict::words::{self, fixed};
use std::fmt::Write as _;

/// Arguments of `capstan diagnose`.
#[derive(clap::Args, Debug)]
#[command(after_help = capstan_data::COLUMNS_HELP)]
pub struct Args {
    /// The pairs.
    #[command(flatten)]
    pub input: super::input::DataArgs,
    /// Print one JSON object instead of the summary.
    #[arg(long)]
    pub json: bool,
    /// How the steps are timed.
    #[command(flatten)]
    pub timing: super::input::TimingArgs,
    /// A within-run (shape) effect is reported when its ΔBIC is below minus this.
    #[arg(long, default_value_t = diagnose::WITHIN_THRESHOLD, allow_negative_numbers = true)]
    pub within_threshold: f64,
    /// A between-run or between-cord effect is reported when its ΔBIC is below minus this.
    #[arg(long, default_value_t = diagnose::BETWEEN_THRESHOLD, allow_negative_numbers = true)]
    pub between_threshold: f64,
}

/// Run `capstan diagnose`.
pub fn run(args: Args) -> anyhow::Result<()> {
    for (flag, v) in [
        ("--within-threshold", args.within_threshold),
        ("--between-threshold", args.between_threshold),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            anyhow::bail!("{flag} {v}: must be a finite number, 0 or more");
        }
    }
    let data = args.input.load()?;
    let data_warnings = super::check_data(&data)?;
    let opts = Options {
        within_threshold: args.within_threshold,
        between_threshold: args.between_threshold,
        protocol_times: args.timing.protocol_times,
        ..Options::default()
    };
    let mut d = diagnose::diagnose_with(&data, &opts);
    if args.json {
        // Where the answer came from, and what the data checks warned about, in the answer.
        d.provenance = Some(args.input.provenance()?);
        d.data.warnings = Some(data_warnings);
        crate::outln!("{}", d.to_json());
    } else {
        crate::out!("{}", summary(&d, &data.source));
    }
    Ok(())
}

/// The human summary: the verdict, the effects with their evidence, what is left, what
/// could not be tested.
pub fn summary(d: &Diagnosis, source: &str) -> String {
    let mut s = String::new();
    verdict_lines(&mut s, d, source);
    effect_lines(&mut s, d);
    fit_lines(&mut s, d);
    candidate_lines(&mut s, d);
    let _ = writeln!(
        s,
        "rows used: {} in the T2 fits, {} with T1 and T2 above zero for the logarithms",
        d.rows_used.t2_fits, d.rows_used.logarithms
    );
    let _ = writeln!(s, "({:.3} s)", d.elapsed_s);
    s
}

/// The data in one line, how they were read, the verdict and the diagnosis.
fn verdict_lines(s: &mut String, d: &Diagnosis, source: &str) {
    let g = &d.design;
    let _ = writeln!(
        s,
        "{source}: {} rows, {} cord{}, {} run{}; wraps {:?} deg, diameters {:?} mm, drive {:?} V",
        g.rows,
        g.cords,
        if g.cords == 1 { "" } else { "s" },
        g.runs,
        if g.runs == 1 { "" } else { "s" },
        g.wraps_deg,
        g.diameters_mm,
        g.drive_v
    );
    let _ = writeln!(s, "{}", d.data.structure.statement);
    let _ = writeln!(s, "{}", d.verdict);
    if d.unexplained {
        // The pattern the JSON gives, or none (sizes that differ by wrap, or an effect at the
        // edge of its range, say it in the verdict above).
        let pattern = d
            .residual_pattern
            .map_or(String::new(), |p| format!(" ({p})"));
        let _ = writeln!(s, "diagnosis: UNEXPLAINED{pattern}");
    } else if d.effects.is_empty() {
        let _ = writeln!(
            s,
            "diagnosis: none (no effect reaches ΔBIC {:.0} within runs or {:.0} between runs/cords)",
            d.thresholds.within_run, d.thresholds.between
        );
    } else {
        let names: Vec<&str> = d.effects.iter().map(|f| f.effect).collect();
        let _ = writeln!(s, "diagnosis: {}", names.join(" + "));
    }
}

/// Each effect found with its size and level, and the rivals not ruled out in its place.
fn effect_lines(s: &mut String, d: &Diagnosis) {
    for f in &d.effects {
        let _ = writeln!(
            s,
            "  {:<20} {}  [{}]",
            f.effect,
            words::effect_phrase(f),
            f.level.words()
        );
        for r in d.rivals.iter().filter(|r| r.instead_of == f.effect) {
            let _ = writeln!(
                s,
                "    or {:<17} set with it in its place: ΔBIC {:+.1} (not ruled out)",
                r.effect, r.delta_bic
            );
        }
    }
}

/// Euler-Eytelwein's and the effects' RMSE, and the scatter of mu and the noise.
fn fit_lines(s: &mut String, d: &Diagnosis) {
    let b = &d.baseline;
    let _ = writeln!(
        s,
        "Euler-Eytelwein: mu = {}, RMSE(T2) {} N with one mu, {} N with every run's own mu",
        fixed(b.mu, 4),
        fixed(b.rmse_t2_n, 3),
        fixed(b.rmse_t2_run_mu_n, 3)
    );
    if !d.effects.is_empty() {
        let _ = writeln!(
            s,
            "with the effects found: RMSE(T2) {} N with one mu, {} N with every run's own mu",
            fixed(d.extended.rmse_t2_n, 3),
            fixed(d.extended.rmse_t2_run_mu_n, 3)
        );
    }
    let sc = &d.scatter;
    let _ = writeln!(
        s,
        "scatter of mu: cord to cord {}, run to run {}; noise {} N + {} % of T2, lag-1 autocorrelation {}",
        percent_or(sc.cord_pct, "not estimable (one cord)"),
        percent_or(sc.run_pct, "not estimable (one run per cord)"),
        fixed(sc.noise_abs_n, 3),
        fixed(100.0 * sc.noise_rel, 2),
        if sc.lag1_autocorrelation.is_finite() {
            fixed(sc.lag1_autocorrelation, 2)
        } else {
            "not identified (no time order inside runs)".to_string()
        }
    );
}

/// "5.83 %", or why the spread could not be estimated.
fn percent_or(v: f64, why: &str) -> String {
    if v.is_finite() {
        format!("{v:.2} %")
    } else {
        why.to_string()
    }
}

/// Every candidate's evidence, then what could not be tested or identified.
fn candidate_lines(s: &mut String, d: &Diagnosis) {
    let _ = writeln!(
        s,
        "candidates (ΔBIC given the effects found; named if below the threshold of its level and large enough to matter):"
    );
    for c in &d.candidates {
        let value = c
            .parameters
            .iter()
            .next()
            .map_or("-".to_string(), |(k, v)| {
                if c.parameter_se.is_finite() {
                    format!("{k} = {v:.4e} ± {:.1e}", c.parameter_se)
                } else if let Some((lo, hi)) = c.edge_interval {
                    format!("{k} = {v:.4e} (at the edge of its range; 95 % interval {lo:.1e} to {hi:.1e})")
                } else {
                    format!("{k} = {v:.4e} (no standard error: one run, or at the edge of its range)")
                }
            });
        let _ = writeln!(
            s,
            "  {:<20} {:>10.1}  {value}  [{}]{}",
            c.effect,
            c.delta_bic,
            c.level.words(),
            if c.selected {
                "  found"
            } else if c.supported {
                "  supported"
            } else {
                ""
            }
        );
    }
    for n in &d.not_testable {
        let _ = writeln!(s, "  {:<20} not testable: {}", n.effect, n.reason);
    }
    for n in &d.adequacy.not_identified {
        let _ = writeln!(s, "  not identified: {n}");
    }
}
