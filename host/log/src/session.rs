//! One logging session: bytes in, decoded records routed to the files as they arrive, the run
//! under way and its set-up values tracked, progress handed to the caller as notes, and the
//! summary at the end. The setup-mode records, which belong to no run, are `setup`'s.

mod setup;

use super::files::{decimal, Files};
use super::summary::{RecordCounts, RunCalibration, RunSummary, Sourced, Summary, TruncatedTail};
use super::{LogOptions, Note, Outcome, Result, Stop, PAIRS_INCOMPLETE_CSV};
use capstan_data::Pair;
use capstan_link::decoder::{BadFrame, Decoder, Located};
use capstan_link::elf::{Firmware, RecordKind};
use capstan_link::frame::Event;
use capstan_link::seq::SeqEvent;
use capstan_rig::record::{Fault, RawSample, Record, RunEnd, RunStart, StepPair};

/// The run the records belong to: its entry in the summary's runs, and the set-up values its
/// pairs are written with.
#[derive(Clone, Copy)]
struct Current {
    index: usize,
    diameter: Option<f64>,
    wrap: Option<f64>,
    drive: Option<f64>,
}

/// Writes one session's files.
pub struct Logger<'f> {
    decoder: Decoder<'f>,
    opts: LogOptions,
    source: String,
    files: Files,
    counts: RecordCounts,
    runs: Vec<RunSummary>,
    current: Option<Current>,
    pairs_incomplete: u64,
    /// Complete runs: their run-end record arrived and no fault ended them.
    completed: usize,
    /// The rig is in setup mode as far as the records tell (`setup::keeps_setup`): a fault
    /// while no run is under way is a setup-mode fault, not the start of a run whose
    /// run_start was lost.
    in_setup: bool,
    events: Vec<Located>,
    bad: Vec<BadFrame>,
    /// The board's starts seen so far (1, then one more at every restart): the `boot` label
    /// of the pairs.
    boot: u32,
    /// What `summary.json` says made the session ([`Logger::set_provenance`]).
    provenance: Option<serde_json::Value>,
    /// A session a signal stopped replaces an earlier one ([`Logger::keep_interrupted_apart`]).
    interrupted_replaces: bool,
    /// Where the session's messages go as they arise.
    notes: Notes<'f>,
}

/// Where a session's [`Note`]s go as they arise (`capstan log` prints each on stderr).
pub type Notes<'f> = Box<dyn FnMut(Note) + 'f>;

/// Does this run-end record close a complete run? Only if no fault ended it: a run the
/// firmware stopped (the button's abort, a load at its tare, over-force, a broken cord, ...)
/// did not run its protocol to the end, whatever pairs it made before.
pub fn completes(e: &RunEnd) -> bool {
    e.fault.is_none()
}

/// A run number for messages: `?` when unknown.
fn or_unknown(run: &str) -> &str {
    if run.is_empty() {
        "?"
    } else {
        run
    }
}

impl<'f> Logger<'f> {
    /// Start a session into `opts.out_dir`; `source` names the byte source in the summary.
    /// What the session has to say goes to `notes` as it arises, from the opening of the
    /// directory on.
    pub fn create(
        fw: &'f Firmware,
        opts: LogOptions,
        source: &str,
        notes: Notes<'f>,
    ) -> Result<Self> {
        Self::with_decoder(Decoder::new(fw), opts, source, notes)
    }

    /// A session fed records already decoded ([`Logger::take_records`]): the simulated board,
    /// which runs the firmware's code on the host. Nothing is encoded, so there is no
    /// `stream.defmt` to keep: give it [`LogOptions::save_stream`] false.
    pub fn create_for_records(opts: LogOptions, source: &str, notes: Notes<'f>) -> Result<Self> {
        Self::with_decoder(Decoder::records_only(), opts, source, notes)
    }

    fn with_decoder(
        decoder: Decoder<'f>,
        opts: LogOptions,
        source: &str,
        mut notes: Notes<'f>,
    ) -> Result<Self> {
        Ok(Logger {
            decoder,
            files: Files::create(&opts, &mut notes)?,
            source: source.to_string(),
            opts,
            counts: RecordCounts::default(),
            runs: Vec::new(),
            current: None,
            pairs_incomplete: 0,
            completed: 0,
            in_setup: false,
            events: Vec::new(),
            bad: Vec::new(),
            boot: 1,
            provenance: None,
            interrupted_replaces: true,
            notes,
        })
    }

    /// A session a signal stops replaces no earlier session in the directory: it is kept
    /// beside it as `incomplete-<id>` (and becomes the directory's only where there was
    /// none). For a session that plans its runs (the simulated board's `--runs`), where a
    /// signal means "not all of them"; a board's session ends by a signal as a matter of
    /// course.
    pub fn keep_interrupted_apart(&mut self) {
        self.interrupted_replaces = false;
    }

    /// What made the session (program, commit, command line, the input's and the ELF's
    /// SHA-256), written into `summary.json`.
    pub fn set_provenance(&mut self, p: serde_json::Value) {
        self.provenance = Some(p);
    }

    /// Complete runs: their run-end record arrived and no fault ended them (what `--runs`
    /// counts, and what a session needs to replace an earlier one).
    pub fn completed_runs(&self) -> usize {
        self.completed
    }

    /// Bytes received so far.
    pub fn bytes_seen(&self) -> u64 {
        self.decoder.bytes_seen()
    }

    /// Take a chunk of the stream: decode it, write what it completes, flush every file.
    pub fn feed(&mut self, bytes: &[u8]) -> Result<()> {
        self.push(bytes)?;
        self.files.flush()
    }

    /// Take records already decoded, in order (a [`Logger::create_for_records`] session),
    /// written as [`Logger::push`] writes decoded ones; the files are flushed.
    pub fn take_records(&mut self, records: Vec<Event>) -> Result<()> {
        let mut events = std::mem::take(&mut self.events);
        self.decoder.push_records(records, &mut events);
        for e in events.drain(..) {
            self.handle(e)?;
        }
        self.events = events;
        self.files.flush()
    }

    /// Flush every file.
    pub fn flush(&mut self) -> Result<()> {
        self.files.flush()
    }

    /// [`Logger::feed`] without the flush (a chunk fed in pieces, flushed once).
    pub fn push(&mut self, bytes: &[u8]) -> Result<()> {
        self.files.stream(bytes)?;
        let mut events = std::mem::take(&mut self.events);
        let mut bad = std::mem::take(&mut self.bad);
        self.decoder.push(bytes, &mut events, &mut bad);
        for b in bad.drain(..) {
            if self.opts.progress {
                (self.notes)(Note::Session(format!(
                    "bad frame {} at byte {}: {}",
                    b.frame, b.byte_offset, b.reason
                )));
            }
        }
        for e in events.drain(..) {
            self.handle(e)?;
        }
        self.events = events;
        self.bad = bad;
        Ok(())
    }

    /// The run under way, opened as a run of unknown number if its run-start record was lost
    /// (or logging began mid-run). Returns it with its run number for the CSV (empty: unknown).
    fn current_run(&mut self, seq: u32) -> (Current, String) {
        if self.current.is_none() {
            let s = self.opts.setup;
            self.runs.push(RunSummary::new(
                None,
                seq,
                Sourced::choose(s.capstan_diameter_mm, None),
                Sourced::choose(s.wrap_deg, None),
                Sourced::choose(s.drive_v, None),
            ));
            self.current = Some(Current {
                index: self.runs.len() - 1,
                diameter: s.capstan_diameter_mm,
                wrap: s.wrap_deg,
                drive: s.drive_v,
            });
        }
        let c = self.current.expect("just set");
        let run = self.runs[c.index]
            .run
            .map_or(String::new(), |r| r.to_string());
        (c, run)
    }

    fn handle(&mut self, located: Located) -> Result<()> {
        match &located.seq {
            Some(SeqEvent::Gap(g)) if self.opts.progress => (self.notes)(Note::Session(format!(
                "LOST {} record(s) after seq {} (byte {})",
                g.missing, g.after_seq, g.byte_offset
            ))),
            Some(SeqEvent::Restart(r)) => {
                if self.opts.progress {
                    (self.notes)(Note::Session(format!(
                        "the board restarted after seq {} (byte {})",
                        r.after_seq, r.byte_offset
                    )));
                }
                self.current = None;
                self.boot += 1;
            }
            _ => {}
        }
        match located.event {
            Event::Message { level, text } => self.files.message(&level, &text),
            Event::Record { seq, record } => self.record(seq, &record),
        }
    }

    fn record(&mut self, seq: u32, record: &Record) -> Result<()> {
        let setup_fault = self.in_setup && self.current.is_none();
        self.in_setup = setup::keeps_setup(record, self.in_setup);
        match record {
            Record::RunStart(s) => {
                self.run_start(seq, s);
                Ok(())
            }
            Record::Raw(r) => self.raw(seq, r),
            Record::Pair(p) => self.pair(seq, p),
            Record::Fault(f) if setup_fault => self.setup_fault(seq, f),
            Record::Fault(f) => self.fault(seq, f),
            Record::RunEnd(e) => {
                self.run_end(seq, e);
                Ok(())
            }
            Record::Settings(r) => self.settings(seq, r),
            Record::Live(l) => self.live(seq, l),
            Record::Reply(r) => self.reply(seq, r),
        }
    }

    fn run_start(&mut self, seq: u32, s: &RunStart) {
        self.counts.run_start += 1;
        let flags = self.opts.setup;
        let p = &s.protocol;
        // 0 (or garbage) in the record means "not given".
        let given = |v: f32| (v.is_finite() && v > 0.0).then_some(decimal(v));
        let drive = s.calibration.amp.drive_v(p.amp_control_v);
        let mut summary = RunSummary::new(
            Some(s.run),
            seq,
            Sourced::choose(flags.capstan_diameter_mm, given(p.capstan_diameter_mm)),
            Sourced::choose(flags.wrap_deg, given(p.wrap_deg)),
            Sourced::choose(
                flags.drive_v,
                Some(decimal(drive)).filter(|v| v.is_finite()),
            ),
        );
        let fw = self.decoder.firmware();
        // Records decoded on the host (no firmware table) carry every field.
        let sent =
            |field: &str| fw.is_none_or(|fw| fw.record_has_field(RecordKind::RunStart, field));
        let settings = capstan_rig::Settings {
            protocol: s.protocol,
            calibration: s.calibration,
        };
        summary.calibration = Some(RunCalibration::of(&settings, sent));
        self.current = Some(Current {
            index: self.runs.len(),
            diameter: summary.capstan_diameter_mm.value,
            wrap: summary.wrap_deg.value,
            drive: summary.drive_v.value,
        });
        let missing: Vec<&str> = [
            ("--wrap-deg", summary.wrap_deg.value),
            ("--diameter-mm", summary.capstan_diameter_mm.value),
            ("--drive-v", summary.drive_v.value),
        ]
        .iter()
        .filter(|(_, v)| v.is_none())
        .map(|(flag, _)| *flag)
        .collect();
        self.runs.push(summary);
        if self.opts.progress {
            (self.notes)(Note::Session(format!(
                "run {} started (seq {seq}): {} levels, {} ms each",
                s.run,
                p.levels(),
                p.dwell_ms
            )));
            if !missing.is_empty() {
                // Said at once: the operator can still stop and restart with the flags.
                (self.notes)(Note::Session(format!(
                    "WARNING: run {}'s run_start record does not give {} and no \
                     flag does: its pairs go to {PAIRS_INCOMPLETE_CSV}",
                    s.run,
                    missing.join(", ")
                )));
            }
        }
    }

    fn raw(&mut self, seq: u32, r: &RawSample) -> Result<()> {
        self.counts.raw += 1;
        let (c, run) = self.current_run(seq);
        self.runs[c.index].raw += 1;
        self.files.raw(&run, seq, r)
    }

    fn pair(&mut self, seq: u32, p: &StepPair) -> Result<()> {
        self.counts.pair += 1;
        let progress = self.opts.progress;
        let (c, run) = self.current_run(seq);
        let rs = &mut self.runs[c.index];
        let pair = Pair {
            capstan_diameter_mm: c.diameter,
            // Unknown: an empty cell (the pair then goes to pairs-incomplete.csv).
            wrap_deg: c.wrap.unwrap_or(f64::NAN),
            drive_v: c.drive,
            run: rs.run.map(f64::from),
            step: Some(p.step as f64),
            time_s: Some(p.t_mid_ms as f64 / 1000.0),
            t1_n: decimal(p.t1.mean_n),
            t2_n: decimal(p.t2.mean_n),
            // Force control's target (0: none).
            extra: vec![decimal(p.t2_target_n)],
            labels: vec![self.boot.to_string()],
        };
        let complete =
            c.diameter.is_some() && c.wrap.is_some() && c.drive.is_some() && rs.run.is_some();
        rs.pairs += 1;
        if !(p.t1.mean_n.is_finite() && p.t2.mean_n.is_finite()) {
            rs.pairs_not_written += 1;
        } else if complete {
            self.files.pair(&pair)?;
        } else {
            // Every row of pairs.csv is complete, so `capstan analyze` reads it; the others
            // are kept apart, with the cells that are unknown left empty.
            rs.pairs_incomplete += 1;
            self.pairs_incomplete += 1;
            let run_unknown = rs.run.is_none();
            if self.files.open_incomplete()? && progress && run_unknown {
                (self.notes)(Note::Session(format!(
                    "WARNING: pairs without their run's run_start record (lost, \
                     or logging began mid-run): their run is unknown; they go to \
                     {PAIRS_INCOMPLETE_CSV}"
                )));
            }
            self.files.incomplete_pair(&pair)?;
        }
        if progress {
            (self.notes)(Note::Session(format!(
                "run {} step {}: T1 {} N, T2 {} N ({} samples)",
                or_unknown(&run),
                p.step,
                p.t1.mean_n,
                p.t2.mean_n,
                p.t1.count
            )));
        }
        Ok(())
    }

    fn fault(&mut self, seq: u32, flt: &Fault) -> Result<()> {
        self.counts.fault += 1;
        let (c, run) = self.current_run(seq);
        self.runs[c.index].faults += 1;
        self.files.fault(&run, seq, flt)?;
        if self.opts.progress {
            (self.notes)(Note::Session(format!(
                "FAULT {} at {} s (run {})",
                flt.kind.name(),
                flt.t_us as f64 / 1e6,
                or_unknown(&run)
            )));
        }
        Ok(())
    }

    fn run_end(&mut self, seq: u32, e: &RunEnd) {
        self.counts.run_end += 1;
        self.current_run(seq);
        let c = self.current.take().expect("set");
        let rs = &mut self.runs[c.index];
        if completes(e) && !rs.complete {
            self.completed += 1;
            rs.complete = true;
        }
        rs.ended = true;
        rs.pairs_reported = Some(e.pairs);
        rs.ended_by_fault = e.fault.map(|k| k.name());
        rs.end_time_s = Some(e.t_us as f64 / 1e6);
        if self.opts.progress {
            (self.notes)(Note::Session(format!(
                "run {} ended at {} s: {} pairs{}",
                rs.run.map_or("?".to_string(), |r| r.to_string()),
                e.t_us as f64 / 1e6,
                e.pairs,
                e.fault.map_or(String::new(), |k| format!(
                    ", fault {} (cut short: not a complete run)",
                    k.name()
                ))
            )));
        }
    }

    /// End the session: account for an unfinished frame, flush, write `summary.json`, and
    /// replace the directory's previous session with this one if it holds a complete run (or
    /// `allow_empty` was given); see [`Logger::finish_with`].
    pub fn finish(self, stop: &Stop) -> Result<Summary> {
        self.finish_with(stop).map(|(s, _)| s)
    }

    /// [`Logger::finish`], saying what became of the files: a session without a complete run
    /// replaces nothing (a good recorded session is irreplaceable); what it received is kept
    /// as `incomplete-<id>`, or dropped if nothing was.
    pub fn finish_with(mut self, stop: &Stop) -> Result<(Summary, Outcome)> {
        let tail = self.decoder.finish();
        self.files.flush()?;
        let d = &self.decoder;
        let summary = Summary {
            source: self.source.clone(),
            elf: d.firmware().map_or_else(
                || "(none: the simulated board)".to_string(),
                |f| f.path.clone(),
            ),
            stopped: stop.to_string(),
            bytes: d.bytes_seen(),
            frames: d.frames_seen,
            records: self.counts.clone(),
            messages: d.messages,
            first_seq: d.seq.first_seq,
            last_seq: d.seq.last_seq,
            missing_records: d.seq.missing_records,
            gaps: d.seq.gaps.clone(),
            restarts: d.seq.restarts.clone(),
            backwards: d.seq.backwards.clone(),
            bad_frames: d.bad_frames,
            bad_frame_examples: d.bad_examples.clone(),
            // A frame cut by the end of the stream (or a lost probe) is damage; one cut where we
            // chose to stop reading (a limit, Ctrl-C) is not.
            truncated_tail: tail
                .filter(|_| !matches!(stop, Stop::Interrupted(_) | Stop::Limit(_)))
                .map(|(byte_offset, bytes)| TruncatedTail { byte_offset, bytes }),
            runs: self.runs.clone(),
            pairs_incomplete: self.pairs_incomplete,
            provenance: self.provenance.clone(),
        };
        let json = serde_json::to_string_pretty(&summary).expect("summary serialises");
        let had_session = (self.opts.out_dir)
            .join(capstan_outdir::manifest_name("log"))
            .exists();
        let apart =
            matches!(stop, Stop::Interrupted(_)) && !self.interrupted_replaces && had_session;
        let commit = !apart && (self.opts.allow_empty || summary.runs.iter().any(|r| r.complete));
        let outcome = self.files.close(
            &(json + "\n"),
            commit,
            summary.bytes > 0 || summary.frames > 0,
        )?;
        Ok((summary, outcome))
    }
}
