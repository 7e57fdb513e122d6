//! Owen-scrambled Sobol points (sobol_burley).

use super::points::Points;
use super::sampler::Sampler;
use super::sequence::extend_sequence;
use crate::error::{Error, Result};

/// sobol_burley computes at most 2^16 points per sequence.
pub const MAX_POINTS: usize = 1 << 16;
/// Highest dimension sobol_burley provides direction numbers for.
pub const MAX_DIM: usize = sobol_burley::NUM_DIMENSIONS as usize;

/// Owen-scrambled Sobol sequence (Burley 2020); extending a seed's own design continues the
/// sequence, so n + m points equal the one-shot design of n + m.
pub struct Sobol;

/// A 64-bit seed folded into sobol_burley's 32-bit scramble seed.
pub fn scramble_seed(seed: u64) -> u32 {
    (crate::numeric::splitmix64(seed) >> 32) as u32
}

/// Points `start..start + n` of the scrambled sequence for `seed`.
pub fn sobol_points(dim: usize, start: usize, n: usize, seed: u32) -> Points {
    let mut data = Vec::with_capacity(n * dim);
    for i in start..start + n {
        for j in 0..dim {
            data.push(sobol_burley::sample(i as u32, j as u32, seed) as f64);
        }
    }
    Points::from_flat(dim, data)
}

impl Sampler for Sobol {
    fn name(&self) -> &'static str {
        "sobol"
    }

    /// Continues the sequence after the existing points (see `sequence::extend_sequence`): a
    /// Sobol design of n points extended by m with the same seed equals the design of n + m.
    fn extend(&self, existing: &Points, n_new: usize, seed: u64) -> Result<Points> {
        let d = existing.dim();
        if d > MAX_DIM {
            return Err(Error::invalid(format!(
                "sobol supports at most {MAX_DIM} dimensions, asked for {d}"
            )));
        }
        let s = scramble_seed(seed);
        extend_sequence(existing, n_new, MAX_POINTS, |start, n| {
            sobol_points(d, start, n, s)
        })
    }
}
