//! `mbgc export`: the fitted equations as Rust, LaTeX or sympy.

use mbgc::outputs::refuse_overwriting_inputs;
use std::path::PathBuf;

use clap::Args;

use mbgc::error::write_atomic;
use mbgc::export::{export, Format};
use mbgc::metamodel::Metamodel;

#[derive(Debug, Args)]
pub struct ExportArgs {
    /// Model file written by `mbgc fit`.
    #[arg(long)]
    pub model: PathBuf,
    #[arg(long, value_parser = crate::choice::choice::<Format>(Format::ALL.map(Format::name)))]
    pub format: Format,
    /// Write to this file instead of standard output.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

pub fn run(a: &ExportArgs) -> anyhow::Result<()> {
    if let Some(out) = &a.out {
        refuse_overwriting_inputs("--out", out, &[("--model", &a.model)])?;
    }
    let model = Metamodel::load(&a.model)?;
    let text = export(&model, a.format);
    match &a.out {
        Some(p) => {
            write_atomic(p, text.as_bytes())?;
            mbgc_output::outln!("wrote {}", p.display())?;
        }
        None => mbgc_output::out!("{text}")?,
    }
    Ok(())
}
