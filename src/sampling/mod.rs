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
pub mod sobol;

pub use design::Design;
pub use points::Points;

use crate::error::{Error, Result};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// A design method.
pub trait Sampler {
    /// Short name as used on the command line.
    fn name(&self) -> &'static str;
    /// Whether the method can extend an existing design.
    fn sequential(&self) -> bool {
        true
    }
    /// Returns `n_new` new points of dimension `existing.dim()`; `existing` stays untouched.
    fn extend(&self, existing: &Points, n_new: usize, seed: u64) -> Result<Points>;
}

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

/// The seeded generator used by every method: ChaCha8 is portable, so a seed gives the same
/// design on every platform.
pub fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
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

/// Extends a design with points of a deterministic sequence (Sobol, Halton); `gen(start, count)`
/// returns points `start..start + count` of the sequence, which has `max_points` points at most.
///
/// If the existing points are the sequence's own first points, the sequence simply continues, so
/// extending equals generating the larger design at once. A sequence knows nothing of anyone
/// else's points, though, and continuing it beside a foreign design puts some new points right
/// next to old ones. Then we walk on along the sequence and skip every point closer to an
/// existing point than the minimum distance of the one-shot design of the final size (halving
/// that radius if the sequence runs out), which keeps the new points as spread as the sequence's
/// own design.
pub(crate) fn extend_sequence(
    existing: &Points,
    n_new: usize,
    max_points: usize,
    gen: impl Fn(usize, usize) -> Points,
) -> Result<Points> {
    let n_old = existing.len();
    let too_many = |n: usize| {
        Error::invalid(format!(
            "the sequence has at most {max_points} points; asked for {n}. Use fssf-f for larger designs"
        ))
    };
    if n_old + n_new > max_points {
        return Err(too_many(n_old + n_new));
    }
    if n_old == 0 {
        return Ok(gen(0, n_new));
    }
    let own = gen(0, n_old);
    let is_prefix = own
        .as_flat()
        .iter()
        .zip(existing.as_flat())
        .all(|(a, b)| (a - b).abs() <= 1e-9);
    if is_prefix {
        return Ok(gen(n_old, n_new));
    }
    let mut radius2 = if n_old + n_new >= 2 {
        metrics::mid(&gen(0, n_old + n_new)).powi(2)
    } else {
        0.0
    };
    loop {
        let mut out = Points::with_capacity(existing.dim(), n_new);
        let mut index = n_old;
        while out.len() < n_new && index < max_points {
            let chunk = (2 * n_new).min(max_points - index);
            let pts = gen(index, chunk);
            for p in pts.rows() {
                if existing.rows().all(|x| points::dist2(p, x) >= radius2) {
                    out.push(p);
                    if out.len() == n_new {
                        break;
                    }
                }
            }
            index += chunk;
        }
        if out.len() == n_new {
            return Ok(out);
        }
        if radius2 == 0.0 {
            return Err(too_many(index + n_new - out.len()));
        }
        radius2 = if radius2 < 1e-24 { 0.0 } else { radius2 / 4.0 };
    }
}
