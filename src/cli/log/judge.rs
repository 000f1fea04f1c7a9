//! `capstan log`'s judgement of its own command line and of a session: the arguments
//! against the physical ranges before anything is opened, and the exit status and message a
//! session ends with (committed or not, strict, probe lost).

use super::Args;
use anyhow::bail;
use capstan_log::{Outcome, Stop, Summary};

/// The command line's values against the physical ranges (`data::ranges`; `--drive-v`
/// against the rig's drive), and `--from` checked, before anything is opened or written.
pub(super) fn check_args(args: &Args) -> anyhow::Result<()> {
    use capstan_data::ranges;
    if let Some(d) = args.duration {
        ranges::LOG_DURATION_S.option("--duration", d)?;
    }
    for (flag, v, r) in [
        ("--diameter-mm", args.diameter_mm, &ranges::DIAMETER_MM),
        ("--wrap-deg", args.wrap_deg, &ranges::WRAP_DEG),
    ] {
        if let Some(v) = v {
            r.option(flag, v)?;
        }
    }
    // The drive voltage recorded into the pairs: one the rig's drive gives (narrower than the
    // data's range), as `condition` and `predict` check it.
    if let Some(v) = args.drive_v {
        let limits = crate::cli::predict::limits::RigLimits::firmware_defaults();
        limits.check_drive_for(v, "pairs.csv would record a drive the rig cannot run")?;
    }
    if let Some(board) = &args.sim.sim {
        let (b, o) = (absolute(board), absolute(&args.out));
        if o.starts_with(&b) || b.starts_with(&o) {
            bail!(
                "--out {} and --sim {}: the session would be written into the simulated \
                 board's directory, or the board's into the session's; choose another --out",
                args.out.display(),
                board.display()
            );
        }
    }
    if args.runs == Some(0) {
        bail!("--runs 0: must be 1 or more (the number of complete runs to log)");
    }
    if args.sim.sim.is_some() {
        super::sim::check(args)?;
    }
    let Some(from) = args.from.as_deref().filter(|f| *f != "-") else {
        return Ok(());
    };
    if std::path::Path::new(from).is_dir() {
        bail!("--from {from} is a directory: give the saved stream file (e.g. DIR/stream.defmt)");
    }
    let inside = std::fs::canonicalize(from).ok().and_then(|f| {
        let out = std::fs::canonicalize(&args.out).ok()?;
        Some(f == out.join(capstan_log::STREAM_FILE))
    });
    if inside == Some(true) {
        bail!(
            "--from {from} is the saved stream of the session in --out {}: decoding it \
             there would replace it; choose another --out",
            args.out.display()
        );
    }
    Ok(())
}

/// The path as the file system resolves it (symbolic links followed where it exists).
fn absolute(p: &std::path::Path) -> std::path::PathBuf {
    std::fs::canonicalize(p)
        .or_else(|_| std::path::absolute(p))
        .unwrap_or_else(|_| p.to_path_buf())
}

/// A session without a complete run: it replaced nothing; say why, where what was received
/// is, and what to do.
pub(super) fn not_committed(
    summary: &Summary,
    stop: &Stop,
    outcome: &Outcome,
    args: &Args,
) -> anyhow::Result<()> {
    let dir = args.out.display();
    let complete = summary.runs.iter().filter(|r| r.complete).count();
    if let (Stop::Interrupted(why), Outcome::Kept(p), true) = (stop, outcome, complete > 0) {
        // A planned session (the simulated board's --runs) stopped short: it replaces no
        // earlier session.
        return Err(crate::cli::signal::Interrupted(format!(
            "interrupted ({why}) after {complete} complete run(s): they are kept in {}; {dir} \
             is as it was (a session stopped short does not replace the one there)",
            p.display()
        ))
        .into());
    }
    let why = if summary.bytes == 0 && summary.records.total() == 0 {
        "nothing was received".to_string()
    } else if summary.records.total() == 0 {
        format!(
            "no rig records in {} bytes ({} frames, {} did not decode): is the stream from the \
             firmware built as {}?",
            summary.bytes,
            summary.frames,
            summary.bad_frames,
            super::elf_name(args)
        )
    } else {
        let faulted: Vec<String> = (summary.runs.iter())
            .filter_map(|r| {
                let run = r.run.map_or("?".to_string(), |n| n.to_string());
                Some(format!(
                    "run {run} was cut short by the fault {}",
                    r.ended_by_fault?
                ))
            })
            .collect();
        let cut = if faulted.is_empty() {
            String::new()
        } else {
            format!(": {}", faulted.join(", "))
        };
        format!(
            "no complete run in {} records{cut} (a complete run ends with its run_end record, \
             and no fault ended it)",
            summary.records.total()
        )
    };
    let kept = match outcome {
        Outcome::Kept(p) => format!("what was received is kept in {}", p.display()),
        _ => "nothing was kept".to_string(),
    };
    let msg = format!(
        "{why}; {dir} is as it was (a session replaces files only with a complete run), {kept}; \
         pass --allow-empty to keep such a session as {dir}'s files"
    );
    if let Stop::ProbeLost(e) = stop {
        bail!("lost the probe while logging ({e}): {msg}");
    }
    if matches!(stop, Stop::Interrupted(_)) {
        return Err(crate::cli::signal::Interrupted(format!("interrupted: {msg}")).into());
    }
    bail!("{msg}")
}

pub(super) fn verdict(summary: &Summary, stop: &Stop, args: &Args) -> anyhow::Result<()> {
    let dir = args.out.display();
    if let Stop::ProbeLost(e) = stop {
        bail!("lost the probe while logging ({e}); everything received until then is in {dir}");
    }
    if summary.records.total() == 0 && summary.bytes > 0 {
        bail!(
            "no rig records in {} bytes ({} frames, {} did not decode): is the stream from the \
             firmware built as {}?",
            summary.bytes,
            summary.frames,
            summary.bad_frames,
            super::elf_name(args)
        );
    }
    if args.strict && summary.bytes == 0 && summary.records.total() == 0 {
        bail!("--strict: the stream is empty (no byte received)");
    }
    if args.strict && summary.runs.iter().all(|r| !r.complete) {
        bail!("--strict: no complete run in the stream (see {dir}/summary.json)");
    }
    if args.strict && !summary.is_clean() {
        bail!(
            "--strict: {} record(s) lost, {} bad frame(s){} (see {dir}/summary.json)",
            summary.missing_records,
            summary.bad_frames,
            if summary.truncated_tail.is_some() {
                ", stream truncated"
            } else {
                ""
            }
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use capstan_log::RecordCounts;
    use clap::Parser;

    fn summary(records: RecordCounts, bytes: u64, missing: u64) -> Summary {
        Summary {
            source: "test".into(),
            elf: "fw.elf".into(),
            stopped: "end of stream".into(),
            bytes,
            frames: 3,
            records,
            messages: 0,
            first_seq: Some(0),
            last_seq: Some(9),
            missing_records: missing,
            gaps: Vec::new(),
            restarts: Vec::new(),
            backwards: Vec::new(),
            bad_frames: 0,
            bad_frame_examples: Vec::new(),
            truncated_tail: None,
            runs: vec![complete_run()],
            pairs_incomplete: 0,
            provenance: None,
        }
    }

    fn complete_run() -> capstan_log::RunSummary {
        use capstan_log::{RunSummary, Sourced};
        let mut r = RunSummary::new(
            Some(1),
            0,
            Sourced::choose(None, None),
            Sourced::choose(None, None),
            Sourced::choose(None, None),
        );
        r.complete = true;
        r
    }

    fn args(extra: &[&str]) -> Args {
        let mut argv = vec![
            "capstan", "log", "--elf", "fw.elf", "--out", "d", "--from", "-",
        ];
        argv.extend(extra);
        match crate::cli::Cli::parse_from(argv).command {
            crate::cli::Command::Log(a) => a,
            _ => unreachable!(),
        }
    }

    #[test]
    fn exit_status_says_what_went_wrong() {
        let some = RecordCounts {
            raw: 10,
            ..RecordCounts::default()
        };
        let ok = summary(some.clone(), 100, 0);
        assert!(verdict(&ok, &Stop::EndOfStream, &args(&[])).is_ok());
        assert!(verdict(&ok, &Stop::Interrupted("Ctrl-C"), &args(&[])).is_ok());
        let lost = verdict(&ok, &Stop::ProbeLost("USB gone".into()), &args(&[]));
        assert!(lost
            .unwrap_err()
            .to_string()
            .contains("lost the probe while logging (USB gone)"));
        let gaps = summary(some, 100, 2);
        assert!(verdict(&gaps, &Stop::EndOfStream, &args(&[])).is_ok());
        let strict = verdict(&gaps, &Stop::EndOfStream, &args(&["--strict"]));
        assert!(strict.unwrap_err().to_string().contains("2 record(s) lost"));
        let none = summary(RecordCounts::default(), 100, 0);
        let e = verdict(&none, &Stop::EndOfStream, &args(&[])).unwrap_err();
        assert!(e.to_string().contains("no rig records in 100 bytes"));
        // A session committed without a complete run (only with --allow-empty: otherwise
        // `not_committed` judges it) is not an error, except under --strict.
        let empty = summary(RecordCounts::default(), 0, 0);
        assert!(verdict(&empty, &Stop::EndOfStream, &args(&[])).is_ok());
        let e = verdict(&empty, &Stop::EndOfStream, &args(&["--strict"])).unwrap_err();
        assert!(e.to_string().contains("the stream is empty"), "{e}");
        let mut unfinished = summary(
            RecordCounts {
                raw: 10,
                ..RecordCounts::default()
            },
            100,
            0,
        );
        unfinished.runs[0].complete = false;
        assert!(verdict(&unfinished, &Stop::EndOfStream, &args(&[])).is_ok());
        let e = verdict(&unfinished, &Stop::EndOfStream, &args(&["--strict"])).unwrap_err();
        assert!(e.to_string().contains("no complete run"), "{e}");
    }
}
