//! The plan's `capstan rig` commands as they run when pasted: with the board selector the user
//! gave `plan`, or a placeholder that says what to put there (a bare `capstan rig set …` fails
//! with "say which board").

use crate::Plan;

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
