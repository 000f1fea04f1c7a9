//! Writing to stdout and stderr when the reader may have gone (`capstan … | head`): a closed
//! pipe ends the output quietly instead of panicking as `println!` does; the command still
//! finishes its files, and exits with 141, the status of a process ended by SIGPIPE.
//! (Rust ignores SIGPIPE, so the write returns `BrokenPipe`; restoring the signal's default
//! would kill the process in the middle of writing its output set.)

use std::io::Write;
use std::sync::atomic::{AtomicBool, Ordering};

static OUT_CLOSED: AtomicBool = AtomicBool::new(false);
static ERR_CLOSED: AtomicBool = AtomicBool::new(false);

/// The exit status of a command whose output pipe was closed by its reader.
pub const BROKEN_PIPE_STATUS: u8 = 141;

/// Whether a reader closed stdout or stderr before the output was written.
pub fn pipe_closed() -> bool {
    OUT_CLOSED.load(Ordering::Relaxed) || ERR_CLOSED.load(Ordering::Relaxed)
}

/// Any failure to print (a closed pipe, mostly) ends printing on that stream, never the
/// command; the other stream goes on.
fn note(closed: &AtomicBool, r: std::io::Result<()>) {
    if r.is_err() {
        closed.store(true, Ordering::Relaxed);
    }
}

/// Print to stdout (once its pipe is closed, nothing more is written there).
pub fn out(args: std::fmt::Arguments<'_>) {
    if !OUT_CLOSED.load(Ordering::Relaxed) {
        let mut o = std::io::stdout().lock();
        note(&OUT_CLOSED, o.write_fmt(args).and_then(|()| o.flush()));
    }
}

/// Print to stderr.
pub fn err(args: std::fmt::Arguments<'_>) {
    if !ERR_CLOSED.load(Ordering::Relaxed) {
        note(&ERR_CLOSED, std::io::stderr().lock().write_fmt(args));
    }
}

/// `println!` that survives a closed pipe.
#[macro_export]
macro_rules! outln {
    () => { $crate::term::out(format_args!("\n")) };
    ($($t:tt)*) => { $crate::term::out(format_args!("{}\n", format_args!($($t)*))) };
}

/// `print!` that survives a closed pipe.
#[macro_export]
macro_rules! out {
    ($($t:tt)*) => { $crate::term::out(format_args!($($t)*)) };
}

/// `eprintln!` that survives a closed pipe.
#[macro_export]
macro_rules! errln {
    () => { $crate::term::err(format_args!("\n")) };
    ($($t:tt)*) => { $crate::term::err(format_args!("{}\n", format_args!($($t)*))) };
}
