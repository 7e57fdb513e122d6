//! Independent uniform points: the baseline every space-filling method must beat.

use rand::{Rng, RngExt};

use super::points::Points;
use super::sampler::{rng, Sampler};
use crate::error::Result;

/// Independent uniform sampling; continuing the seeded stream makes extension agree with drawing
/// all points at once.
pub struct Random;

impl Sampler for Random {
    fn name(&self) -> &'static str {
        "random"
    }

    /// Continues the seed's stream after the existing points, so that extending a random design
    /// of n points by m gives the same design as drawing n + m at once.
    fn extend(&self, existing: &Points, n_new: usize, seed: u64) -> Result<Points> {
        let d = existing.dim();
        let mut r = rng(seed);
        for _ in 0..existing.len() * d {
            let _: f64 = r.random();
        }
        Ok(uniform_points(&mut r, d, n_new))
    }
}

/// `n` independent uniform points in [0, 1)^dim drawn from `r`.
pub fn uniform_points<R: Rng>(r: &mut R, dim: usize, n: usize) -> Points {
    let data = (0..n * dim).map(|_| r.random::<f64>()).collect();
    Points::from_flat(dim.max(1), data)
}
