//! What `capstan rig` prints: the answer to a command (a sentence from its reply record, the
//! settings from a settings record), live values and the settable keys. Every number comes
//! from a record; the wording of replies, settings and faults is `log::words`, shared with
//! `capstan log` and the rig link.

use capstan_link::rig::Answer;
use capstan_link::words::{reply_sentence, settings_lines, unit};
use capstan_rig::command::{Command, CommandKind, Key};
use capstan_rig::record::Live;

/// The firmware refused the command.
#[derive(Clone, Debug, PartialEq)]
pub struct Refused(pub String);

impl std::fmt::Display for Refused {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Refused {}

/// The lines answering `cmd` (stdout), or the firmware's refusal (`refused: REASON`).
pub fn answer_lines(answer: &Answer, cmd: &Command) -> Result<Vec<String>, Refused> {
    if let Some(e) = answer.run_end {
        let fault = e
            .fault
            .map_or(String::new(), |k| format!(" ({})", k.name()));
        return Ok(vec![format!(
            "abort: the run stopped at {:.1} s after {} pair(s){fault}",
            e.t_us as f64 / 1e6,
            e.pairs
        )]);
    }
    let Some(reply) = answer.reply else {
        return Ok(Vec::new());
    };
    if reply.error.is_some() {
        return Err(Refused(reply_sentence(&reply, Some(cmd))));
    }
    let mut lines = vec![reply_sentence(&reply, Some(cmd))];
    let reports_settings = matches!(
        reply.command,
        CommandKind::Show | CommandKind::Store | CommandKind::Defaults
    );
    if let Some(s) = answer.settings.filter(|_| reports_settings) {
        if reply.command != CommandKind::Store {
            // The settings' own first line says it all (`show`, `defaults`).
            lines.clear();
        }
        lines.extend(settings_lines(&s));
    }
    Ok(lines)
}

/// Header of the live table.
pub const LIVE_HEADER: &str = "    time_s      T1_N  T1_counts      T2_N  T2_counts  servo_deg";

/// One live reading as a row of the table.
pub fn live_line(l: &Live) -> String {
    format!(
        "{:>10.1} {:>9.3} {:>10} {:>9.3} {:>10} {:>10.1}",
        l.t_ms as f64 / 1e3,
        l.force_n[0],
        l.counts[0],
        l.force_n[1],
        l.counts[1],
        l.servo_deg
    )
}

/// The settable keys with their units, one a line.
pub fn key_lines() -> Vec<String> {
    Key::ALL
        .iter()
        .map(|&k| {
            let unit = match unit(k.name()) {
                "" => "-",
                u => u,
            };
            format!("{:<18} {:<8} {}", k.name(), unit, k.setting().meaning())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use capstan_link::words::fault_line;
    use capstan_rig::command::CommandError;
    use capstan_rig::hal::Channel;
    use capstan_rig::record::{Fault, FaultKind, Reply, RunEnd, SettingsReport, SettingsSource};
    use capstan_rig::{Calibration, Protocol, Settings};

    fn reply(command: CommandKind, error: Option<CommandError>, values: [f32; 2]) -> Answer {
        Answer {
            reply: Some(Reply {
                command,
                error,
                values,
            }),
            ..Answer::default()
        }
    }

    #[test]
    fn the_answer_is_said_with_the_numbers_of_the_reply() {
        let a = reply(CommandKind::Weigh, None, [0.0163, 1012.4]);
        let cmd = Command::Weigh(Channel::T1, 9.80665);
        assert_eq!(
            answer_lines(&a, &cmd).unwrap(),
            ["weigh t1: 0.01630 N/count (mean 1012.4 counts; measured from the zero taken in this setup session with nothing hanging)"]
        );
        let a = reply(CommandKind::Zero, None, [412.3, 388.1]);
        assert_eq!(
            answer_lines(&a, &Command::Zero).unwrap(),
            ["zero: T1 zero 412.3 counts, T2 zero 388.1 counts (taken as no load: nothing hanging on either hook, the cord slack)"]
        );
        let a = reply(CommandKind::Jog, Some(CommandError::NotInSetup), [0.0; 2]);
        let e = answer_lines(&a, &Command::Jog(5.0)).unwrap_err();
        assert_eq!(
            e.0,
            format!("refused: {}", CommandError::NotInSetup.message())
        );
    }

    #[test]
    fn show_and_store_print_the_settings_of_their_record() {
        let mut s = Settings {
            protocol: Protocol::default(),
            calibration: Calibration::default(),
        };
        s.protocol.wrap_deg = 540.0;
        let mut a = reply(CommandKind::Show, None, [0.0; 2]);
        a.settings = Some(SettingsReport {
            source: SettingsSource::Current,
            settings: s,
        });
        let lines = answer_lines(&a, &Command::Show).unwrap();
        assert_eq!(
            lines[0],
            format!("settings: {}", SettingsSource::Current.message())
        );
        assert!(
            lines.contains(&format!("  {:<18} 540 °", "wrap_deg")),
            "{lines:#?}"
        );
        let mut a = reply(CommandKind::Store, None, [0.0; 2]);
        a.settings = Some(SettingsReport {
            source: SettingsSource::Stored,
            settings: s,
        });
        let lines = answer_lines(&a, &Command::Store).unwrap();
        assert_eq!(lines[0], "store: the settings are stored in flash");
        assert_eq!(lines[1], "settings: stored in flash");
    }

    #[test]
    fn an_abort_during_a_run_is_answered_by_the_run_end() {
        let a = Answer {
            run_end: Some(RunEnd {
                t_us: 12_500_000,
                pairs: 2,
                fault: Some(FaultKind::Abort),
            }),
            ..Answer::default()
        };
        assert_eq!(
            answer_lines(&a, &Command::Abort).unwrap(),
            ["abort: the run stopped at 12.5 s after 2 pair(s) (abort)"]
        );
    }

    #[test]
    fn faults_live_values_and_keys_are_said_with_their_units() {
        let f = Fault {
            kind: FaultKind::OverForce,
            channel: Some(Channel::T2),
            value: 61.5,
            t_us: 1_000,
        };
        assert!(fault_line(&f).starts_with("FAULT over_force on T2 (value 61.5)"));
        let l = Live {
            t_ms: 12_345,
            counts: [1012, 388],
            force_n: [9.80665, -0.02],
            servo_deg: 95.0,
        };
        let row = live_line(&l);
        assert_eq!(row.len(), LIVE_HEADER.len(), "{row}\n{LIVE_HEADER}");
        assert!(row.contains("9.807") && row.contains("1012") && row.contains("95.0"));
        let keys = key_lines();
        assert_eq!(keys.len(), Key::ALL.len());
        assert!(keys[0].starts_with("rest_deg           °"), "{}", keys[0]);
        assert!(keys.iter().any(|k| k.starts_with("order              -")));
    }
}
