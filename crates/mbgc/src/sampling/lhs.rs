//! Latin hypercube designs: classic (random permutation and jitter per dimension) and maximin
//! (the classic design improved by coordinate swaps that lower the Morris-Mitchell phi_p
//! criterion, a smooth stand-in for maximising the minimum distance). One-shot: the strata
//! depend on the final size, so an LHS cannot be extended.

use rand::seq::SliceRandom;
use rand::RngExt;

use super::points::dist2;
use super::points::Points;
use super::sampler::{rng, Sampler};
use crate::error::{Error, Result};

/// Latin hypercube design: each of the n strata of width 1/n in every dimension holds exactly one
/// point.
pub struct Lhs {
    /// Whether to improve the random LHS by coordinate swaps that lower phi_p (limited to
    /// [`MAXIMIN_MAX_POINTS`] points by the distance matrix it keeps).
    pub maximin: bool,
    /// Exponent of phi_p; large values approach the maximin criterion.
    pub p: i32,
}

/// Distance matrix memory bound for the maximin optimisation.
pub const MAXIMIN_MAX_POINTS: usize = 4000;

impl Lhs {
    /// Classic LHS: a random permutation of strata and uniform jitter within each stratum.
    pub fn classic() -> Self {
        Lhs {
            maximin: false,
            p: 0,
        }
    }

    /// Maximin LHS with phi_p exponent p = 50, close to maximising the minimum intersite distance.
    pub fn maximin() -> Self {
        Lhs {
            maximin: true,
            p: 50,
        }
    }
}

impl Sampler for Lhs {
    fn name(&self) -> &'static str {
        if self.maximin {
            "lhs-maximin"
        } else {
            "lhs"
        }
    }

    fn sequential(&self) -> bool {
        false
    }

    fn extend(&self, existing: &Points, n: usize, seed: u64) -> Result<Points> {
        // Before anything is drawn or allocated.
        if self.maximin && n > MAXIMIN_MAX_POINTS {
            return Err(Error::invalid(format!(
                "--n {n}: lhs-maximin is limited to {MAXIMIN_MAX_POINTS} points (it keeps the \
                 full distance matrix); use fssf-f for larger space-filling designs"
            )));
        }
        if !existing.is_empty() {
            return Err(Error::invalid(
                "a Latin hypercube is one-shot and cannot extend an existing design",
            ));
        }
        let d = existing.dim();
        let mut r = rng(seed);
        let mut data = vec![0.0; n * d];
        let mut perm: Vec<usize> = (0..n).collect();
        for k in 0..d {
            perm.shuffle(&mut r);
            for i in 0..n {
                data[i * d + k] = (perm[i] as f64 + r.random::<f64>()) / n as f64;
            }
        }
        let mut pts = Points::from_flat(d, data);
        if self.maximin && n > 2 {
            pts = optimise_phi_p(pts, self.p, &mut r);
        }
        Ok(pts)
    }
}

/// Greedy column-swap descent on phi_p = sum_{i<j} (d_ij / r0)^-p, with the pairwise squared
/// distances kept in a matrix so that a swap is evaluated in O(n).
fn optimise_phi_p<R: rand::Rng>(pts: Points, p: i32, r: &mut R) -> Points {
    let n = pts.len();
    let d = pts.dim();
    let mut x = pts.as_flat().to_vec();
    // Normalise by the typical nearest-neighbour spacing so that terms stay in f64 range.
    let r0sq = (1.0 / n as f64).powf(2.0 / d as f64);
    let half_p = p / 2;
    let term = |d2: f64| (d2 / r0sq).max(1e-6).powi(-half_p);
    // Squared distances and their phi_p terms, so that a trial swap costs two powi per point.
    let mut d2 = vec![0.0; n * n];
    let mut t = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..i {
            let v = dist2(&x[i * d..(i + 1) * d], &x[j * d..(j + 1) * d]);
            d2[i * n + j] = v;
            d2[j * n + i] = v;
            t[i * n + j] = term(v);
            t[j * n + i] = t[i * n + j];
        }
    }
    // Work bound keeps 1000 x 12 designs well under a second.
    let iterations = (200 * n).min(30_000_000 / (2 * n));
    let mut new_a = vec![(0.0, 0.0); n];
    let mut new_b = vec![(0.0, 0.0); n];
    for _ in 0..iterations {
        let k = r.random_range(0..d);
        let a = r.random_range(0..n);
        let b = r.random_range(0..n);
        if a == b {
            continue;
        }
        let (xa, xb) = (x[a * d + k], x[b * d + k]);
        let mut delta = 0.0;
        for j in 0..n {
            if j == a || j == b {
                continue;
            }
            let xj = x[j * d + k];
            let da = d2[a * n + j] - (xa - xj).powi(2) + (xb - xj).powi(2);
            let db = d2[b * n + j] - (xb - xj).powi(2) + (xa - xj).powi(2);
            let (ta, tb) = (term(da), term(db));
            new_a[j] = (da, ta);
            new_b[j] = (db, tb);
            delta += ta + tb - t[a * n + j] - t[b * n + j];
        }
        if delta < 0.0 {
            x.swap(a * d + k, b * d + k);
            for j in 0..n {
                if j == a || j == b {
                    continue;
                }
                for (row, (v, tv)) in [(a, new_a[j]), (b, new_b[j])] {
                    d2[row * n + j] = v;
                    d2[j * n + row] = v;
                    t[row * n + j] = tv;
                    t[j * n + row] = tv;
                }
            }
        }
    }
    Points::from_flat(d, x)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn is_latin(p: &Points) -> bool {
        let n = p.len();
        (0..p.dim()).all(|k| {
            let mut seen = vec![false; n];
            p.rows().all(|row| {
                let s = (row[k] * n as f64).floor() as usize;
                !std::mem::replace(&mut seen[s], true)
            })
        })
    }

    #[test]
    fn both_variants_are_latin_and_maximin_spreads_more() {
        let c = Lhs::classic().extend(&Points::new(5), 50, 3).unwrap();
        let m = Lhs::maximin().extend(&Points::new(5), 50, 3).unwrap();
        assert!(is_latin(&c) && is_latin(&m));
        let mid = |p: &Points| super::super::metrics::mid(p);
        assert!(
            mid(&m) > mid(&c),
            "maximin {} vs classic {}",
            mid(&m),
            mid(&c)
        );
    }
}
