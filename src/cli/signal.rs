//! Stopping on SIGINT, SIGTERM or SIGHUP: the first signal asks the command to finish the work
//! in flight and keep everything completed (a campaign's finished runs, a logged session);
//! a second one exits at once (status 130), leaving the previous results and the work done
//! so far in a staging directory that the next run keeps (see `outdir`).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Once;

static STOP: AtomicBool = AtomicBool::new(false);
static INSTALL: Once = Once::new();

/// Exit status of a command stopped by a signal (as a shell reports SIGINT).
pub const INTERRUPTED_STATUS: u8 = 130;

/// The flag the signal handler sets; installs the handler on first use.
pub fn stop_flag(command: &'static str) -> &'static AtomicBool {
    INSTALL.call_once(|| {
        // Fails only if a handler is already set (a test calling twice): harmless.
        let _ = ctrlc::set_handler(move || {
            if STOP.swap(true, Ordering::SeqCst) {
                crate::errln!("capstan {command}: second signal, exiting now");
                std::process::exit(INTERRUPTED_STATUS.into());
            }
            crate::errln!(
                "capstan {command}: stopping: finishing the work in flight and keeping what is \
                 done (again to exit at once)"
            );
        });
    });
    &STOP
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
