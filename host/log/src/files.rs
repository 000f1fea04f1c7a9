//! The session's files and their rows: the CSV writers (raw samples, faults, and the pairs
//! through `data::PairsWriter`, the same schema `simulate` writes and `analyze` reads), the
//! firmware's other log lines and the received bytes. Nothing here decides what goes where;
//! the session does.

use super::{
    LogError, LogOptions, Note, Result, FAULTS_CSV, FAULTS_HEADER, LIVE_CSV, LIVE_HEADER,
    MESSAGES_TXT, PAIRS_CSV, PAIRS_INCOMPLETE_CSV, RAW_CSV, RAW_HEADER, SETTINGS_CSV, STREAM_FILE,
    SUMMARY_JSON,
};
use capstan_data::{Pair, PairsWriter};
use capstan_link::words::{setting_values, source_name};
use capstan_outdir::{OutputDir, Staged};
use capstan_rig::hal::Channel;
use capstan_rig::record::{Fault, Live, RawSample, SettingsReport};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::PathBuf;

/// The open files of one session: an output set (`outdir`) whose files grow as the records
/// arrive, flushed after every chunk, and replace the previous session's when it closes. If
/// the process dies, the next run into the directory keeps them as `incomplete-*`.
pub(super) struct Files {
    set: Staged,
    dir: PathBuf,
    raw: BufWriter<File>,
    pairs: PairsWriter<BufWriter<File>>,
    faults: BufWriter<File>,
    messages: BufWriter<File>,
    stream: Option<BufWriter<File>>,
    /// `pairs-incomplete.csv`, created when its first row arrives.
    incomplete: Option<PairsWriter<BufWriter<File>>>,
    /// `settings.csv`, created when its first row arrives.
    settings: Option<BufWriter<File>>,
    /// `live.csv`, created when its first row arrives.
    live: Option<BufWriter<File>>,
}

fn create(set: &mut Staged, name: &str, header: Option<&str>) -> Result<BufWriter<File>> {
    let mut w = set.create(name).map_err(LogError::dir)?;
    if let Some(h) = header {
        writeln!(w, "{h}").map_err(|e| LogError::write(name, e))?;
    }
    Ok(w)
}

/// A pairs CSV of the session: the schema's columns, `t2_target_n` (force control's target,
/// 0 where there is none) and `boot`, the board's start each run belongs to (a reset starts the
/// run numbers again; `boot` keeps those runs apart for the reader).
fn create_pairs(set: &mut Staged, name: &str) -> Result<PairsWriter<BufWriter<File>>> {
    let w = create(set, name, None)?;
    PairsWriter::with_extra(w, &["t2_target_n"], &["boot"]).map_err(|e| LogError::write(name, e))
}

/// f32 as written: the shortest decimal that reads back to the same f32.
fn f(v: f32) -> String {
    v.to_string()
}

/// An f32 as the f64 of its shortest decimal (12.7f32 -> 12.7, not 12.699999809265137). Written
/// as an f64, it is the same shortest decimal again.
pub(super) fn decimal(v: f32) -> f64 {
    v.to_string().parse().unwrap_or(f64::NAN)
}

impl Files {
    /// Create (or, with `overwrite`, replace) the session's files in `opts.out_dir`. Refuses a
    /// directory that holds another session's files unless `overwrite` is set. What opening
    /// the directory recovered is told to `note`.
    pub fn create(opts: &LogOptions, note: &mut dyn FnMut(Note)) -> Result<Files> {
        let dir = &opts.out_dir;
        let names = [
            RAW_CSV,
            PAIRS_CSV,
            PAIRS_INCOMPLETE_CSV,
            FAULTS_CSV,
            SETTINGS_CSV,
            LIVE_CSV,
            SUMMARY_JSON,
            STREAM_FILE,
            MESSAGES_TXT,
        ];
        // Locked and recovered first, so the check sees what is really there.
        let out = OutputDir::open(dir, "log", &names).map_err(LogError::dir)?;
        for r in &out.recovered {
            note(Note::Recovered(r.to_string()));
        }
        if !opts.overwrite {
            let existing: Vec<&str> = names.into_iter().filter(|n| dir.join(n).exists()).collect();
            if !existing.is_empty() {
                return Err(LogError::AlreadyLogged {
                    dir: dir.clone(),
                    existing,
                });
            }
        }
        let mut set = out.stage().map_err(LogError::dir)?;
        set.keep_on_failure(opts.kept_after_failure);
        Ok(Files {
            raw: create(&mut set, RAW_CSV, Some(RAW_HEADER))?,
            pairs: create_pairs(&mut set, PAIRS_CSV)?,
            faults: create(&mut set, FAULTS_CSV, Some(FAULTS_HEADER))?,
            messages: create(&mut set, MESSAGES_TXT, None)?,
            stream: if opts.save_stream {
                Some(create(&mut set, STREAM_FILE, None)?)
            } else {
                None
            },
            incomplete: None,
            settings: None,
            live: None,
            set,
            dir: dir.clone(),
        })
    }

    /// Keep received bytes (if the session keeps them).
    pub fn stream(&mut self, bytes: &[u8]) -> Result<()> {
        if let Some(s) = &mut self.stream {
            s.write_all(bytes)
                .map_err(|e| LogError::write(self.at("stream.defmt"), e))?;
        }
        Ok(())
    }

    /// One of the firmware's other log lines.
    pub fn message(&mut self, level: &str, text: &str) -> Result<()> {
        writeln!(self.messages, "{level} {text}")
            .map_err(|e| LogError::write(self.at("messages.txt"), e))
    }

    /// A raw sample of run `run` (empty: unknown).
    pub fn raw(&mut self, run: &str, seq: u32, r: &RawSample) -> Result<()> {
        writeln!(
            self.raw,
            "{run},{seq},{},{},{},{},{},{}",
            r.t_us as f64 / 1e6,
            r.counts[0],
            r.counts[1],
            f(r.force_n[0]),
            f(r.force_n[1]),
            f(r.t2_target_n)
        )
        .map_err(|e| LogError::write(self.at("raw.csv"), e))
    }

    /// A fault of run `run` (empty: unknown).
    pub fn fault(&mut self, run: &str, seq: u32, flt: &Fault) -> Result<()> {
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
        .map_err(|e| LogError::write(self.at("faults.csv"), e))
    }

    /// A complete pair, to `pairs.csv`.
    pub fn pair(&mut self, p: &Pair) -> Result<()> {
        self.pairs
            .write(p)
            .map_err(|e| LogError::write(self.at("pairs.csv"), e))
    }

    /// Make sure `pairs-incomplete.csv` exists; true if this call created it.
    pub fn open_incomplete(&mut self) -> Result<bool> {
        if self.incomplete.is_some() {
            return Ok(false);
        }
        self.incomplete = Some(create_pairs(&mut self.set, PAIRS_INCOMPLETE_CSV)?);
        Ok(true)
    }

    /// A pair lacking a set-up value or its run number, to `pairs-incomplete.csv` (opened by
    /// [`Files::open_incomplete`]).
    pub fn incomplete_pair(&mut self, p: &Pair) -> Result<()> {
        let w = self.incomplete.as_mut().expect("opened first");
        w.write(p)
            .map_err(|e| LogError::write(self.at("pairs-incomplete.csv"), e))
    }

    /// A settings report, to `settings.csv` (created with its header by the first).
    pub fn settings(&mut self, seq: u32, r: &SettingsReport) -> Result<()> {
        let values = setting_values(&r.settings);
        if self.settings.is_none() {
            let names: Vec<&str> = values.iter().map(|v| v.name).collect();
            let header = format!("seq,source,{}", names.join(","));
            self.settings = Some(create(&mut self.set, SETTINGS_CSV, Some(&header))?);
        }
        let w = self.settings.as_mut().expect("just created");
        let cells: Vec<&str> = values.iter().map(|v| v.value.as_str()).collect();
        writeln!(w, "{seq},{},{}", source_name(r.source), cells.join(","))
            .map_err(|e| LogError::write(self.at("settings.csv"), e))
    }

    /// A live reading of setup mode, to `live.csv` (created with its header by the first).
    pub fn live(&mut self, seq: u32, l: &Live) -> Result<()> {
        if self.live.is_none() {
            self.live = Some(create(&mut self.set, LIVE_CSV, Some(LIVE_HEADER))?);
        }
        let w = self.live.as_mut().expect("just created");
        writeln!(
            w,
            "{seq},{},{},{},{},{},{}",
            l.t_ms as f64 / 1e3,
            l.counts[0],
            l.counts[1],
            f(l.force_n[0]),
            f(l.force_n[1]),
            f(l.servo_deg)
        )
        .map_err(|e| LogError::write(self.at("live.csv"), e))
    }

    /// The file of a failed write of `name`: the final path, where the user looks.
    fn at(&self, name: &str) -> String {
        self.dir.join(name).display().to_string()
    }

    /// Flush every file.
    pub fn flush(&mut self) -> Result<()> {
        let dir = self.dir.display().to_string();
        let at = |name: &str| format!("{dir}/{name}");
        self.raw
            .flush()
            .map_err(|e| LogError::write(at(RAW_CSV), e))?;
        self.pairs
            .flush()
            .map_err(|e| LogError::write(at(PAIRS_CSV), e))?;
        self.faults
            .flush()
            .map_err(|e| LogError::write(at(FAULTS_CSV), e))?;
        self.messages
            .flush()
            .map_err(|e| LogError::write(at(MESSAGES_TXT), e))?;
        if let Some(s) = &mut self.stream {
            s.flush().map_err(|e| LogError::write(at(STREAM_FILE), e))?;
        }
        if let Some(w) = &mut self.incomplete {
            w.flush()
                .map_err(|e| LogError::write(at(PAIRS_INCOMPLETE_CSV), e))?;
        }
        if let Some(w) = &mut self.settings {
            w.flush()
                .map_err(|e| LogError::write(at(SETTINGS_CSV), e))?;
        }
        if let Some(w) = &mut self.live {
            w.flush().map_err(|e| LogError::write(at(LIVE_CSV), e))?;
        }
        Ok(())
    }

    /// Close the session: flush, add `summary.json`, and, if `commit`, replace the previous
    /// session's files; otherwise keep the files apart (if `received` anything) or drop them.
    pub fn close(
        mut self,
        summary_json: &str,
        commit: bool,
        received: bool,
    ) -> Result<super::Outcome> {
        self.flush()?;
        drop((
            self.raw,
            self.pairs,
            self.faults,
            self.messages,
            self.stream,
            self.incomplete,
            self.settings,
            self.live,
        ));
        (self.set.write(SUMMARY_JSON, summary_json.as_bytes())).map_err(LogError::dir)?;
        if commit {
            self.set.commit().map_err(LogError::dir)?;
            Ok(super::Outcome::Committed)
        } else if received {
            Ok(super::Outcome::Kept(
                self.set.keep().map_err(LogError::dir)?,
            ))
        } else {
            self.set.discard();
            Ok(super::Outcome::Discarded)
        }
    }
}
