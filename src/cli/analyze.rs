//! `capstan analyze` (being built).

/// Arguments of `capstan analyze`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Run `capstan analyze`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`capstan analyze` is not built yet")
}
