//! Variance-based global sensitivity: Sobol first-order and total indices by the
//! Saltelli/Jansen estimators (Saltelli et al. 2010, Table 2 (b) and (f)), with bootstrap
//! percentile intervals.
//!
//! Two independent N-point matrices A and B come from one scrambled Sobol sequence of dimension
//! 2k (A its first k coordinates, B the rest); A_B^(i) is A with column i taken from B. With
//! V the variance of f over A and B together:
//! - first order S_i = mean(f(B) (f(A_B^(i)) - f(A))) / V: the share of the variance that x_i
//!   explains alone;
//! - total S_Ti = mean((f(A) - f(A_B^(i)))^2) / (2 V): its share with all its interactions.
//!
//! The cost is N (k + 2) evaluations. A point where f is not finite drops its whole index j
//! (A_j, B_j and every A_B^(i)_j) and is counted.

use rand::RngExt;
use serde::Serialize;

use crate::error::{Error, Result};
use crate::sampling::sobol::{scramble_seed, sobol_points, MAX_DIM, MAX_POINTS};

/// Sobol indices of one input with bootstrap percentile intervals.
#[derive(Debug, Clone, Serialize)]
pub struct Index {
    /// First-order index S_i: the share of Var(f) that x_i explains alone, in [0, 1] up to
    /// estimation noise.
    pub first: f64,
    /// 95 % bootstrap percentile interval of S_i.
    pub first_ci95: [f64; 2],
    /// Total index S_Ti: x_i's share including all its interactions, >= S_i up to noise;
    /// near 0 means x_i can be fixed anywhere in its range.
    pub total: f64,
    /// 95 % bootstrap percentile interval of S_Ti.
    pub total_ci95: [f64; 2],
}

/// Sobol indices of every input of one response.
#[derive(Debug, Clone, Serialize)]
pub struct Indices {
    /// Per input, in the inputs' order.
    pub inputs: Vec<Index>,
    /// Variance V of f over A and B together, in the response's unit squared.
    pub variance: f64,
    /// Mean of f over A and B together, in the response's unit.
    pub mean: f64,
    /// Base points used and dropped (f not finite somewhere in the point's set).
    pub samples: usize,
    /// Base points left out because f was not finite at one of their N (k + 2) evaluations.
    pub dropped: usize,
}

/// Fewest bootstrap resamples: the 2.5 % and 97.5 % quantiles need some below and above them.
pub const MIN_BOOTSTRAP: usize = 40;
/// Most bootstrap resamples: beyond this the intervals do not change, only the time grows.
pub const MAX_BOOTSTRAP: usize = 100_000;

/// Refuses a bootstrap count outside [`MIN_BOOTSTRAP`]..=[`MAX_BOOTSTRAP`] (the one range, for
/// the command line to check before any evaluation too).
pub fn check_bootstrap(bootstrap: usize) -> Result<()> {
    if !(MIN_BOOTSTRAP..=MAX_BOOTSTRAP).contains(&bootstrap) {
        return Err(Error::invalid(format!(
            "--bootstrap {bootstrap}: expected {MIN_BOOTSTRAP} to {MAX_BOOTSTRAP} resamples (a 95 % \
             percentile interval needs a few dozen; each costs a pass over the base points)"
        )));
    }
    Ok(())
}

/// Rows of points, `[row][input]`.
pub type Rows = Vec<Vec<f64>>;

/// The base matrices A and B (`[row][input]`, in the unit cube).
pub fn base_matrices(k: usize, n: usize, seed: u64) -> Result<(Rows, Rows)> {
    if k == 0 || 2 * k > MAX_DIM {
        return Err(Error::invalid(format!(
            "sobol indices: {k} inputs; expected 1 to {}",
            MAX_DIM / 2
        )));
    }
    if !(2..=MAX_POINTS).contains(&n) {
        return Err(Error::invalid(format!(
            "sobol indices: --samples {n}; expected 2 to {MAX_POINTS}"
        )));
    }
    // Skip the first point (all coordinates 0.5 after scrambling would still be fine, but an
    // unscrambled origin is a corner many equations are not finite at).
    let pts = sobol_points(2 * k, 1, n, scramble_seed(seed));
    let a = pts.rows().map(|r| r[..k].to_vec()).collect();
    let b = pts.rows().map(|r| r[k..].to_vec()).collect();
    Ok((a, b))
}

/// The rows of A_B^(i).
pub fn mixed(a: &[Vec<f64>], b: &[Vec<f64>], i: usize) -> Vec<Vec<f64>> {
    a.iter()
        .zip(b)
        .map(|(ra, rb)| {
            let mut r = ra.clone();
            r[i] = rb[i];
            r
        })
        .collect()
}

fn point_estimates(
    ya: &[f64],
    yb: &[f64],
    yab: &[Vec<f64>],
    idx: &[usize],
) -> (Vec<(f64, f64)>, f64) {
    let n = idx.len() as f64;
    let mean = idx.iter().map(|&j| ya[j] + yb[j]).sum::<f64>() / (2.0 * n);
    let var = idx
        .iter()
        .map(|&j| (ya[j] - mean).powi(2) + (yb[j] - mean).powi(2))
        .sum::<f64>()
        / (2.0 * n);
    let est = yab
        .iter()
        .map(|yi| {
            let s1 = idx.iter().map(|&j| yb[j] * (yi[j] - ya[j])).sum::<f64>() / n / var;
            let st = idx.iter().map(|&j| (ya[j] - yi[j]).powi(2)).sum::<f64>() / (2.0 * n) / var;
            (s1, st)
        })
        .collect();
    (est, var)
}

/// Indices from the evaluations f(A), f(B) and f(A_B^(i)) of one response, with `bootstrap`
/// resamples (seeded) for the 95 % intervals.
pub fn estimate(
    ya: &[f64],
    yb: &[f64],
    yab: &[Vec<f64>],
    bootstrap: usize,
    seed: u64,
) -> Result<Indices> {
    check_bootstrap(bootstrap)?;
    let n = ya.len();
    let keep: Vec<usize> = (0..n)
        .filter(|&j| ya[j].is_finite() && yb[j].is_finite() && yab.iter().all(|y| y[j].is_finite()))
        .collect();
    if keep.len() < 2 {
        return Err(Error::invalid(format!(
            "sobol indices: only {} of {n} base points have finite values",
            keep.len()
        )));
    }
    let (est, var) = point_estimates(ya, yb, yab, &keep);
    let mean = keep.iter().map(|&j| ya[j] + yb[j]).sum::<f64>() / (2 * keep.len()) as f64;
    if var <= 0.0 {
        return Err(Error::invalid(
            "sobol indices: the response does not vary over the domain (variance 0)",
        ));
    }
    let mut rng = crate::sampling::rng(seed);
    let k = yab.len();
    let mut firsts = vec![Vec::with_capacity(bootstrap); k];
    let mut totals = vec![Vec::with_capacity(bootstrap); k];
    let mut idx = vec![0usize; keep.len()];
    for _ in 0..bootstrap {
        for v in idx.iter_mut() {
            *v = keep[rng.random_range(0..keep.len())];
        }
        let (e, _) = point_estimates(ya, yb, yab, &idx);
        for (i, (s1, st)) in e.into_iter().enumerate() {
            firsts[i].push(s1);
            totals[i].push(st);
        }
    }
    let ci = |v: &mut Vec<f64>| -> [f64; 2] {
        v.retain(|x| x.is_finite());
        if v.is_empty() {
            return [f64::NAN, f64::NAN];
        }
        v.sort_by(f64::total_cmp);
        [
            crate::numeric::quantile_sorted(v, 0.025),
            crate::numeric::quantile_sorted(v, 0.975),
        ]
    };
    let inputs = est
        .into_iter()
        .enumerate()
        .map(|(i, (s1, st))| Index {
            first: s1,
            first_ci95: ci(&mut firsts[i]),
            total: st,
            total_ci95: ci(&mut totals[i]),
        })
        .collect();
    Ok(Indices {
        inputs,
        variance: var,
        mean,
        samples: n,
        dropped: n - keep.len(),
    })
}

/// An input's physical value from a unit-cube coordinate over its domain: log-uniform for an
/// input the model reads through a log, uniform otherwise.
pub fn input_from_unit(inp: &crate::metamodel::Input, u: f64) -> f64 {
    let [lo, hi] = inp.domain;
    match inp.transform {
        crate::metamodel::Transform::Log { .. } if lo > 0.0 => {
            (lo.ln() + u * (hi.ln() - lo.ln())).exp()
        }
        _ => lo + u * (hi - lo),
    }
}

/// Indices of the named responses of a saved model over its own domain (N base points).
pub fn model_indices(
    model: &crate::metamodel::Metamodel,
    responses: &[String],
    n: usize,
    seed: u64,
    bootstrap: usize,
) -> Result<Vec<(String, Indices)>> {
    let k = model.inputs.len();
    let (ua, ub) = base_matrices(k, n, seed)?;
    let phys = |rows: &[Vec<f64>]| -> Rows {
        (0..k)
            .map(|j| {
                rows.iter()
                    .map(|r| input_from_unit(&model.inputs[j], r[j]))
                    .collect()
            })
            .collect()
    };
    let (xa, xb) = (phys(&ua), phys(&ub));
    let xab: Vec<Rows> = (0..k).map(|i| phys(&mixed(&ua, &ub, i))).collect();
    responses
        .iter()
        .map(|name| {
            let rm = model
                .response(name)
                .ok_or_else(|| Error::invalid(format!("response {name}: not in the model")))?;
            let ya = model.predict(rm, &xa);
            let yb = model.predict(rm, &xb);
            let yab: Rows = xab.iter().map(|x| model.predict(rm, x)).collect();
            let s = estimate(&ya, &yb, &yab, bootstrap, seed)
                .map_err(|e| Error::invalid(format!("response {name}: {e}")))?;
            Ok((name.clone(), s))
        })
        .collect()
}

/// The Ishigami function (a = 7, b = 0.1) on [-pi, pi]^3 from unit-cube coordinates: the
/// standard test of Sobol estimators, with known indices [`ISHIGAMI_FIRST`], [`ISHIGAMI_TOTAL`].
pub fn ishigami(u: &[f64]) -> f64 {
    use std::f64::consts::PI;
    let x: Vec<f64> = u.iter().map(|v| -PI + 2.0 * PI * v).collect();
    x[0].sin() + 7.0 * x[1].sin().powi(2) + 0.1 * x[2].powi(4) * x[0].sin()
}

/// Analytic first-order indices of the Ishigami function with a = 7, b = 0.1.
pub const ISHIGAMI_FIRST: [f64; 3] = [0.313_905, 0.442_411, 0.0];
/// Analytic total indices of the Ishigami function with a = 7, b = 0.1.
pub const ISHIGAMI_TOTAL: [f64; 3] = [0.557_589, 0.442_411, 0.243_684];

#[cfg(test)]
mod tests {
    use super::*;

    fn run(n: usize, seed: u64) -> Indices {
        let (a, b) = base_matrices(3, n, seed).unwrap();
        let f = |rows: &[Vec<f64>]| rows.iter().map(|r| ishigami(r)).collect::<Vec<f64>>();
        let yab: Vec<Vec<f64>> = (0..3).map(|i| f(&mixed(&a, &b, i))).collect();
        estimate(&f(&a), &f(&b), &yab, 300, seed).unwrap()
    }

    #[test]
    fn ishigami_indices_are_recovered_within_their_intervals() {
        let s = run(8192, 7);
        for i in 0..3 {
            let x = &s.inputs[i];
            assert!(
                (x.first - ISHIGAMI_FIRST[i]).abs() < 0.03,
                "S{} = {}",
                i + 1,
                x.first
            );
            assert!(
                (x.total - ISHIGAMI_TOTAL[i]).abs() < 0.03,
                "ST{} = {}",
                i + 1,
                x.total
            );
            let w = 0.02;
            assert!(
                x.first_ci95[0] - w <= ISHIGAMI_FIRST[i]
                    && ISHIGAMI_FIRST[i] <= x.first_ci95[1] + w
            );
            assert!(
                x.total_ci95[0] - w <= ISHIGAMI_TOTAL[i]
                    && ISHIGAMI_TOTAL[i] <= x.total_ci95[1] + w
            );
            assert!(x.first_ci95[1] - x.first_ci95[0] < 0.15);
        }
        // V = a^2/8 + b pi^4/5 + b^2 pi^8/18 + 1/2 = 13.8446
        assert!((s.variance - 13.8446).abs() < 0.4, "{}", s.variance);
    }

    #[test]
    fn same_seed_same_indices_and_intervals_shrink_with_samples() {
        let a = run(1024, 3);
        let b = run(1024, 3);
        assert_eq!(a.inputs[0].first, b.inputs[0].first);
        assert_eq!(a.inputs[2].total_ci95, b.inputs[2].total_ci95);
        let big = run(8192, 3);
        let w = |s: &Indices| s.inputs[0].total_ci95[1] - s.inputs[0].total_ci95[0];
        assert!(w(&big) < w(&a), "{} vs {}", w(&big), w(&a));
    }

    #[test]
    fn non_finite_points_are_dropped_and_counted() {
        let (a, b) = base_matrices(2, 64, 1).unwrap();
        let f = |rows: &[Vec<f64>]| {
            rows.iter()
                .map(|r| {
                    if r[0] < 0.1 {
                        f64::NAN
                    } else {
                        r[0] + 2.0 * r[1]
                    }
                })
                .collect::<Vec<f64>>()
        };
        let yab: Vec<Vec<f64>> = (0..2).map(|i| f(&mixed(&a, &b, i))).collect();
        let s = estimate(&f(&a), &f(&b), &yab, 50, 1).unwrap();
        assert!(s.dropped > 0 && s.dropped < 64);
    }
}
