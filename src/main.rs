use clap::Parser;

fn main() -> std::process::ExitCode {
    let cli = capstan::cli::Cli::parse();
    match capstan::cli::run(cli) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
