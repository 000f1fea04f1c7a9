//! `capstan condition RAW --out DIR`: a raw time series into the pairs CSV, by the firmware's
//! conditioning rules (`capstan_condition`): the options in, the files and the lines said out.

use anyhow::bail;
use capstan_condition::{output, Columns, ReadOptions, Request, Settings};
use std::path::PathBuf;
use std::time::Instant;

const AFTER_HELP: &str = "\
INPUTS (the columns it reads: a time and two tensions, T1 the servo side, T2 the fixed side)
  Our raw.csv (capstan log, capstan simulate's raw/: time_s, t1_n, t2_n, run), a logger's
  export, or Logger Pro's text export (File > Export As > Text: \"Vernier Format\" blocks,
  one per run). A logger's export may be separated by commas, semicolons, tabs or blanks,
  with decimal points or commas (1,5), a byte-order mark, any line ending, and a block of
  metadata above the header (a DAQ's `Logger,...` lines, LabVIEW's ***End_of_Header***):
  the header is the line above the first rows of numbers, or give it (--header-row N, or
  --skip-rows N lines before it). Logger Pro's \"Export as CSV\" puts runs side by side
  (`Run 1: Time (s)`, `Run 2: Time (s)`, ...): each block is its own run.
  The columns are found by name (time, t, X_Value; t1, force 1, force; t2, force 2), or
  named: --time-column, --t1-column, --t2-column take a header name (`Force 2`, with or
  without its unit; `Run 2: Time` for one run's column only) or a column number (1 = the
  first). Units from the header, `Force (N)`, `T1 [kgf]`, `t1_n`, `Time (ms)`, or a units
  line: s, ms, us, min, h; N, mN, kN, daN, gf, g, kgf, kg (a mass read as its weight),
  lbf, lb, ozf. Volts, counts and unknown units are refused by name: convert them first.

LEVELS
  By default the level changes are found from the tensions themselves (robust to noise,
  spikes and transients; any order: monotone, up-down, pulse). Or from the protocol:
  --first-change-s S --dwell-s S (the thesis: 10.5 after the trigger, 10), or from a trigger
  column (--trigger-column NAME: its rising edge is time zero). The rest before the first
  level and after the last gives no pair; each level's window is the firmware's: from
  --window-after-ms after the change to --window-before-ms before the next (2000 and 1000).

OUTPUTS (DIR)
  pairs.csv    the pairs, in the schema analyze reads
  levels.csv   every level: run, step, its segment and window (s), samples, means and sds,
               status (ok, or why no pair: a level never silently dropped)
  condition.json  what was read (format, columns, units) and done, with timings";

/// Arguments of `capstan condition`.
#[derive(clap::Args, Debug)]
#[command(after_long_help = AFTER_HELP)]
pub struct Args {
    /// The raw time series.
    #[arg(value_name = "RAW")]
    pub raw: PathBuf,
    /// Output directory.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// The time column: its header name (with or without the unit; `Run 2: Time` for one
    /// run's) or its number (1 = the first column).
    #[arg(long, value_name = "NAME|N")]
    pub time_column: Option<String>,
    /// The T1 column (the servo side), by name or number.
    #[arg(long, value_name = "NAME|N")]
    pub t1_column: Option<String>,
    /// The T2 column (the fixed side), by name or number.
    #[arg(long, value_name = "NAME|N")]
    pub t2_column: Option<String>,
    /// A logger trigger column: its first rising edge is the run's time zero.
    #[arg(long, value_name = "NAME|N")]
    pub trigger_column: Option<String>,
    /// The run-number column [default: a column named `run`, if any]; its rows need not be
    /// together (each run's rows are gathered).
    #[arg(long, value_name = "NAME|N")]
    pub run_column: Option<String>,
    /// Lines to pass before the header (a logger's metadata block) [default: found].
    #[arg(long, value_name = "N", conflicts_with = "header_row")]
    pub skip_rows: Option<usize>,
    /// The header's line number (1 = the first line) [default: found: the line above the
    /// first rows of numbers].
    #[arg(long, value_name = "LINE")]
    pub header_row: Option<usize>,
    /// Protocol: the first level change (rest to level 1), s of the file's time (or after the
    /// trigger's edge; default there the firmware's 10.5). With --dwell-s: the levels from the
    /// protocol, not found.
    #[arg(
        long,
        value_name = "S",
        requires = "dwell_s",
        allow_negative_numbers = true
    )]
    pub first_change_s: Option<f64>,
    /// Protocol: time each level is held, s.
    #[arg(long, value_name = "S")]
    pub dwell_s: Option<f64>,
    /// Levels per run [default: the firmware protocol's, 12]; found from the tensions, a
    /// different count is reported as a level not found. At least 1.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub levels: Option<u32>,
    /// Shortest time between two level changes when finding them, s.
    #[arg(long, value_name = "S", default_value_t = 3.0)]
    pub min_dwell_s: f64,
    /// The window starts this long after a change, ms [default: the firmware's, 2000].
    #[arg(long, value_name = "MS")]
    pub window_after_ms: Option<u32>,
    /// The window ends this long before the next change, ms [default: the firmware's, 1000].
    #[arg(long, value_name = "MS")]
    pub window_before_ms: Option<u32>,
    /// Wrap angle for the pairs, deg (an export does not say it).
    #[arg(long, value_name = "DEG", allow_negative_numbers = true)]
    pub wrap_deg: f64,
    /// Capstan diameter for the pairs, mm.
    #[arg(long, value_name = "MM", allow_negative_numbers = true)]
    pub diameter_mm: Option<f64>,
    /// Drive voltage for the pairs, V (0 to the rig's 13.2 V).
    #[arg(long, value_name = "V", allow_negative_numbers = true)]
    pub drive_v: Option<f64>,
    /// The first run's number, from 1 (runs the file does not number count up from it).
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub run: u32,
    /// Print one JSON object (condition.json) on stdout.
    #[arg(long)]
    pub json: bool,
}

/// What the options ask the conditioning for.
fn request(a: &Args) -> Request {
    Request {
        first_change_s: a.first_change_s,
        dwell_s: a.dwell_s,
        trigger: a.trigger_column.is_some(),
        levels: a.levels,
        min_dwell_s: a.min_dwell_s,
        window_after_ms: a.window_after_ms,
        window_before_ms: a.window_before_ms,
        wrap_deg: a.wrap_deg,
        diameter_mm: a.diameter_mm,
        drive_v: crate::cli::predict::limits::recorded_drive(a.drive_v),
        first_run: a.run,
    }
}

/// How the options ask the file to be read.
fn read_options(a: &Args) -> ReadOptions {
    ReadOptions {
        columns: Columns {
            time: a.time_column.clone(),
            t1: a.t1_column.clone(),
            t2: a.t2_column.clone(),
            trigger: a.trigger_column.clone(),
            run: a.run_column.clone(),
        },
        skip_rows: a.skip_rows,
        header_row: a.header_row,
    }
}

/// Run `capstan condition`.
pub fn run(a: Args) -> anyhow::Result<()> {
    let t0 = Instant::now();
    // The rig's drive range first: it is narrower than the data's, so a negative or
    // infinite voltage is refused in the rig's words, as a too high one.
    if let Some(v) = a.drive_v {
        let limits = crate::cli::predict::limits::RigLimits::firmware_defaults();
        limits.check_drive_for(v, "the pairs would record a drive the rig cannot run")?;
    }
    let set = Settings::from_request(&request(&a))?;
    let names = ["pairs.csv", "levels.csv", "condition.json"];
    let mut out = crate::outputs::open_out(&a.out, "condition", &names)?.stage()?;
    let c = capstan_condition::condition_file(&a.raw, &read_options(&a), &set)?;
    let mut csv = Vec::new();
    capstan_data::write_pairs_to(&mut csv, &c.pairs)?;
    out.write("pairs.csv", &csv)?;
    out.write("levels.csv", output::levels_csv(&c.runs).as_bytes())?;
    let not_found = c.not_found();
    let json = serde_json::json!({
        "source": a.raw.display().to_string(),
        "provenance": crate::provenance::of_input(Some(&a.raw))?,
        "format": c.layout.format,
        "read": &c.layout,
        "columns": &c.layout.used,
        "placement": format!("{:?}", set.placement),
        "window_after_s": set.window_after_s,
        "window_before_s": set.window_before_s,
        "runs": c.runs,
        "pairs": c.pairs.len(),
        "problems": not_found,
        "elapsed": {"read_s": c.read_s, "condition_s": c.condition_s, "total_s": t0.elapsed().as_secs_f64()},
    });
    out.write(
        "condition.json",
        serde_json::to_string_pretty(&json)?.as_bytes(),
    )?;
    out.commit()?;
    let said = output::read_lines(&a.raw, &c.layout)
        .into_iter()
        .chain(output::run_lines(&c.runs));
    for line in said {
        crate::errln!("{line}");
    }
    crate::errln!(
        "{} pairs -> {}",
        c.pairs.len(),
        a.out.join("pairs.csv").display()
    );
    if a.json {
        crate::outln!("{}", serde_json::to_string_pretty(&json)?);
    }
    if not_found > 0 {
        bail!(
            "{not_found} level(s) or run(s) not found (see above and {}/levels.csv); the pairs \
             found are in {}/pairs.csv",
            a.out.display(),
            a.out.display()
        );
    }
    Ok(())
}
