//! Fitted equations in other languages: Rust (bit-for-bit the same values as `mbgc predict`),
//! LaTeX (for reading and papers) and sympy (for algebra and the SRBench exact-recovery rule).

pub mod latex;
pub mod names;
pub mod rust;
pub mod sympy;

use crate::metamodel::Metamodel;

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    Rust,
    Latex,
    Sympy,
}

pub fn export(model: &Metamodel, format: Format) -> String {
    match format {
        Format::Rust => rust::module(model),
        Format::Latex => latex::document(model),
        Format::Sympy => sympy::lines(model),
    }
}
