//! Halton points with random digit permutations (scrambling), which removes the correlation of
//! the plain sequence between dimensions with large prime bases.

use rand::seq::SliceRandom;

use super::points::Points;
use super::sampler::{rng, Sampler};
use super::sequence::extend_sequence;
use crate::error::Result;

/// Halton sequence in prime bases 2, 3, 5, ... (one base per dimension).
pub struct Halton {
    /// Whether digits are randomly permuted per position and dimension (default `true`); the
    /// unscrambled sequence has strongly correlated 2-D projections for large prime bases.
    pub scrambled: bool,
}

impl Default for Halton {
    fn default() -> Self {
        Halton { scrambled: true }
    }
}

/// The first `n` primes.
pub fn primes(n: usize) -> Vec<u64> {
    let mut ps: Vec<u64> = Vec::with_capacity(n);
    let mut c = 2u64;
    while ps.len() < n {
        if ps
            .iter()
            .take_while(|&&p| p * p <= c)
            .all(|&p| !c.is_multiple_of(p))
        {
            ps.push(c);
        }
        c += 1;
    }
    ps
}

impl Sampler for Halton {
    fn name(&self) -> &'static str {
        "halton"
    }

    /// Continues the sequence after the existing points (see `sequence::extend_sequence`), so
    /// extension and one-shot designs of the same seed agree.
    fn extend(&self, existing: &Points, n_new: usize, seed: u64) -> Result<Points> {
        let d = existing.dim();
        let bases = primes(d);
        let mut r = rng(seed);
        // One permutation per digit position and dimension; enough positions to resolve 2^-53.
        let perms: Vec<Vec<Vec<u64>>> = bases
            .iter()
            .map(|&b| {
                let levels = (53.0 * 2f64.ln() / (b as f64).ln()).ceil() as usize;
                (0..levels)
                    .map(|_| {
                        let mut p: Vec<u64> = (0..b).collect();
                        if self.scrambled {
                            p.shuffle(&mut r);
                        }
                        p
                    })
                    .collect()
            })
            .collect();
        // The unscrambled sequence starts at index 1: its index 0 is the origin.
        let skip = usize::from(!self.scrambled);
        let gen = |start: usize, n: usize| {
            let mut data = Vec::with_capacity(n * d);
            for i in start + skip..start + skip + n {
                for (j, &b) in bases.iter().enumerate() {
                    let mut idx = i as u64;
                    let mut v = 0.0;
                    let mut scale = 1.0 / b as f64;
                    for perm in &perms[j] {
                        v += perm[(idx % b) as usize] as f64 * scale;
                        idx /= b;
                        scale /= b as f64;
                        if !self.scrambled && idx == 0 {
                            break;
                        }
                    }
                    data.push(v.min(1.0 - f64::EPSILON));
                }
            }
            Points::from_flat(d, data)
        };
        extend_sequence(existing, n_new, usize::MAX / 2, gen)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unscrambled_matches_van_der_corput() {
        let p = Halton { scrambled: false }
            .extend(&Points::new(2), 4, 0)
            .unwrap();
        let want = [
            [0.5, 1.0 / 3.0],
            [0.25, 2.0 / 3.0],
            [0.75, 1.0 / 9.0],
            [0.125, 4.0 / 9.0],
        ];
        for (i, w) in want.iter().enumerate() {
            assert!((p.row(i)[0] - w[0]).abs() < 1e-15 && (p.row(i)[1] - w[1]).abs() < 1e-15);
        }
    }
}
