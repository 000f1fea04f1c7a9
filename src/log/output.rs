//! The files a logged run leaves in its directory, written as the records arrive and flushed
//! after every chunk of the stream, so an interrupted session keeps everything decoded so far:
//!
//! | file | what |
//! |---|---|
//! | `raw.csv` | `run,seq,time_s,t1_counts,t2_counts,t1_n,t2_n`: the decimated raw samples |
//! | `pairs.csv` | the conditioned pairs, in the schema of `data.rs` (`analyze` reads it) |
//! | `pairs-incomplete.csv` | only if needed: pairs whose set-up (wrap, diameter, drive voltage) or run number is unknown, same schema with those cells empty |
//! | `faults.csv` | `run,seq,time_s,kind,channel,value` |
//! | `messages.txt` | the firmware's other log lines (`LEVEL text`) |
//! | `stream.defmt` | the bytes as received (for `capstan log --from`), unless read from a file |
//! | `summary.json` | counts, runs, sequence gaps, bad frames, why the session stopped |
//!
//! Times are seconds since the logger trigger's rising edge (negative before it).

use super::decoder::{BadFrame, Decoder, Located};
use super::elf::Firmware;
use super::seq::{Backwards, Gap, Restart, SeqEvent};
use super::stream::Event;
use crate::data::PAIRS_HEADER;
use anyhow::Context;
use firmware::hal::Channel;
use firmware::record::Record;
use serde::Serialize;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// File names in the output directory.
pub const RAW_CSV: &str = "raw.csv";
/// Conditioned pairs.
pub const PAIRS_CSV: &str = "pairs.csv";
/// Pairs that lack a set-up value or their run number (created only when one arrives).
pub const PAIRS_INCOMPLETE_CSV: &str = "pairs-incomplete.csv";
/// Faults.
pub const FAULTS_CSV: &str = "faults.csv";
/// Other log lines.
pub const MESSAGES_TXT: &str = "messages.txt";
/// The received bytes.
pub const STREAM_FILE: &str = "stream.defmt";
/// The summary.
pub const SUMMARY_JSON: &str = "summary.json";

/// Header of `raw.csv`.
pub const RAW_HEADER: &str = "run,seq,time_s,t1_counts,t2_counts,t1_n,t2_n";
/// Header of `faults.csv`.
pub const FAULTS_HEADER: &str = "run,seq,time_s,kind,channel,value";

/// Rig set-up given on the command line; each overrides the run-start record's value.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SetupFlags {
    /// Capstan diameter, mm.
    pub capstan_diameter_mm: Option<f64>,
    /// Wrap angle, deg.
    pub wrap_deg: Option<f64>,
    /// Drive-motor voltage, V.
    pub drive_v: Option<f64>,
}

/// How to log.
#[derive(Clone, Debug)]
pub struct LogOptions {
    /// Output directory (created if needed).
    pub out_dir: PathBuf,
    /// Replace files of an earlier session in `out_dir` (otherwise refuse).
    pub overwrite: bool,
    /// Keep a copy of the received bytes in `stream.defmt`.
    pub save_stream: bool,
    /// Set-up values for `pairs.csv`.
    pub setup: SetupFlags,
    /// Report runs, pairs, faults and gaps on stderr as they arrive.
    pub progress: bool,
}

/// Why a session ended.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Stop {
    /// The stream (file, pipe) ended.
    EndOfStream,
    /// Ctrl-C.
    Interrupted,
    /// The probe or the target stopped answering.
    ProbeLost(String),
    /// A limit given on the command line was reached.
    Limit(String),
}

impl std::fmt::Display for Stop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Stop::EndOfStream => f.write_str("end of stream"),
            Stop::Interrupted => f.write_str("interrupted (Ctrl-C)"),
            Stop::ProbeLost(e) => write!(f, "probe lost: {e}"),
            Stop::Limit(l) => write!(f, "limit reached: {l}"),
        }
    }
}

/// Where a set-up value of the pairs came from.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Sourced {
    /// The value written (`None`: the cell is empty).
    pub value: Option<f64>,
    /// `flag`, `run_start` or `unknown`.
    pub from: &'static str,
}

/// One run as the log saw it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RunSummary {
    /// Run number since boot (`None` if its run-start record was lost).
    pub run: Option<u32>,
    /// Sequence number of its first record seen.
    pub first_seq: u32,
    /// Its run-end record arrived.
    pub complete: bool,
    /// Raw samples received.
    pub raw: u64,
    /// Pairs received.
    pub pairs: u64,
    /// Pairs not written anywhere (a window without samples: mean is NaN).
    pub pairs_not_written: u64,
    /// Pairs written to pairs-incomplete.csv instead of pairs.csv.
    pub pairs_incomplete: u64,
    /// Pairs the run-end record says the rig made.
    pub pairs_reported: Option<u32>,
    /// Faults received.
    pub faults: u64,
    /// The fault that ended the run, if one did.
    pub ended_by_fault: Option<&'static str>,
    /// End time, s since the trigger.
    pub end_time_s: Option<f64>,
    /// Capstan diameter written to pairs.csv.
    pub capstan_diameter_mm: Sourced,
    /// Wrap angle written to pairs.csv.
    pub wrap_deg: Sourced,
    /// Drive voltage written to pairs.csv.
    pub drive_v: Sourced,
}

/// Counts by record kind.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct RecordCounts {
    /// run_start
    pub run_start: u64,
    /// raw
    pub raw: u64,
    /// pair
    pub pair: u64,
    /// fault
    pub fault: u64,
    /// run_end
    pub run_end: u64,
}

/// Everything `summary.json` says.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    /// Where the bytes came from.
    pub source: String,
    /// The ELF used to decode them.
    pub elf: String,
    /// Why the session ended.
    pub stopped: String,
    /// Bytes received.
    pub bytes: u64,
    /// Frames cut from them.
    pub frames: u64,
    /// Records decoded, by kind.
    pub records: RecordCounts,
    /// Other log lines.
    pub messages: u64,
    /// First and last sequence numbers seen.
    pub first_seq: Option<u32>,
    /// Last sequence number seen.
    pub last_seq: Option<u32>,
    /// Records known lost (sum over the gaps).
    pub missing_records: u64,
    /// Where records were lost.
    pub gaps: Vec<Gap>,
    /// Where the board restarted.
    pub restarts: Vec<Restart>,
    /// Records numbered below the expected one.
    pub backwards: Vec<Backwards>,
    /// Frames that did not decode.
    pub bad_frames: u64,
    /// The first of them, with the reason.
    pub bad_frame_examples: Vec<BadFrame>,
    /// An unfinished frame at the end of the stream: (byte offset, length).
    pub truncated_tail: Option<TruncatedTail>,
    /// The runs.
    pub runs: Vec<RunSummary>,
    /// Pairs written to pairs-incomplete.csv (unknown wrap, diameter, drive voltage or run).
    pub pairs_incomplete: u64,
}

/// An unfinished frame at the end of the stream.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct TruncatedTail {
    /// Byte offset of its start.
    pub byte_offset: u64,
    /// Its length.
    pub bytes: u64,
}

impl Summary {
    /// True if nothing was lost or damaged.
    pub fn is_clean(&self) -> bool {
        self.missing_records == 0
            && self.bad_frames == 0
            && self.truncated_tail.is_none()
            && self.backwards.is_empty()
    }

    /// The human report (a few lines, for stderr).
    pub fn human(&self, dir: &Path) -> String {
        let r = &self.records;
        let complete = self.runs.iter().filter(|r| r.complete).count();
        let mut s = format!(
            "capstan log: {} run(s) ({} complete), {} pairs, {} raw samples, {} faults, {} \
             messages from {} bytes ({}); files in {}",
            self.runs.len(),
            complete,
            r.pair,
            r.raw,
            r.fault,
            self.messages,
            self.bytes,
            self.stopped,
            dir.display()
        );
        if self.missing_records > 0 {
            let places: Vec<String> = self
                .gaps
                .iter()
                .take(5)
                .map(|g| {
                    format!(
                        "{} after seq {} (byte {})",
                        g.missing, g.after_seq, g.byte_offset
                    )
                })
                .collect();
            let more = if self.gaps.len() > 5 { ", ..." } else { "" };
            s += &format!(
                "\ncapstan log: LOST {} record(s) in {} gap(s): {}{more}",
                self.missing_records,
                self.gaps.len(),
                places.join("; ")
            );
        }
        if self.bad_frames > 0 {
            let first = &self.bad_frame_examples[0];
            s += &format!(
                "\ncapstan log: {} frame(s) did not decode; first: frame {} at byte {}: {}",
                self.bad_frames, first.frame, first.byte_offset, first.reason
            );
        }
        if let Some(t) = self.truncated_tail {
            s += &format!(
                "\ncapstan log: the stream ends inside a frame ({} bytes from byte {} dropped)",
                t.bytes, t.byte_offset
            );
        }
        for rs in &self.restarts {
            s += &format!(
                "\ncapstan log: the board restarted after seq {} (byte {})",
                rs.after_seq, rs.byte_offset
            );
        }
        if !self.backwards.is_empty() {
            s += &format!(
                "\ncapstan log: {} record(s) numbered out of order (first: seq {} where {} was expected)",
                self.backwards.len(),
                self.backwards[0].seq,
                self.backwards[0].expected_seq
            );
        }
        if let Some(first) = self.first_seq.filter(|&s| s != 0) {
            s += &format!(
                "\ncapstan log: the stream joins the board at seq {first}: records before it were \
                 sent before logging began"
            );
        }
        if self.pairs_incomplete > 0 {
            s += &format!(
                "\ncapstan log: {} pair(s) lack a set-up value or their run number and are in \
                 {PAIRS_INCOMPLETE_CSV}, not {PAIRS_CSV}; decode the stream again with \
                 --wrap-deg/--diameter-mm/--drive-v (capstan log --from {}/{STREAM_FILE} ...)",
                self.pairs_incomplete,
                dir.display()
            );
        }
        s
    }
}

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
    raw: BufWriter<File>,
    pairs: BufWriter<File>,
    faults: BufWriter<File>,
    messages: BufWriter<File>,
    stream: Option<BufWriter<File>>,
    counts: RecordCounts,
    runs: Vec<RunSummary>,
    current: Option<Current>,
    pairs_incomplete: u64,
    incomplete: Option<BufWriter<File>>,
    events: Vec<Located>,
    bad: Vec<BadFrame>,
}

fn create(dir: &Path, name: &str, header: Option<&str>) -> anyhow::Result<BufWriter<File>> {
    let path = dir.join(name);
    let file = File::create(&path).with_context(|| format!("cannot create {}", path.display()))?;
    let mut w = BufWriter::new(file);
    if let Some(h) = header {
        writeln!(w, "{h}").with_context(|| format!("cannot write {}", path.display()))?;
    }
    Ok(w)
}

fn opt(v: Option<f64>) -> String {
    v.map_or(String::new(), |v| v.to_string())
}

/// f32 as written: the shortest decimal that reads back to the same f32.
fn f(v: f32) -> String {
    v.to_string()
}

/// An f32 as the f64 of its shortest decimal (12.7f32 -> 12.7, not 12.699999809265137).
fn decimal(v: f32) -> f64 {
    v.to_string().parse().unwrap_or(f64::NAN)
}

impl<'f> Logger<'f> {
    /// Start a session into `opts.out_dir`; `source` names the byte source in the summary.
    pub fn create(fw: &'f Firmware, opts: LogOptions, source: &str) -> anyhow::Result<Self> {
        let dir = &opts.out_dir;
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create the output directory {}", dir.display()))?;
        if !opts.overwrite {
            let existing: Vec<&str> = [
                RAW_CSV,
                PAIRS_CSV,
                PAIRS_INCOMPLETE_CSV,
                FAULTS_CSV,
                SUMMARY_JSON,
                STREAM_FILE,
                MESSAGES_TXT,
            ]
            .into_iter()
            .filter(|n| dir.join(n).exists())
            .collect();
            if !existing.is_empty() {
                anyhow::bail!(
                    "{} already holds a logged session ({}): choose another --out, or pass \
                     --overwrite to replace it",
                    dir.display(),
                    existing.join(", ")
                );
            }
        }
        if opts.overwrite {
            // Files of the earlier session that this one may not write again.
            let stale = [
                Some(PAIRS_INCOMPLETE_CSV),
                (!opts.save_stream).then_some(STREAM_FILE),
            ];
            for name in stale.into_iter().flatten() {
                let path = dir.join(name);
                if path.exists() {
                    std::fs::remove_file(&path)
                        .with_context(|| format!("cannot remove {}", path.display()))?;
                }
            }
        }
        Ok(Logger {
            decoder: Decoder::new(fw),
            raw: create(dir, RAW_CSV, Some(RAW_HEADER))?,
            pairs: create(dir, PAIRS_CSV, Some(&PAIRS_HEADER.join(",")))?,
            faults: create(dir, FAULTS_CSV, Some(FAULTS_HEADER))?,
            messages: create(dir, MESSAGES_TXT, None)?,
            stream: if opts.save_stream {
                Some(create(dir, STREAM_FILE, None)?)
            } else {
                None
            },
            source: source.to_string(),
            opts,
            counts: RecordCounts::default(),
            runs: Vec::new(),
            current: None,
            pairs_incomplete: 0,
            incomplete: None,
            events: Vec::new(),
            bad: Vec::new(),
        })
    }

    /// Runs whose run-end record has arrived.
    pub fn completed_runs(&self) -> usize {
        self.runs.iter().filter(|r| r.complete).count()
    }

    /// Bytes received so far.
    pub fn bytes_seen(&self) -> u64 {
        self.decoder.bytes_seen()
    }

    /// Take a chunk of the stream: decode it, write what it completes, flush every file.
    pub fn feed(&mut self, bytes: &[u8]) -> anyhow::Result<()> {
        if let Some(s) = &mut self.stream {
            s.write_all(bytes).context("cannot write stream.defmt")?;
        }
        let mut events = std::mem::take(&mut self.events);
        let mut bad = std::mem::take(&mut self.bad);
        self.decoder.push(bytes, &mut events, &mut bad);
        for b in bad.drain(..) {
            if self.opts.progress {
                eprintln!(
                    "capstan log: bad frame {} at byte {}: {}",
                    b.frame, b.byte_offset, b.reason
                );
            }
        }
        for e in events.drain(..) {
            self.handle(e)?;
        }
        self.events = events;
        self.bad = bad;
        self.flush()
    }

    fn flush(&mut self) -> anyhow::Result<()> {
        let dir = self.opts.out_dir.display().to_string();
        for (w, name) in [
            (&mut self.raw, RAW_CSV),
            (&mut self.pairs, PAIRS_CSV),
            (&mut self.faults, FAULTS_CSV),
            (&mut self.messages, MESSAGES_TXT),
        ] {
            w.flush()
                .with_context(|| format!("cannot write {dir}/{name}"))?;
        }
        if let Some(s) = &mut self.stream {
            s.flush()
                .with_context(|| format!("cannot write {dir}/{STREAM_FILE}"))?;
        }
        if let Some(w) = &mut self.incomplete {
            w.flush()
                .with_context(|| format!("cannot write {dir}/{PAIRS_INCOMPLETE_CSV}"))?;
        }
        Ok(())
    }

    fn current_run(&mut self, seq: u32) -> &mut Current {
        if self.current.is_none() {
            // Records without a run start (it was lost, or logging began mid-run).
            let s = self.opts.setup;
            self.runs.push(RunSummary {
                run: None,
                first_seq: seq,
                complete: false,
                raw: 0,
                pairs: 0,
                pairs_not_written: 0,
                pairs_incomplete: 0,
                pairs_reported: None,
                faults: 0,
                ended_by_fault: None,
                end_time_s: None,
                capstan_diameter_mm: sourced(s.capstan_diameter_mm, None),
                wrap_deg: sourced(s.wrap_deg, None),
                drive_v: sourced(s.drive_v, None),
            });
            self.current = Some(Current {
                index: self.runs.len() - 1,
                diameter: s.capstan_diameter_mm,
                wrap: s.wrap_deg,
                drive: s.drive_v,
            });
        }
        self.current.as_mut().expect("just set")
    }

    fn handle(&mut self, located: Located) -> anyhow::Result<()> {
        let progress = self.opts.progress;
        match &located.seq {
            Some(SeqEvent::Gap(g)) if progress => eprintln!(
                "capstan log: LOST {} record(s) after seq {} (byte {})",
                g.missing, g.after_seq, g.byte_offset
            ),
            Some(SeqEvent::Restart(r)) => {
                if progress {
                    eprintln!(
                        "capstan log: the board restarted after seq {} (byte {})",
                        r.after_seq, r.byte_offset
                    );
                }
                self.current = None;
            }
            _ => {}
        }
        let (seq, record) = match located.event {
            Event::Message { level, text } => {
                writeln!(self.messages, "{level} {text}").context("cannot write messages.txt")?;
                return Ok(());
            }
            Event::Record { seq, record } => (seq, record),
        };
        let run_cell = |c: &Option<Current>, runs: &[RunSummary]| {
            c.as_ref()
                .and_then(|c| runs[c.index].run)
                .map_or(String::new(), |r| r.to_string())
        };
        match record {
            Record::RunStart(s) => {
                self.counts.run_start += 1;
                let flags = self.opts.setup;
                let p = &s.protocol;
                // 0 (or garbage) in the record means "not given".
                let given = |v: f32| (v.is_finite() && v > 0.0).then_some(decimal(v));
                let drive = s.calibration.amp.drive_v(p.amp_control_v);
                let summary = RunSummary {
                    run: Some(s.run),
                    first_seq: seq,
                    complete: false,
                    raw: 0,
                    pairs: 0,
                    pairs_not_written: 0,
                    pairs_incomplete: 0,
                    pairs_reported: None,
                    faults: 0,
                    ended_by_fault: None,
                    end_time_s: None,
                    capstan_diameter_mm: sourced(
                        flags.capstan_diameter_mm,
                        given(p.capstan_diameter_mm),
                    ),
                    wrap_deg: sourced(flags.wrap_deg, given(p.wrap_deg)),
                    drive_v: sourced(
                        flags.drive_v,
                        Some(decimal(drive)).filter(|v| v.is_finite()),
                    ),
                };
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
                if progress {
                    eprintln!(
                        "capstan log: run {} started (seq {seq}): {} levels, {} ms each",
                        s.run,
                        p.levels(),
                        p.dwell_ms
                    );
                }
                if progress && !missing.is_empty() {
                    // Said at once: the operator can still stop and restart with the flags.
                    eprintln!(
                        "capstan log: WARNING: run {}'s run_start record does not give {} and \
                         no flag does: its pairs go to {PAIRS_INCOMPLETE_CSV}",
                        s.run,
                        missing.join(", ")
                    );
                }
            }
            Record::Raw(r) => {
                self.counts.raw += 1;
                let run = {
                    self.current_run(seq);
                    run_cell(&self.current, &self.runs)
                };
                let c = self.current.as_ref().expect("set");
                self.runs[c.index].raw += 1;
                writeln!(
                    self.raw,
                    "{run},{seq},{},{},{},{},{}",
                    r.t_us as f64 / 1e6,
                    r.counts[0],
                    r.counts[1],
                    f(r.force_n[0]),
                    f(r.force_n[1])
                )
                .context("cannot write raw.csv")?;
            }
            Record::Pair(p) => {
                self.counts.pair += 1;
                self.current_run(seq);
                let run = run_cell(&self.current, &self.runs);
                let c = self.current.as_ref().expect("set");
                let rs = &mut self.runs[c.index];
                rs.pairs += 1;
                let row = format!(
                    "{},{},{},{run},{},{},{},{}",
                    opt(c.diameter),
                    opt(c.wrap),
                    opt(c.drive),
                    p.step,
                    p.t_mid_ms as f64 / 1000.0,
                    f(p.t1.mean_n),
                    f(p.t2.mean_n)
                );
                let complete = c.diameter.is_some()
                    && c.wrap.is_some()
                    && c.drive.is_some()
                    && rs.run.is_some();
                if !(p.t1.mean_n.is_finite() && p.t2.mean_n.is_finite()) {
                    rs.pairs_not_written += 1;
                } else if complete {
                    writeln!(self.pairs, "{row}").context("cannot write pairs.csv")?;
                } else {
                    // Every row of pairs.csv is complete, so `capstan analyze` reads it; the
                    // others are kept apart, with the cells that are unknown left empty.
                    rs.pairs_incomplete += 1;
                    self.pairs_incomplete += 1;
                    if self.incomplete.is_none() {
                        self.incomplete = Some(create(
                            &self.opts.out_dir,
                            PAIRS_INCOMPLETE_CSV,
                            Some(&PAIRS_HEADER.join(",")),
                        )?);
                        if progress && rs.run.is_none() {
                            eprintln!(
                                "capstan log: WARNING: pairs without their run's run_start \
                                 record (lost, or logging began mid-run): their run is unknown; \
                                 they go to {PAIRS_INCOMPLETE_CSV}"
                            );
                        }
                    }
                    let w = self.incomplete.as_mut().expect("just created");
                    writeln!(w, "{row}").context("cannot write pairs-incomplete.csv")?;
                }
                if progress {
                    eprintln!(
                        "capstan log: run {} step {}: T1 {} N, T2 {} N ({} samples)",
                        if run.is_empty() { "?" } else { &run },
                        p.step,
                        f(p.t1.mean_n),
                        f(p.t2.mean_n),
                        p.t1.count
                    );
                }
            }
            Record::Fault(flt) => {
                self.counts.fault += 1;
                self.current_run(seq);
                let run = run_cell(&self.current, &self.runs);
                let c = self.current.as_ref().expect("set");
                self.runs[c.index].faults += 1;
                let channel = match flt.channel {
                    Some(Channel::T1) => "t1",
                    Some(Channel::T2) => "t2",
                    None => "",
                };
                writeln!(
                    self.faults,
                    "{run},{seq},{},{},{channel},{}",
                    flt.t_us as f64 / 1e6,
                    flt.kind.name(),
                    f(flt.value)
                )
                .context("cannot write faults.csv")?;
                if progress {
                    eprintln!(
                        "capstan log: FAULT {} at {} s (run {})",
                        flt.kind.name(),
                        flt.t_us as f64 / 1e6,
                        if run.is_empty() { "?" } else { &run }
                    );
                }
            }
            Record::RunEnd(e) => {
                self.counts.run_end += 1;
                self.current_run(seq);
                let c = self.current.take().expect("set");
                let rs = &mut self.runs[c.index];
                rs.complete = true;
                rs.pairs_reported = Some(e.pairs);
                rs.ended_by_fault = e.fault.map(|k| k.name());
                rs.end_time_s = Some(e.t_us as f64 / 1e6);
                if progress {
                    eprintln!(
                        "capstan log: run {} ended at {} s: {} pairs{}",
                        rs.run.map_or("?".to_string(), |r| r.to_string()),
                        e.t_us as f64 / 1e6,
                        e.pairs,
                        e.fault
                            .map_or(String::new(), |k| format!(", fault {}", k.name()))
                    );
                }
            }
        }
        Ok(())
    }

    /// End the session: account for an unfinished frame, flush, write `summary.json`.
    pub fn finish(mut self, stop: &Stop) -> anyhow::Result<Summary> {
        let tail = self.decoder.finish();
        self.flush()?;
        let d = &self.decoder;
        let summary = Summary {
            source: self.source.clone(),
            elf: d_elf(&self.decoder),
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
            truncated_tail: tail.map(|(byte_offset, bytes)| TruncatedTail { byte_offset, bytes }),
            runs: self.runs.clone(),
            pairs_incomplete: self.pairs_incomplete,
        };
        let path = self.opts.out_dir.join(SUMMARY_JSON);
        let json = serde_json::to_string_pretty(&summary).expect("summary serialises");
        std::fs::write(&path, json + "\n")
            .with_context(|| format!("cannot write {}", path.display()))?;
        Ok(summary)
    }
}

fn d_elf(d: &Decoder) -> String {
    d.firmware().path.clone()
}

fn sourced(flag: Option<f64>, record: Option<f64>) -> Sourced {
    match (flag, record) {
        (Some(v), _) => Sourced {
            value: Some(v),
            from: "flag",
        },
        (None, Some(v)) => Sourced {
            value: Some(v),
            from: "run_start",
        },
        (None, None) => Sourced {
            value: None,
            from: "unknown",
        },
    }
}
