use clap::Parser;

fn main() -> std::process::ExitCode {
    let cli = capstan::cli::Cli::parse();
    let r = capstan::cli::run(cli);
    if let Err(e) = &r {
        capstan::errln!("error: {e:#}");
    }
    if r.is_ok() && capstan::term::pipe_closed() {
        // The reader went away (`| head`): end quietly, as a process ended by SIGPIPE does.
        return std::process::ExitCode::from(capstan::term::BROKEN_PIPE_STATUS);
    }
    match r {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) if e.is::<capstan::cli::signal::Interrupted>() => {
            std::process::ExitCode::from(capstan::cli::signal::INTERRUPTED_STATUS)
        }
        Err(_) => std::process::ExitCode::FAILURE,
    }
}
