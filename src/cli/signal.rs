//! Stopping on SIGINT, SIGTERM or SIGHUP: the first signal asks the command to finish the work
//! in flight and keep everything completed (a campaign's finished runs, a logged session). A
//! second one exits at once (status 130) — but only if it comes at least [`SECOND_AFTER`]
//! after the first: a double Ctrl-C, or `timeout -s INT` signalling the command and then its
//! process group, delivers two within milliseconds, and must not cost the completed work.
//! Exiting at once keeps the work of every open output set as `DIR/incomplete-<id>` and says
//! where (`outdir::keep_open_sets`); the previous results stay as they were.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, Once};
use std::time::{Duration, Instant};

static STOP: AtomicBool = AtomicBool::new(false);
static INSTALL: Once = Once::new();
/// The first signal: when, and which.
static FIRST: Mutex<Option<(Instant, &'static str)>> = Mutex::new(None);

/// Exit status of a command stopped by a signal (as a shell reports SIGINT).
pub const INTERRUPTED_STATUS: u8 = 130;

/// A second signal counts (exits at once) only this long after the first.
pub const SECOND_AFTER: Duration = Duration::from_millis(500);

/// What a signal does, given the first one's time (if any) and now.
#[derive(Debug, PartialEq, Eq)]
pub enum Action {
    /// The first: finish the work in flight, keep what is done.
    Stop,
    /// Another within [`SECOND_AFTER`] of the first: the same request again, ignored.
    Ignore,
    /// Another, later: exit at once.
    Exit,
}

/// The action for a signal at `now` when the first came at `first`.
pub fn action(first: Option<Instant>, now: Instant) -> Action {
    match first {
        None => Action::Stop,
        Some(t) if now.duration_since(t) < SECOND_AFTER => Action::Ignore,
        Some(_) => Action::Exit,
    }
}

/// The signal by name, as a summary says why a command stopped.
fn name_of(signal: i32) -> &'static str {
    #[cfg(unix)]
    {
        use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
        match signal {
            SIGINT => "Ctrl-C",
            SIGTERM => "SIGTERM",
            SIGHUP => "SIGHUP: the terminal closed",
            _ => "a signal",
        }
    }
    #[cfg(not(unix))]
    {
        let _ = signal;
        "Ctrl-C"
    }
}

/// Handle one signal for `command`.
fn on_signal(command: &'static str, signal: i32) {
    let now = Instant::now();
    let mut first = FIRST.lock().unwrap_or_else(|e| e.into_inner());
    match action(first.map(|f| f.0), now) {
        Action::Stop => {
            *first = Some((now, name_of(signal)));
            STOP.store(true, Ordering::SeqCst);
            crate::errln!(
                "capstan {command}: stopping ({}): finishing the work in flight and keeping \
                 what is done (the same signal again, after half a second, exits at once)",
                name_of(signal)
            );
        }
        Action::Ignore => {}
        Action::Exit => exit_now(command, "second signal"),
    }
}

/// Exit at once (status 130), keeping the work of every open output set and saying where.
fn exit_now(command: &str, why: &str) -> ! {
    let kept = capstan_outdir::keep_open_sets();
    let where_ = if kept.is_empty() {
        "nothing was being written".to_string()
    } else {
        let list: Vec<String> = kept.iter().map(|k| k.display().to_string()).collect();
        format!("the work done so far is kept in {}", list.join(", "))
    };
    crate::errln!("capstan {command}: {why}, exiting now; {where_}");
    std::process::exit(INTERRUPTED_STATUS.into());
}

/// For a command whose work in flight keeps nothing (a plan is written only when finished):
/// once stopped, if it has not returned `grace` later, exit at once as a second signal would.
/// This bounds the time from a signal to the exit whatever the command is computing.
pub fn exit_if_still_running_after(command: &'static str, grace: Duration) {
    let stop = stop_flag(command);
    std::thread::spawn(move || {
        while !stop.load(Ordering::SeqCst) {
            std::thread::sleep(Duration::from_millis(50));
        }
        std::thread::sleep(grace);
        let why = format!(
            "still working {} s after the signal",
            grace.as_secs_f64().round()
        );
        exit_now(command, &why);
    });
}

/// The flag the signal handler sets; installs the handler on first use.
pub fn stop_flag(command: &'static str) -> &'static AtomicBool {
    INSTALL.call_once(|| install(command));
    &STOP
}

/// Why the command was asked to stop, if it was: "Ctrl-C", "SIGTERM", ...
pub fn stop_reason() -> Option<&'static str> {
    FIRST.lock().unwrap_or_else(|e| e.into_inner()).map(|f| f.1)
}

#[cfg(unix)]
fn install(command: &'static str) {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    // Fails only if the signals cannot be registered at all: then they keep their default
    // action (the process ends), which loses nothing the journal of `outdir` cannot recover.
    if let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) {
        std::thread::spawn(move || {
            for s in signals.forever() {
                on_signal(command, s);
            }
        });
    }
}

#[cfg(not(unix))]
fn install(command: &'static str) {
    // Fails only if a handler is already set (a test calling twice): harmless.
    let _ = ctrlc::set_handler(move || on_signal(command, 2));
}

/// The command was stopped by a signal after keeping its completed work.
#[derive(Debug)]
pub struct Interrupted(pub String);

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Interrupted {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_signal_counts_only_after_half_a_second() {
        let t = Instant::now();
        assert_eq!(action(None, t), Action::Stop);
        assert_eq!(
            action(Some(t), t + Duration::from_millis(1)),
            Action::Ignore
        );
        assert_eq!(
            action(Some(t), t + Duration::from_millis(499)),
            Action::Ignore
        );
        assert_eq!(
            action(Some(t), t + Duration::from_millis(500)),
            Action::Exit
        );
    }
}
