//! Fitted equations in other languages: Rust (bit-for-bit the same values as `mbgc predict`),
//! LaTeX (for reading and papers) and sympy (for algebra and the SRBench exact-recovery rule).

pub mod latex;
pub mod names;
pub mod rust;
pub mod sympy;

use crate::metamodel::Metamodel;

/// The languages a metamodel's equations are written in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// A Rust module with one function per response.
    Rust,
    /// A LaTeX document with one equation per response.
    Latex,
    /// One sympy-readable line per response.
    Sympy,
}

impl Format {
    /// Every format, in the order the command line lists them.
    pub const ALL: [Format; 3] = [Format::Rust, Format::Latex, Format::Sympy];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Format::Rust => "rust",
            Format::Latex => "latex",
            Format::Sympy => "sympy",
        }
    }
}

impl std::str::FromStr for Format {
    type Err = crate::Error;

    fn from_str(s: &str) -> crate::Result<Format> {
        Format::ALL
            .into_iter()
            .find(|f| f.name() == s)
            .ok_or_else(|| {
                crate::Error::invalid(format!(
                    "export format \"{s}\": expected one of {}",
                    Format::ALL.map(Format::name).join(", ")
                ))
            })
    }
}

/// The metamodel's equations as source text in `format`.
pub fn export(model: &Metamodel, format: Format) -> String {
    match format {
        Format::Rust => rust::module(model),
        Format::Latex => latex::document(model),
        Format::Sympy => sympy::lines(model),
    }
}
