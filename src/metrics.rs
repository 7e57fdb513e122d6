//! `mbgc metrics`: space-filling metrics of a design file.

use mbgc_output::say;
use mbgc_output::Output;
use std::path::PathBuf;

use clap::Args;

use mbgc::sampling::{metrics, Design};
use mbgc::space::Space;

#[derive(Debug, Args)]
pub struct MetricsArgs {
    /// Design CSV (unit-cube coordinates unless --space is given).
    pub design: PathBuf,
    /// Space file to map physical values back to the unit cube.
    #[arg(long)]
    pub space: Option<PathBuf>,
    /// Standard output holds one JSON object; the text goes to standard error.
    #[arg(long)]
    pub json: bool,
}

pub fn run(a: &MetricsArgs) -> anyhow::Result<()> {
    let space = a.space.as_deref().map(Space::from_file).transpose()?;
    let design = Design::read(&a.design, space.as_ref())?;
    if design.len() < 2 {
        anyhow::bail!(
            "{}: rows: expected at least 2 points to compute distances, found {}",
            a.design.display(),
            design.len()
        );
    }
    let m = metrics::metrics(&design.unit);
    let out = Output::new(a.json);
    say!(out, "design  {}", a.design.display());
    say!(out, "n       {}", m.n);
    say!(out, "dim     {}", m.dim);
    say!(
        out,
        "MID     {:.6}   minimum intersite distance (larger is better)",
        m.mid
    );
    say!(
        out,
        "COV     {:.6}   cover measure (smaller is better)",
        m.cov
    );
    say!(
        out,
        "CD^2    {:.6e}   centered L2 discrepancy, squared",
        m.cd
    );
    say!(
        out,
        "WD^2    {:.6e}   wrap-around L2 discrepancy, squared",
        m.wd
    );
    out.object(&m)?;
    Ok(())
}
