//! The setup-mode records in words, shared by `capstan rig` (what it prints, and what its link
//! notes while it waits for an answer) and `capstan log` (`messages.txt`, `settings.csv`): a
//! sentence for each `reply`, a line for each fault, each setting with its unit, and a name
//! for each settings source. Every number in a sentence is the record's.

use capstan_rig::command::{Command, CommandKind, Key};
use capstan_rig::hal::Channel;
use capstan_rig::record::{Fault, Reply, SettingsReport, SettingsSource};
use capstan_rig::{Settings, StepOrder};
use capstan_wire::{Setting, Value};

/// A stable name of a settings source, for CSV and JSON (the wire schema's).
pub const fn source_name(source: SettingsSource) -> &'static str {
    source.name()
}

/// The name of a step order, as `set order NAME` takes it (the wire schema's).
pub const fn order_name(order: StepOrder) -> &'static str {
    order.name()
}

/// The unit of a setting, by its name (the wire schema's; empty for the order or a name the
/// schema lacks).
pub fn unit(name: &str) -> &'static str {
    Setting::from_name(name).map_or("", |s| s.unit())
}

/// One setting, as written.
#[derive(Clone, Debug, PartialEq)]
pub struct SettingValue {
    /// Its name (the `settings` record's field, the key `set` takes where it is settable).
    pub name: &'static str,
    /// The value as text: the shortest decimal of the f32, a whole number of ms, an order name.
    pub value: String,
    /// Its unit (empty for the order).
    pub unit: &'static str,
}

/// Every setting, in the `settings` record's order (the wire schema's table).
pub fn setting_values(s: &Settings) -> Vec<SettingValue> {
    Setting::ALL
        .iter()
        .map(|&setting| {
            let bits = s.get(setting);
            let value = match setting.value() {
                Value::Code => setting
                    .code_name(bits as u8)
                    .map_or_else(|| bits.to_string(), str::to_string),
                Value::Whole => bits.to_string(),
                Value::Real => f32::from_bits(bits).to_string(),
            };
            SettingValue {
                name: setting.name(),
                value,
                unit: setting.unit(),
            }
        })
        .collect()
}

/// A settings report as lines: where the settings came from, then one setting a line, then
/// a warning for each sensitivity nobody measured ([`unmeasured_lines`]).
pub fn settings_lines(report: &SettingsReport) -> Vec<String> {
    let mut lines = vec![format!("settings: {}", report.source.message())];
    for v in setting_values(&report.settings) {
        let value = format!("{} {}", v.value, v.unit);
        lines.push(format!("  {:<18} {}", v.name, value.trim_end()));
    }
    lines.extend(unmeasured_lines(&report.settings));
    lines
}

/// A line for each force channel whose sensitivity nobody measured or typed (the built-in
/// placeholder): the board runs nothing until it is.
pub fn unmeasured_lines(s: &Settings) -> Vec<String> {
    let c = &s.calibration;
    [(Channel::T1, &c.t1), (Channel::T2, &c.t2)]
        .into_iter()
        .filter(|(_, ch)| !ch.source.is_measured())
        .map(|(ch, _)| {
            let n = ch.name();
            format!(
                "UNMEASURED: {}'s sensitivity ({n}_n_per_count) is the built-in placeholder, \
                 measured by nobody: the board runs nothing until it is weighed (weigh {n} \
                 NEWTONS in setup mode) or typed (set {n}_n_per_count), and stored",
                n.to_uppercase()
            )
        })
        .collect()
}

/// `v` with `digits` significant digits (0.0163 → "0.01630" at 4).
fn significant(v: f32, digits: i32) -> String {
    if v == 0.0 || !v.is_finite() {
        return v.to_string();
    }
    let magnitude = v.abs().log10().floor() as i32;
    let decimals = (digits - 1 - magnitude).clamp(0, 12) as usize;
    format!("{v:.decimals$}")
}

/// The value of `set KEY` as the firmware took it: an order by name, ms whole.
fn set_value(key: Key, value: f32) -> String {
    match key {
        k if k.setting().value() == Value::Code => k
            .setting()
            .code_name(value as u8)
            .filter(|_| (value as u8) as f32 == value)
            .map_or_else(|| value.to_string(), str::to_string),
        _ => {
            let unit = unit(key.name());
            format!("{value} {unit}").trim_end().to_string()
        }
    }
}

/// The sentence for a reply. `sent` is the command it answers, if known (it names the channel
/// of a `weigh`, which the reply does not carry).
pub fn reply_sentence(reply: &Reply, sent: Option<&Command>) -> String {
    if let Some(e) = reply.error {
        return format!("refused: {}", e.message());
    }
    let [v1, v2] = reply.values;
    let word = reply.command.word();
    match reply.command {
        CommandKind::Setup => format!("setup: in setup mode, servo at {v1:.1}°"),
        CommandKind::Leave => "leave: setup mode left, the servo homes to rest".into(),
        CommandKind::Jog | CommandKind::Servo => format!("{word}: servo at {v1:.1}°"),
        CommandKind::Zero => {
            format!("zero: T1 zero {v1:.1} counts, T2 zero {v2:.1} counts (taken as no load: nothing hanging on either hook, the cord slack)")
        }
        CommandKind::Weigh => {
            let channel = match sent {
                Some(Command::Weigh(Channel::T1, _)) => " t1",
                Some(Command::Weigh(Channel::T2, _)) => " t2",
                _ => "",
            };
            let npc = significant(v1, 4);
            format!("weigh{channel}: {npc} N/count (mean {v2:.1} counts; measured from the zero taken in this setup session with nothing hanging)")
        }
        CommandKind::Set => match Key::ALL.get(v1 as usize).filter(|_| v1 >= 0.0) {
            Some(&key) => format!("set {} = {}", key.name(), set_value(key, v2)),
            None => format!("set: key code {v1} = {v2}"),
        },
        CommandKind::Show => "show: done".into(),
        CommandKind::Store => "store: the settings are stored in flash".into(),
        CommandKind::Defaults => {
            "defaults: built-in defaults in force (send store to keep them)".into()
        }
        CommandKind::Run => format!(
            "run: run {v1:.0} armed: press the rig's button within {v2:.0} s to start it (the host \
             never starts the drive)"
        ),
        // The firmware answers a run's abort with 1 (the run stops, fault `abort`), setup
        // mode's with 0.
        CommandKind::Abort if v1 == 1.0 => {
            "abort: the run stops (fault abort), the outputs go to their safe state".into()
        }
        CommandKind::Abort => "abort: setup mode left, the servo homes to rest".into(),
        CommandKind::Ack => "ack: fault acknowledged".into(),
        CommandKind::Unparsed => "?: done".into(),
    }
}

/// One reply as a line: its sentence, and the command word before a refusal.
pub fn reply_line(r: &Reply, sent: Option<&Command>) -> String {
    let sentence = reply_sentence(r, sent);
    match r.error {
        Some(_) => format!("{}: {sentence}", r.command.word()),
        None => sentence,
    }
}

/// A fault, for stderr.
pub fn fault_line(f: &Fault) -> String {
    let channel = match f.channel {
        Some(Channel::T1) => " on T1",
        Some(Channel::T2) => " on T2",
        None => "",
    };
    // (A fault latched at boot after a reset has no value: NaN.)
    let value = if f.value.is_nan() {
        String::new()
    } else {
        format!(" (value {})", f.value)
    };
    let go_on = if f.kind.needs_press() {
        "press the rig's button to go on (a reset latched it: the host's `ack` is refused)"
    } else {
        "press the button or send `ack` to go on"
    };
    format!(
        "FAULT {}{channel}{value}: the rig's outputs are safe; {go_on}",
        f.kind.name(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use capstan_rig::command::CommandError;
    use capstan_rig::{Calibration, Protocol};

    fn ok(command: CommandKind, values: [f32; 2]) -> Reply {
        Reply {
            command,
            error: None,
            values,
        }
    }

    #[test]
    fn each_reply_is_said_with_the_numbers_of_the_record() {
        let say = |r: Reply| reply_sentence(&r, None);
        assert_eq!(
            say(ok(CommandKind::Jog, [95.0, 0.0])),
            "jog: servo at 95.0°"
        );
        assert_eq!(
            say(ok(CommandKind::Servo, [42.3, 0.0])),
            "servo: servo at 42.3°"
        );
        assert_eq!(
            say(ok(CommandKind::Zero, [412.3, 388.1])),
            "zero: T1 zero 412.3 counts, T2 zero 388.1 counts (taken as no load: nothing hanging on either hook, the cord slack)"
        );
        let weigh = ok(CommandKind::Weigh, [0.0163, 1012.4]);
        let sent = Command::Weigh(Channel::T1, 9.80665);
        assert_eq!(
            reply_sentence(&weigh, Some(&sent)),
            "weigh t1: 0.01630 N/count (mean 1012.4 counts; measured from the zero taken in this setup session with nothing hanging)"
        );
        assert_eq!(say(weigh), "weigh: 0.01630 N/count (mean 1012.4 counts; measured from the zero taken in this setup session with nothing hanging)");
        let dwell = Key::DwellMs.code() as f32;
        assert_eq!(
            say(ok(CommandKind::Set, [dwell, 8000.0])),
            "set dwell_ms = 8000 ms"
        );
        let order = Key::Order.code() as f32;
        assert_eq!(
            say(ok(CommandKind::Set, [order, 1.0])),
            "set order = updown"
        );
        let npc = Key::T2NPerCount.code() as f32;
        assert_eq!(
            say(ok(CommandKind::Set, [npc, 0.0121])),
            "set t2_n_per_count = 0.0121 N/count"
        );
        assert_eq!(
            say(ok(CommandKind::Set, [99.0, 1.0])),
            "set: key code 99 = 1"
        );
        assert_eq!(
            say(ok(CommandKind::Run, [3.0, 30.0])),
            "run: run 3 armed: press the rig's button within 30 s to start it (the host never starts the drive)"
        );
        assert_eq!(
            say(ok(CommandKind::Setup, [125.0, 0.0])),
            "setup: in setup mode, servo at 125.0°"
        );
    }

    #[test]
    fn a_refusal_says_the_firmware_reason() {
        for e in CommandError::ALL {
            let r = Reply {
                command: CommandKind::Jog,
                error: Some(e),
                values: [1.0, 2.0],
            };
            assert_eq!(
                reply_sentence(&r, None),
                format!("refused: {}", e.message())
            );
        }
    }

    #[test]
    fn a_settings_report_lists_every_setting_with_its_unit_and_source() {
        let mut s = Settings {
            protocol: Protocol::default(),
            calibration: Calibration::default(),
        };
        s.protocol.dwell_ms = 8000;
        s.calibration.servo.max_deg = 175.5;
        let lines = settings_lines(&SettingsReport {
            source: SettingsSource::Stored,
            settings: s,
        });
        assert_eq!(lines[0], "settings: stored in flash");
        // Every setting, and the placeholder sensitivities said twice.
        assert_eq!(lines.len(), 1 + capstan_wire::settings::SETTINGS + 2);
        let last = lines.len() - 1;
        assert!(lines[last].starts_with("UNMEASURED: T2's sensitivity"));
        assert!(lines.contains(&format!("  {:<18} unmeasured", "t1_cal")));
        assert!(
            lines.contains(&format!("  {:<18} 8000 ms", "dwell_ms")),
            "{lines:#?}"
        );
        assert!(lines.contains(&format!("  {:<18} 175.5 °", "servo_max_deg")));
        assert!(lines.contains(&format!("  {:<18} monotone", "order")));
        assert!(lines.contains(&format!("  {:<18} 0.015 N/count", "t1_n_per_count")));
        // Every settable key is among the settings, with a unit unless it is the order.
        let values = setting_values(&s);
        for k in Key::ALL {
            let v = values
                .iter()
                .find(|v| v.name == k.name())
                .unwrap_or_else(|| panic!("{}", k.name()));
            let unitless = k.setting().value() == Value::Code
                || matches!(k, Key::ForceSineSteps | Key::ModelMu | Key::ModelExponent);
            assert_eq!(v.unit.is_empty(), unitless, "{}", k.name());
        }
    }

    #[test]
    fn every_source_has_its_own_name() {
        let names: Vec<&str> = SettingsSource::ALL
            .iter()
            .map(|&s| source_name(s))
            .collect();
        let mut unique = names.clone();
        unique.sort();
        unique.dedup();
        assert_eq!(unique.len(), names.len());
    }
}
