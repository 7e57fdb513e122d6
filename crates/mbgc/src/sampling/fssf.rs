//! Fully sequential space-filling designs (Shang & Apley 2020, "Fully-sequential space-filling
//! design algorithms for computer experiments", J. Quality Technology 53).
//!
//! Both variants pick greedily from a large fixed candidate set (N = 1000 d + 2 n_max scrambled
//! Sobol points): each new point is the unused candidate farthest (in minimum distance) from all
//! points chosen so far, including the points of an existing design.
//!
//! - FSSF-f (forward): the first point of an empty design is a random candidate.
//! - FSSF-fr (forward-reflected): each candidate also counts its mirror image in the nearest face
//!   of the cube as a design point, at distance b(c) = 2 min_j min(c_j, 1 - c_j), scaled by
//!   sqrt(2d) ("minimax", the reference default) or d ("maximin"). This keeps points off the
//!   boundary, where a plain maximin greedy search puts too many of them.

use rand::RngExt;

use super::points::dist2;
use super::points::Points;
use super::sampler::{rng, Sampler};
use super::sobol::{scramble_seed, sobol_points, MAX_DIM, MAX_POINTS};
use crate::error::{Error, Result};

/// How FSSF-fr scales the distance b(c) of a candidate to its mirror image in the nearest face.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BoundaryWeight {
    /// Initial squared candidate distance 2 d b(c)^2 (reference default).
    Minimax,
    /// Initial squared candidate distance d^2 b(c)^2.
    Maximin,
}

/// FSSF design: each new point is the unused candidate farthest from all points chosen so far
/// (including an existing design), optionally counting reflections in the cube faces.
pub struct Fssf {
    /// `None` for FSSF-f; the reflected-boundary weight for FSSF-fr.
    pub reflected: Option<BoundaryWeight>,
    /// Number of candidates; `None` uses 1000 d + 2 n_max.
    pub candidates: Option<usize>,
}

impl Fssf {
    /// FSSF-f with the reference defaults (no reflection, 1000 d + 2 n_max candidates).
    pub fn forward() -> Self {
        Fssf {
            reflected: None,
            candidates: None,
        }
    }

    /// FSSF-fr with the reference defaults (minimax boundary weight, 1000 d + 2 n_max candidates).
    pub fn forward_reflected() -> Self {
        Fssf {
            reflected: Some(BoundaryWeight::Minimax),
            candidates: None,
        }
    }
}

/// Scrambled Sobol candidates; beyond sobol_burley's 2^16 points per sequence, further blocks
/// come from independently scrambled sequences.
fn candidates(dim: usize, n: usize, seed: u64) -> Points {
    let mut pts = Points::with_capacity(dim, n);
    let mut block = 0u64;
    while pts.len() < n {
        let take = (n - pts.len()).min(MAX_POINTS);
        let s = scramble_seed(seed.wrapping_add(block.wrapping_mul(0x5851_F42D_4C95_7F2D)));
        pts.append(&sobol_points(dim, 0, take, s));
        block += 1;
    }
    pts
}

impl Sampler for Fssf {
    fn name(&self) -> &'static str {
        if self.reflected.is_some() {
            "fssf-fr"
        } else {
            "fssf-f"
        }
    }

    fn extend(&self, existing: &Points, n_new: usize, seed: u64) -> Result<Points> {
        let d = existing.dim();
        if d > MAX_DIM {
            return Err(Error::invalid(format!(
                "fssf draws Sobol candidates and supports at most {MAX_DIM} dimensions"
            )));
        }
        let n_max = existing.len().saturating_add(n_new);
        // Saturating: a wrapped count once reported "1998 candidates" for a huge request.
        let n_cand = self.candidates.unwrap_or(
            1000usize
                .saturating_mul(d)
                .saturating_add(n_max.saturating_mul(2)),
        );
        if n_cand < n_new {
            return Err(Error::invalid(format!(
                "fssf needs at least as many candidates ({n_cand}) as new points ({n_new})"
            )));
        }
        let cand = candidates(d, n_cand, seed);
        let flat = cand.as_flat();
        // Squared distance of every candidate to the nearest chosen point (or reflected image);
        // NEG_INFINITY marks a candidate already taken.
        let mut dmin2: Vec<f64> = match self.reflected {
            None => vec![f64::INFINITY; n_cand],
            Some(w) => {
                let factor = match w {
                    BoundaryWeight::Minimax => 2.0 * d as f64,
                    BoundaryWeight::Maximin => (d * d) as f64,
                };
                cand.rows()
                    .map(|c| {
                        let b = 2.0 * c.iter().map(|&x| x.min(1.0 - x)).fold(f64::MAX, f64::min);
                        factor * b * b
                    })
                    .collect()
            }
        };
        let update = |dmin2: &mut [f64], x: &[f64]| {
            for (m, c) in dmin2.iter_mut().zip(flat.chunks_exact(d)) {
                if *m > 0.0 {
                    let v = dist2(c, x);
                    if v < *m {
                        *m = v;
                    }
                }
            }
        };
        for x in existing.rows() {
            update(&mut dmin2, x);
        }
        let mut out = Points::with_capacity(d, n_new);
        let mut r = rng(seed);
        for step in 0..n_new {
            let pick = if step == 0 && existing.is_empty() && self.reflected.is_none() {
                r.random_range(0..n_cand)
            } else {
                argmax(&dmin2)
            };
            let x = cand.row(pick).to_vec();
            dmin2[pick] = f64::NEG_INFINITY;
            update(&mut dmin2, &x);
            out.push(&x);
        }
        Ok(out)
    }
}

/// Index of the largest value; the lowest index wins ties, keeping the result deterministic.
fn argmax(v: &[f64]) -> usize {
    let mut best = 0;
    for (i, &x) in v.iter().enumerate() {
        if x > v[best] {
            best = i;
        }
    }
    best
}
