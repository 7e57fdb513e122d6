//! Space-filling designs in the unit cube.
//!
//! Every method implements [`Sampler`]: given the points already in a design (possibly none, possibly
//! from another method or a user), it returns `n_new` further points. The existing points are
//! never moved. Sequential methods (FSSF-f, FSSF-fr, MIPT, Sobol, Halton, random) take the
//! existing points into account; LHS is one-shot and refuses to extend.

pub mod design;
pub mod fssf;
pub mod halton;
pub mod lhs;
pub mod metrics;
pub mod mipt;
pub mod points;
pub mod random;
pub mod sampler;
pub mod sequence;
pub mod sobol;

pub use design::Design;
pub use points::Points;
pub use sampler::{rng, Sampler};

use crate::error::{Error, Result};

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Method {
    #[value(name = "fssf-f")]
    FssfF,
    #[value(name = "fssf-fr")]
    FssfFr,
    Mipt,
    Sobol,
    Halton,
    Lhs,
    #[value(name = "lhs-maximin")]
    LhsMaximin,
    Random,
}

impl Method {
    pub const ALL: [Method; 8] = [
        Method::FssfF,
        Method::FssfFr,
        Method::Mipt,
        Method::Sobol,
        Method::Halton,
        Method::Lhs,
        Method::LhsMaximin,
        Method::Random,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Method::FssfF => "fssf-f",
            Method::FssfFr => "fssf-fr",
            Method::Mipt => "mipt",
            Method::Sobol => "sobol",
            Method::Halton => "halton",
            Method::Lhs => "lhs",
            Method::LhsMaximin => "lhs-maximin",
            Method::Random => "random",
        }
    }

    /// The sampler with its default settings.
    pub fn sampler(self) -> Box<dyn Sampler + Send + Sync> {
        match self {
            Method::FssfF => Box::new(fssf::Fssf::forward()),
            Method::FssfFr => Box::new(fssf::Fssf::forward_reflected()),
            Method::Mipt => Box::new(mipt::Mipt::default()),
            Method::Sobol => Box::new(sobol::Sobol),
            Method::Halton => Box::new(halton::Halton::default()),
            Method::Lhs => Box::new(lhs::Lhs::classic()),
            Method::LhsMaximin => Box::new(lhs::Lhs::maximin()),
            Method::Random => Box::new(random::Random),
        }
    }
}

/// Generates `n_new` points after `existing` with the given sampler, checking the request.
pub fn extend_design(
    sampler: &dyn Sampler,
    existing: &Points,
    n_new: usize,
    seed: u64,
) -> Result<Points> {
    if existing.dim() == 0 {
        return Err(Error::invalid(
            "the design has no free dimension (every parameter is fixed)",
        ));
    }
    if !existing.is_empty() && !sampler.sequential() {
        return Err(Error::invalid(format!(
            "{} is a one-shot design and cannot extend an existing one; use a sequential \
             method (fssf-f, fssf-fr, mipt, sobol, halton, random)",
            sampler.name()
        )));
    }
    let new = sampler.extend(existing, n_new, seed)?;
    debug_assert_eq!(new.len(), n_new);
    debug_assert!(new.as_flat().iter().all(|v| (0.0..=1.0).contains(v)));
    Ok(new)
}
