//! `capstan log` (being built).

/// Arguments of `capstan log`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Run `capstan log`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`capstan log` is not built yet")
}
