//! What every design method implements, and the generator they all draw from.

use super::points::Points;
use crate::error::Result;
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

/// The seeded generator used by every method: ChaCha8 is portable, so a seed gives the same
/// design on every platform.
pub fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}
