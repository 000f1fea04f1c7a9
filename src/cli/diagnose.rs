//! `capstan diagnose` (being built).

/// Arguments of `capstan diagnose`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Run `capstan diagnose`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`capstan diagnose` is not built yet")
}
