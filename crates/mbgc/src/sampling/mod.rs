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

/// A design method selectable by name, e.g. on the command line or in a campaign plan.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// Fully sequential space-filling, forward variant (Shang & Apley 2020): greedy maximin over a
    /// fixed scrambled-Sobol candidate set; the method the MBGC paper recommends.
    FssfF,
    /// FSSF forward-reflected: as FSSF-f, but each candidate's mirror image in the nearest cube
    /// face counts as a design point, which keeps points off the boundary.
    FssfFr,
    /// Monte Carlo intersite-projected-threshold (Crombecq et al. 2011): space-filling and
    /// non-collapsing in every 1-D projection, but close to random sampling in high dimension.
    Mipt,
    /// Owen-scrambled Sobol sequence; extensible up to 2^16 points.
    Sobol,
    /// Halton sequence with random digit permutations, extensible like Sobol.
    Halton,
    /// Classic Latin hypercube: one point per stratum in every dimension; one-shot, cannot be
    /// extended.
    Lhs,
    /// Latin hypercube improved by coordinate swaps towards maximin distance (Morris-Mitchell
    /// phi_50); one-shot.
    LhsMaximin,
    /// Independent uniform points: the baseline every space-filling method must beat.
    Random,
}

impl std::str::FromStr for Method {
    type Err = Error;

    /// The command-line name (`fssf-f`, `sobol`, ...).
    fn from_str(s: &str) -> Result<Method> {
        Method::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| {
                Error::invalid(format!(
                    "sampling method \"{s}\": expected one of {}",
                    Method::ALL.map(Method::name).join(", ")
                ))
            })
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl Method {
    /// Every method, in the order the command-line help lists them.
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

    /// The command-line name (`fssf-f`, `lhs-maximin`, ...), also written into design metadata;
    /// [`FromStr`](std::str::FromStr) parses it back.
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
///
/// Fails if the design has no free dimension, or if a one-shot method (LHS) is asked to extend
/// a non-empty design.
///
/// # Example
///
/// A seeded Sobol design of a 3-parameter cube, extended once; a sequence design extended with
/// its own seed continues the sequence, so 8 + 8 points equal the one-shot design of 16.
///
/// ```
/// use mbgc::sampling::{extend_design, metrics, Method, Points};
///
/// let sobol = Method::Sobol.sampler();
/// let first = extend_design(sobol.as_ref(), &Points::new(3), 8, 42).unwrap();
/// assert_eq!((first.len(), first.dim()), (8, 3));
/// assert!(first.as_flat().iter().all(|v| (0.0..=1.0).contains(v)));
///
/// let more = extend_design(sobol.as_ref(), &first, 8, 42).unwrap();
/// let at_once = extend_design(sobol.as_ref(), &Points::new(3), 16, 42).unwrap();
/// assert_eq!(more.row(0), at_once.row(8));
///
/// // FSSF-f spreads 20 points over the unit square: no two closer than 0.1.
/// let fssf = Method::FssfF.sampler();
/// let design = extend_design(fssf.as_ref(), &Points::new(2), 20, 7).unwrap();
/// assert_eq!(design.len(), 20);
/// assert!(metrics::mid(&design) > 0.1);
/// ```
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
