//! The setup-mode records in a session: `settings` to `settings.csv`, `live` to `live.csv`,
//! each `reply` as a sentence in `messages.txt`, and a fault in setup mode to `faults.csv`
//! with no run. None of them opens, closes or counts towards a run.

use super::Logger;
use crate::Note;
use capstan_link::words::{reply_sentence, source_name, unmeasured_lines};
use capstan_rig::command::CommandKind;
use capstan_rig::record::{Fault, Live, Record, Reply, SettingsReport, SettingsSource};

/// Whether the rig is (still) in setup mode once `record` has arrived, `before` whether it
/// was: after a live reading or an accepted setup-mode command; no longer after `leave`, an
/// `abort` of it, a `run`, a run record, or a fault (the rig latches it and goes idle); a
/// settings report or a refused command changes nothing.
///
/// Leaving setup mode by the button logs no record: a fault right after it (during the tare
/// of the next run, before its run_start) is taken for a setup-mode fault.
pub(super) fn keeps_setup(record: &Record, before: bool) -> bool {
    match record {
        Record::Live(_) => true,
        Record::Settings(_) => before,
        Record::Reply(r) if r.error.is_some() => before,
        Record::Reply(r) => match r.command {
            CommandKind::Setup
            | CommandKind::Jog
            | CommandKind::Servo
            | CommandKind::Zero
            | CommandKind::Weigh => true,
            CommandKind::Leave | CommandKind::Abort | CommandKind::Run => false,
            _ => before,
        },
        _ => false,
    }
}

impl Logger<'_> {
    pub(super) fn settings(&mut self, seq: u32, r: &SettingsReport) -> crate::Result<()> {
        self.counts.settings += 1;
        self.files.settings(seq, r)?;
        // A sensitivity nobody measured: the board runs nothing (said at the session's first
        // report, and after `defaults`).
        if self.counts.settings == 1 || r.source == SettingsSource::DefaultsAsked {
            for line in unmeasured_lines(&r.settings) {
                (self.notes)(Note::Session(line.clone()));
                self.files.message("WARN", &format!("seq={seq} {line}"))?;
            }
        }
        if self.opts.progress {
            (self.notes)(Note::Session(format!(
                "settings (seq {seq}, {}): {}",
                source_name(r.source),
                r.source.message()
            )));
        }
        Ok(())
    }

    pub(super) fn live(&mut self, seq: u32, l: &Live) -> crate::Result<()> {
        self.counts.live += 1;
        self.files.live(seq, l)
    }

    pub(super) fn reply(&mut self, seq: u32, r: &Reply) -> crate::Result<()> {
        self.counts.reply += 1;
        let sentence = match r.error {
            Some(_) => format!("{}: {}", r.command.word(), reply_sentence(r, None)),
            None => reply_sentence(r, None),
        };
        if self.opts.progress {
            (self.notes)(Note::Session(format!("reply (seq {seq}): {sentence}")));
        }
        self.files
            .message("REPLY", &format!("seq={seq} {sentence}"))
    }

    /// A fault while no run is under way, after setup-mode records: the rig latched it in
    /// setup mode. Its time is since boot (there is no trigger).
    pub(super) fn setup_fault(&mut self, seq: u32, flt: &Fault) -> crate::Result<()> {
        self.counts.fault += 1;
        self.files.fault("", seq, flt)?;
        if self.opts.progress {
            (self.notes)(Note::Session(format!(
                "FAULT {} in setup mode ({} s since boot)",
                flt.kind.name(),
                flt.t_us as f64 / 1e6
            )));
        }
        Ok(())
    }
}
