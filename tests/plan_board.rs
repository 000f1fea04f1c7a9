//! `plan --board`: the options pasted into every printed `capstan rig` command. What a shell
//! reads as more than a word is refused before any work, so a command to copy carries no other.

use std::process::Command;

fn plan_with_board(board: &str) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_capstan"))
        .args(["plan", "--board", board])
        .output()
        .unwrap()
}

#[test]
fn a_board_that_is_not_options_is_refused_at_once() {
    for (board, says) in [
        ("", "give the board's options"),
        ("; echo pwned", "';' is not part of a board's options"),
        (
            "--chip RP2040 && rm -rf /",
            "'&' is not part of a board's options",
        ),
        ("--sim $(pwd)", "'$' is not part of a board's options"),
        ("--sim 'my dir'", "'\\'' is not part of a board's options"),
    ] {
        let o = plan_with_board(board);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{board:?} was taken");
        assert!(err.contains(says), "{board:?}: {err}");
        assert!(o.stdout.is_empty(), "{board:?}: printed a plan");
    }
}
