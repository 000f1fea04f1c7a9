//! The `capstan` command: parses the command line and runs it (see [`capstan::cli`]); exits
//! non-zero with the error and its context on failure.

use clap::Parser;

fn main() -> std::process::ExitCode {
    let cli = capstan::cli::Cli::parse();
    let r = capstan::cli::run(cli);
    if let Err(e) = &r {
        capstan::errln!("error: {e:#}");
    }
    let write_error = capstan::term::out_error();
    if let Some(why) = &write_error {
        // Not a reader that went away: the output was lost (a full disk, an I/O error).
        capstan::errln!(
            "error: cannot write to standard output: {why}; what it should hold is incomplete \
             (the output files, if any, are written)"
        );
    }
    match r {
        Err(e) if e.is::<capstan::cli::signal::Interrupted>() => {
            std::process::ExitCode::from(capstan::cli::signal::INTERRUPTED_STATUS)
        }
        Err(_) => std::process::ExitCode::FAILURE,
        Ok(()) if write_error.is_some() => {
            std::process::ExitCode::from(capstan::term::WRITE_ERROR_STATUS)
        }
        // The reader went away (`| head`): end quietly, as a process ended by SIGPIPE does.
        Ok(()) if capstan::term::pipe_closed() => {
            std::process::ExitCode::from(capstan::term::BROKEN_PIPE_STATUS)
        }
        Ok(()) => std::process::ExitCode::SUCCESS,
    }
}
