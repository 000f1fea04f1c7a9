//! `capstan simulate` (being built).

/// Arguments of `capstan simulate`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Run `capstan simulate`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`capstan simulate` is not built yet")
}
