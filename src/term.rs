//! Writing to stdout and stderr when the reader may have gone (`capstan … | head`): a closed
//! pipe ends the output quietly instead of panicking as `println!` does; the command still
//! finishes its files, and exits with 141, the status of a process ended by SIGPIPE.
//! (Rust ignores SIGPIPE, so the write returns `BrokenPipe`; restoring the signal's default
//! would kill the process in the middle of writing its output set.)
//!
//! Any other failure to write stdout — a full disk (ENOSPC), an I/O error (EIO), stdout closed
//! (`>&-`, which Rust's stdout would otherwise take as a sink) — is not a reader that left: it
//! is an error, said with its cause, with its own exit status ([`WRITE_ERROR_STATUS`]).

use std::io::Write;
use std::sync::atomic::{AtomicBool, Ordering};

static OUT_CLOSED: AtomicBool = AtomicBool::new(false);
/// Why stdout could not be written (not a closed pipe), if it could not.
static OUT_ERROR: std::sync::Mutex<Option<String>> = std::sync::Mutex::new(None);
static OUT_CHECKED: std::sync::Once = std::sync::Once::new();
static ERR_CLOSED: AtomicBool = AtomicBool::new(false);

/// The exit status of a command whose output pipe was closed by its reader.
pub const BROKEN_PIPE_STATUS: u8 = 141;

/// The exit status of a command that could not write its output to stdout (sysexits'
/// EX_IOERR).
pub const WRITE_ERROR_STATUS: u8 = 74;

/// Why stdout could not be written, if that happened (a closed pipe is not this).
pub fn out_error() -> Option<String> {
    OUT_ERROR.lock().unwrap_or_else(|e| e.into_inner()).clone()
}

fn fail_out(why: String) {
    OUT_CLOSED.store(true, Ordering::Relaxed);
    let mut e = OUT_ERROR.lock().unwrap_or_else(|e| e.into_inner());
    e.get_or_insert(why);
}

/// Is stdout open at all? A process started with descriptor 1 closed (`>&-`) gets it
/// reopened on `/dev/null` by Rust's runtime before `main`, read-write, and every write then
/// vanishes: on Linux that descriptor is told from a `> /dev/null` of the shell (write-only)
/// by its access mode. (Elsewhere only a descriptor that is really closed is found.)
fn stdout_is_open() -> bool {
    #[cfg(target_os = "linux")]
    {
        let devnull = std::fs::read_link("/proc/self/fd/1")
            .is_ok_and(|p| p == std::path::Path::new("/dev/null"));
        let read_write = std::fs::read_to_string("/proc/self/fdinfo/1").is_ok_and(|info| {
            info.lines()
                .find_map(|l| l.strip_prefix("flags:"))
                .and_then(|f| u32::from_str_radix(f.trim(), 8).ok())
                .is_some_and(|flags| flags & 3 == 2)
        });
        if devnull && read_write {
            return false;
        }
    }
    #[cfg(unix)]
    {
        use std::os::fd::AsFd;
        std::io::stdout().as_fd().try_clone_to_owned().is_ok()
    }
    #[cfg(not(unix))]
    {
        true
    }
}

/// Whether a reader closed stdout or stderr before the output was written.
pub fn pipe_closed() -> bool {
    OUT_CLOSED.load(Ordering::Relaxed) || ERR_CLOSED.load(Ordering::Relaxed)
}

/// Any failure to print ends printing on that stream, never the command; the other stream
/// goes on.
fn note(closed: &AtomicBool, r: std::io::Result<()>) {
    if r.is_err() {
        closed.store(true, Ordering::Relaxed);
    }
}

/// Print to stdout (once its pipe is closed, or a write failed, nothing more is written
/// there; a failure other than a closed pipe is remembered for [`out_error`]).
pub fn out(args: std::fmt::Arguments<'_>) {
    OUT_CHECKED.call_once(|| {
        if !stdout_is_open() {
            fail_out("standard output is closed".into());
        }
    });
    if OUT_CLOSED.load(Ordering::Relaxed) {
        return;
    }
    let mut o = std::io::stdout().lock();
    match o.write_fmt(args).and_then(|()| o.flush()) {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => {
            OUT_CLOSED.store(true, Ordering::Relaxed);
        }
        Err(e) => fail_out(e.to_string()),
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
