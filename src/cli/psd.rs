use clap::Args;

#[derive(Debug, Args)]
pub struct PsdArgs {}

pub fn run(_args: &PsdArgs) -> anyhow::Result<()> {
    anyhow::bail!("not implemented yet")
}
