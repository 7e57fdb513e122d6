//! Monte Carlo intersite-projected-threshold design, MIPT (Crombecq, Laermans & Dhaene 2011,
//! "Efficient space-filling and non-collapsing sequential design strategies for simulation-based
//! modeling", EJOR 214).
//!
//! For a design of n points, 100 n random candidates are scored: a candidate whose projection on
//! any axis lies closer than d_min to the projection of a design point scores 0, the others score
//! their distance to the nearest design point; the best candidate is added. Crombecq works on
//! [-1, 1]^d with d_min = 2 alpha / n; on the unit cube the same threshold is d_min = alpha / n.
//!
//! Generating the candidates one by one costs O(100 n^2 d) per design and is hopeless for
//! n = 1000, so we draw the same thing faster: the candidates that pass the threshold are exactly
//! uniform on the product of the allowed sets A_k = [0, 1] minus the excluded intervals, and
//! their number is Binomial(100 n, prod |A_k|). We draw that number, then that many points from
//! the allowed set. When none passes, every score is 0 and the literal algorithm returns its first
//! candidate, a uniform random point; we do the same. This is what makes MIPT degrade to random
//! sampling in high dimension: the passing fraction shrinks like prod |A_k|.

use rand::RngExt;
use rand_distr::{Binomial, Distribution};

use super::points::dist2;
use super::points::Points;
use super::sampler::{rng, Sampler};
use crate::error::{Error, Result};

/// MIPT sampler: adds, one at a time, the best of `candidates_per_point * n` random candidates
/// whose 1-D projections all keep at least alpha / n from those of the design.
pub struct Mipt {
    /// Projected-distance tolerance alpha in [0, 1]; Crombecq recommends 0.5.
    pub alpha: f64,
    /// Random candidates per design point (Crombecq: 100).
    pub candidates_per_point: usize,
}

impl Default for Mipt {
    fn default() -> Self {
        Mipt {
            alpha: 0.5,
            candidates_per_point: 100,
        }
    }
}

/// Allowed set of one axis: sorted disjoint intervals and their cumulative lengths.
struct Allowed {
    intervals: Vec<(f64, f64)>,
    cumulative: Vec<f64>,
}

impl Allowed {
    fn new(sorted: &[f64], dmin: f64) -> Self {
        let mut intervals = Vec::new();
        let mut lo = 0.0;
        for &s in sorted {
            let (a, b) = (s - dmin, s + dmin);
            if a > lo {
                intervals.push((lo, a.min(1.0)));
            }
            lo = lo.max(b);
            if lo >= 1.0 {
                break;
            }
        }
        if lo < 1.0 {
            intervals.push((lo, 1.0));
        }
        let mut cumulative = Vec::with_capacity(intervals.len());
        let mut total = 0.0;
        for &(a, b) in &intervals {
            total += b - a;
            cumulative.push(total);
        }
        Allowed {
            intervals,
            cumulative,
        }
    }

    fn length(&self) -> f64 {
        self.cumulative.last().copied().unwrap_or(0.0)
    }

    /// Maps u in [0, 1) uniformly onto the allowed set.
    fn sample(&self, u: f64) -> f64 {
        let t = u * self.length();
        let i = self
            .cumulative
            .partition_point(|&c| c <= t)
            .min(self.intervals.len() - 1);
        let before = if i == 0 { 0.0 } else { self.cumulative[i - 1] };
        let (a, b) = self.intervals[i];
        (a + (t - before)).min(b)
    }
}

impl Sampler for Mipt {
    fn name(&self) -> &'static str {
        "mipt"
    }

    fn extend(&self, existing: &Points, n_new: usize, seed: u64) -> Result<Points> {
        if !(0.0..=1.0).contains(&self.alpha) {
            return Err(Error::invalid(format!(
                "mipt alpha must lie in [0, 1], found {}",
                self.alpha
            )));
        }
        let d = existing.dim();
        // The stream depends on the design size too: extending a design made with the same seed
        // must not replay the random numbers that placed the existing points.
        let mut r = rng(seed ^ (existing.len() as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
        let mut design = existing.clone();
        // Per-axis sorted projections of the design.
        let mut sorted: Vec<Vec<f64>> = (0..d)
            .map(|k| {
                let mut v: Vec<f64> = design.rows().map(|x| x[k]).collect();
                v.sort_by(f64::total_cmp);
                v
            })
            .collect();
        let mut out = Points::with_capacity(d, n_new);
        let mut cand = vec![0.0; d];
        for _ in 0..n_new {
            let n = design.len();
            let x = if n == 0 {
                (0..d).map(|_| r.random::<f64>()).collect::<Vec<_>>()
            } else {
                let dmin = self.alpha / n as f64;
                let allowed: Vec<Allowed> = sorted.iter().map(|s| Allowed::new(s, dmin)).collect();
                let p: f64 = allowed.iter().map(Allowed::length).product();
                let trials = (self.candidates_per_point * n) as u64;
                let passing = if p <= 0.0 {
                    0
                } else if p >= 1.0 {
                    trials
                } else {
                    Binomial::new(trials, p)
                        .expect("p checked to lie in (0, 1)")
                        .sample(&mut r)
                };
                if passing == 0 {
                    (0..d).map(|_| r.random::<f64>()).collect()
                } else {
                    let mut best = Vec::new();
                    let mut best_d2 = -1.0;
                    for _ in 0..passing {
                        for (c, a) in cand.iter_mut().zip(&allowed) {
                            *c = a.sample(r.random::<f64>());
                        }
                        // Early exit once this candidate cannot beat the best one.
                        let mut m = f64::INFINITY;
                        for y in design.rows() {
                            m = m.min(dist2(&cand, y));
                            if m <= best_d2 {
                                break;
                            }
                        }
                        if m > best_d2 {
                            best_d2 = m;
                            best.clone_from(&cand);
                        }
                    }
                    best
                }
            };
            for (k, s) in sorted.iter_mut().enumerate() {
                let pos = s.partition_point(|&v| v < x[k]);
                s.insert(pos, x[k]);
            }
            design.push(&x);
            out.push(&x);
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn allowed_set_excludes_neighbourhoods() {
        let a = Allowed::new(&[0.2, 0.5], 0.1);
        assert_eq!(a.intervals.len(), 3);
        assert!((a.length() - 0.6).abs() < 1e-12);
        for i in 0..100 {
            let x = a.sample(i as f64 / 100.0);
            assert!(!((0.1..0.3).contains(&x) || (0.4..0.6).contains(&x)), "{x}");
        }
    }
}
