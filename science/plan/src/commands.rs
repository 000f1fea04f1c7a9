//! The plan's `capstan rig` commands as they run when pasted: with the board selector the user
//! gave `plan`, or a placeholder that says what to put there (a bare `capstan rig set …` fails
//! with "say which board").

use crate::design::Candidate;
use crate::Plan;
use capstan_rig::Calibration;
use capstan_wire::Key;

/// The placeholder for a board selector the user did not give.
pub const PLACEHOLDER: &str = "--chip RP2040 --elf YOUR_FIRMWARE.elf";

/// Every `capstan rig` command of `plan` (in the commands and quoted in the procedure) with
/// `selector` after `capstan rig`.
pub fn with_board(plan: &mut Plan, selector: &str) {
    let put = |text: &mut String| {
        *text = text.replace("capstan rig ", &format!("capstan rig {selector} "));
    };
    for c in plan.candidates.iter_mut().chain([&mut plan.recommended]) {
        c.candidate.rig_commands.iter_mut().for_each(put);
        c.candidate.procedure.iter_mut().for_each(put);
    }
}

/// `capstan rig set amp_control_v X`: the command that makes the amplifier drive `drive_v` V
/// (at the default calibration's `amp_gain`), and the gain it assumed.
pub fn set_drive(drive_v: f64) -> (String, f64) {
    let gain = Calibration::default().amp.amp_gain as f64;
    let control = ((drive_v / gain) * 1000.0).round() / 1000.0;
    let key = Key::AmpControlV.name();
    (format!("capstan rig set {key} {control}"), gain)
}

/// The step of the procedure that switches the drive to `drive_v` V and repeats the runs.
pub fn switch_step(drive_v: f64) -> String {
    let (set, gain) = set_drive(drive_v);
    format!(
        "`{set}` (drive {drive_v} V with amp_gain {gain}), `capstan rig store`, and the same runs \
         again on every cord"
    )
}

/// A candidate whose protocol runs at more than one drive voltage and whose commands do not
/// set one: the first voltage set with the others (before `store`), a switch to each further
/// voltage in the procedure. Without it a plan on data at two voltages printed commands that
/// ran every cord at whatever voltage the board held.
pub fn switch_voltages(c: &mut Candidate) {
    let key = format!("set {} ", Key::AmpControlV.name());
    let volts = c.design.drive_v.clone();
    let said = |t: &String| t.contains(&key);
    if volts.len() < 2 || c.rig_commands.iter().chain(&c.procedure).any(said) {
        return;
    }
    let store = "capstan rig store";
    let at = (c.rig_commands.iter())
        .position(|t| t == store)
        .unwrap_or(c.rig_commands.len());
    c.rig_commands.insert(at, set_drive(volts[0]).0);
    if !c.rig_commands.iter().any(|t| t == store) {
        c.rig_commands.push(store.to_string());
    }
    c.procedure
        .extend(volts[1..].iter().map(|v| switch_step(*v)));
}
