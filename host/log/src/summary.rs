//! What a session saw, as `summary.json` and the closing lines say it: counts by
//! record kind, each run (complete or not, where its set-up values came from, its
//! calibration), sequence gaps,
//! restarts, bad frames and an unfinished frame at the end.

use super::{LIVE_CSV, MESSAGES_TXT, PAIRS_CSV, PAIRS_INCOMPLETE_CSV, SETTINGS_CSV, STREAM_FILE};
use capstan_link::decoder::BadFrame;
use capstan_link::seq::{Backwards, Gap, Restart};
use capstan_wire::settings::Group;
use capstan_wire::Setting;
use serde::Serialize;
use std::path::Path;

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
    pub ended: bool,
    /// It ran its protocol to the end: its run-end record arrived and no fault ended it. A
    /// run ended by a fault (the button's abort, a load at its tare, over-force, ...) was cut
    /// short whatever pairs it made: it is not complete (a session of such runs replaces
    /// nothing, [`crate::Outcome`]).
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
    /// The calibration the run used, from its run-start record (`None` if it was lost).
    pub calibration: Option<RunCalibration>,
}

/// The calibration of a run, as its run-start record gives it: every calibration setting of
/// the wire schema, by its name and in its order (`t1_zero`, `t1_n_per_count`, …, written as a
/// JSON object). A value is `None` (null) when the record does not carry it (the tare
/// reference, servo map and amplifier full scale came with setup mode: a firmware built before
/// it does not send them) or is not a number.
#[derive(Clone, Debug, PartialEq)]
pub struct RunCalibration(pub Vec<(&'static str, Option<f64>)>);

impl RunCalibration {
    /// From a run-start record's settings; `sent(field)` says whether the record carries
    /// that field (by its name in the record).
    pub fn of(s: &capstan_rig::Settings, sent: impl Fn(&str) -> bool) -> RunCalibration {
        let value = |setting: Setting| {
            let v = super::files::decimal(f32::from_bits(s.get(setting)));
            Some(v).filter(|d| d.is_finite() && sent(setting.name()))
        };
        RunCalibration(
            Setting::ALL
                .iter()
                .filter(|s| s.group() == Group::Calibration)
                .map(|&setting| (setting.name(), value(setting)))
                .collect(),
        )
    }

    /// One value by its setting's name (`None` for a name it lacks or a value not sent).
    pub fn get(&self, name: &str) -> Option<f64> {
        self.0
            .iter()
            .find(|(n, _)| *n == name)
            .and_then(|(_, v)| *v)
    }
}

impl Serialize for RunCalibration {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = serializer.serialize_map(Some(self.0.len()))?;
        for (name, value) in &self.0 {
            map.serialize_entry(name, value)?;
        }
        map.end()
    }
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
    /// settings (setup mode; not part of a run)
    pub settings: u64,
    /// live (setup mode)
    pub live: u64,
    /// reply (answers to host commands)
    pub reply: u64,
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
    /// What made the session: program, commit, command line, the input's and the ELF's
    /// SHA-256 (absent from library sessions that set none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub provenance: Option<serde_json::Value>,
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

    /// The human report, a few lines (`capstan log` says each on stderr): the totals and
    /// where the files are (`dir`), runs a fault cut short, setup mode, what was lost or
    /// damaged, pairs kept out of `pairs.csv`.
    pub fn human(&self, dir: &Path) -> Vec<String> {
        let mut lines = vec![self.totals_line(dir)];
        lines.extend(self.faulted_lines());
        lines.extend(self.setup_line());
        lines.extend(self.damage_lines());
        lines.extend(self.incomplete_line(dir));
        lines
    }

    /// Runs, pairs, samples, faults and messages, from how many bytes, and where the files are.
    fn totals_line(&self, dir: &Path) -> String {
        let r = &self.records;
        let complete = self.runs.iter().filter(|r| r.complete).count();
        let faulted = self
            .runs
            .iter()
            .filter(|r| r.ended_by_fault.is_some())
            .count();
        let cut = if faulted > 0 {
            format!(", {faulted} ended by a fault")
        } else {
            String::new()
        };
        format!(
            "{} run(s) ({} complete{cut}), {} pairs, {} raw samples, {} faults, {} messages \
             from {} bytes ({}); files in {}",
            self.runs.len(),
            complete,
            r.pair,
            r.raw,
            r.fault,
            self.messages,
            self.bytes,
            self.stopped,
            dir.display()
        )
    }

    /// Each run a fault ended: cut short, not complete, with what it made.
    fn faulted_lines(&self) -> Vec<String> {
        (self.runs.iter())
            .filter_map(|r| {
                let fault = r.ended_by_fault?;
                let run = r.run.map_or("?".to_string(), |n| n.to_string());
                Some(format!(
                    "run {run} was cut short by the fault {fault} after {} pair(s): not a \
                     complete run",
                    r.pairs
                ))
            })
            .collect()
    }

    /// The setup-mode records and their files, if any came.
    fn setup_line(&self) -> Option<String> {
        let r = &self.records;
        (r.setup() > 0).then(|| {
            format!(
                "setup mode: {} settings report(s) ({SETTINGS_CSV}), {} live reading(s) \
                 ({LIVE_CSV}), {} command reply record(s) ({MESSAGES_TXT})",
                r.settings, r.live, r.reply
            )
        })
    }

    /// What the stream lost or got wrong: gaps, bad frames, a cut-off tail, restarts,
    /// records out of order, and a start after the board's first record.
    fn damage_lines(&self) -> Vec<String> {
        let mut lines = Vec::new();
        if self.missing_records > 0 {
            let places: Vec<String> = (self.gaps.iter().take(5))
                .map(|g| {
                    format!(
                        "{} after seq {} (byte {})",
                        g.missing, g.after_seq, g.byte_offset
                    )
                })
                .collect();
            let more = if self.gaps.len() > 5 { ", ..." } else { "" };
            lines.push(format!(
                "LOST {} record(s) in {} gap(s): {}{more}",
                self.missing_records,
                self.gaps.len(),
                places.join("; ")
            ));
        }
        if let Some(first) = self
            .bad_frame_examples
            .first()
            .filter(|_| self.bad_frames > 0)
        {
            lines.push(format!(
                "{} frame(s) did not decode; first: frame {} at byte {}: {}",
                self.bad_frames, first.frame, first.byte_offset, first.reason
            ));
        }
        if let Some(t) = self.truncated_tail {
            lines.push(format!(
                "the stream ends inside a frame ({} bytes from byte {} dropped)",
                t.bytes, t.byte_offset
            ));
        }
        lines.extend(self.restarts.iter().map(|rs| {
            format!(
                "the board restarted after seq {} (byte {})",
                rs.after_seq, rs.byte_offset
            )
        }));
        if let Some(b) = self.backwards.first() {
            lines.push(format!(
                "{} record(s) numbered out of order (first: seq {} where {} was expected)",
                self.backwards.len(),
                b.seq,
                b.expected_seq
            ));
        }
        if let Some(first) = self.first_seq.filter(|&s| s != 0) {
            lines.push(format!(
                "the stream joins the board at seq {first}: records before it were sent before \
                 logging began"
            ));
        }
        lines
    }

    /// Pairs kept out of pairs.csv, and how to decode them again with the missing values.
    fn incomplete_line(&self, dir: &Path) -> Option<String> {
        if self.pairs_incomplete == 0 {
            return None;
        }
        // A simulated board's records come without a defmt stream: nothing to decode again.
        if let Some(board) = self.source.strip_prefix("the simulated board in ") {
            return Some(format!(
                "{} pair(s) lack a set-up value or their run number and are in \
                 {PAIRS_INCOMPLETE_CSV}, not {PAIRS_CSV}; the simulated board sends no stream to decode \
                 again: set them on the board before recording (capstan rig --sim {board} set \
                 wrap_deg DEG, then set diameter_mm MM; the drive voltage is amp_control_v × \
                 amp_gain) or give --wrap-deg/--diameter-mm/--drive-v to capstan log --sim",
                self.pairs_incomplete
            ));
        }
        // The stream to decode again: the copy the session saved (from a board or stdin),
        // or the file it was decoded from.
        let saved = dir.join(STREAM_FILE);
        let from = if saved.exists() {
            saved.display().to_string()
        } else {
            self.source.clone()
        };
        Some(format!(
            "{} pair(s) lack a set-up value or their run number and are in \
             {PAIRS_INCOMPLETE_CSV}, not {PAIRS_CSV}; decode the stream again with \
             --wrap-deg/--diameter-mm/--drive-v into another directory (capstan log \
             --elf {} --from {from} --out NEW_DIR --wrap-deg ...)",
            self.pairs_incomplete, self.elf
        ))
    }
}

impl Sourced {
    /// The value from the flag if one was given, else the record's, else unknown.
    pub fn choose(flag: Option<f64>, record: Option<f64>) -> Sourced {
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
}

impl RunSummary {
    /// A run whose first record (sequence number `first_seq`) has just arrived: nothing
    /// counted yet.
    pub fn new(
        run: Option<u32>,
        first_seq: u32,
        capstan_diameter_mm: Sourced,
        wrap_deg: Sourced,
        drive_v: Sourced,
    ) -> RunSummary {
        RunSummary {
            run,
            first_seq,
            ended: false,
            complete: false,
            raw: 0,
            pairs: 0,
            pairs_not_written: 0,
            pairs_incomplete: 0,
            pairs_reported: None,
            faults: 0,
            ended_by_fault: None,
            end_time_s: None,
            capstan_diameter_mm,
            wrap_deg,
            drive_v,
            calibration: None,
        }
    }
}

impl RecordCounts {
    /// Records of every kind.
    pub fn total(&self) -> u64 {
        self.run_start + self.raw + self.pair + self.fault + self.run_end + self.setup()
    }

    /// Records of the setup-mode kinds (settings, live, reply).
    pub fn setup(&self) -> u64 {
        self.settings + self.live + self.reply
    }
}
