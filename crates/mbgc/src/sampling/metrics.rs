//! Space-filling and uniformity metrics of a unit-cube design.
//!
//! - MID, the minimum intersite distance (maximin criterion; larger is better).
//! - COV, the cover measure of Gunzburger & Burkardt (2004): the coefficient of variation
//!   (population form) of the nearest-neighbour distances; 0 for a regular grid, smaller is better.
//! - CD and WD, the centered and wrap-around L2 discrepancies, squared, as
//!   `scipy.stats.qmc.discrepancy` returns them (Hickernell 1998); smaller is better.

use rayon::prelude::*;
use serde::Serialize;

use super::points::{dist2, Points};

/// Space-filling and uniformity metrics of one design, as written to design reports.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Metrics {
    /// Number of points.
    pub n: usize,
    /// Dimension of the unit cube (number of free parameters).
    pub dim: usize,
    /// Minimum intersite distance in unit-cube coordinates, in (0, sqrt(dim)]; larger is better.
    pub mid: f64,
    /// Cover measure: coefficient of variation of the nearest-neighbour distances, >= 0; 0 for a
    /// regular grid, smaller is better.
    pub cov: f64,
    /// Squared centered L2 discrepancy (Hickernell 1998); smaller is more uniform.
    pub cd: f64,
    /// Squared wrap-around L2 discrepancy, which treats the cube as a torus; smaller is more
    /// uniform.
    pub wd: f64,
}

/// All metrics; needs at least two points.
pub fn metrics(p: &Points) -> Metrics {
    let nn = nearest_neighbour_distances(p);
    Metrics {
        n: p.len(),
        dim: p.dim(),
        mid: nn.iter().copied().fold(f64::INFINITY, f64::min),
        cov: cover_measure(&nn),
        cd: centered_l2(p),
        wd: wraparound_l2(p),
    }
}

/// Distance from each point to its nearest other point (parallel over points).
pub fn nearest_neighbour_distances(p: &Points) -> Vec<f64> {
    let n = p.len();
    (0..n)
        .into_par_iter()
        .map(|i| {
            let xi = p.row(i);
            (0..n)
                .filter(|&j| j != i)
                .map(|j| dist2(xi, p.row(j)))
                .fold(f64::INFINITY, f64::min)
                .sqrt()
        })
        .collect()
}

/// Minimum intersite distance (maximin criterion) of a design of at least two points.
pub fn mid(p: &Points) -> f64 {
    nearest_neighbour_distances(p)
        .into_iter()
        .fold(f64::INFINITY, f64::min)
}

/// Cover measure of Gunzburger & Burkardt (2004): population coefficient of variation of the
/// nearest-neighbour distances; needs at least two points.
pub fn cov(p: &Points) -> f64 {
    cover_measure(&nearest_neighbour_distances(p))
}

fn cover_measure(nn: &[f64]) -> f64 {
    let n = nn.len() as f64;
    let mean = nn.iter().sum::<f64>() / n;
    let var = nn.iter().map(|g| (g - mean).powi(2)).sum::<f64>() / n;
    var.sqrt() / mean
}

/// Sum over all ordered pairs (i, j) of f(x_i, x_j), parallel over i. Summation order is fixed
/// per row, and rows are summed in order, so the result does not depend on the thread count.
fn pair_sum(p: &Points, f: impl Fn(&[f64], &[f64]) -> f64 + Sync) -> f64 {
    let n = p.len();
    let rows: Vec<f64> = (0..n)
        .into_par_iter()
        .map(|i| (0..n).map(|j| f(p.row(i), p.row(j))).sum())
        .collect();
    rows.iter().sum()
}

/// Squared centered L2 discrepancy.
pub fn centered_l2(p: &Points) -> f64 {
    let n = p.len() as f64;
    let d = p.dim() as i32;
    let s1: f64 = p
        .rows()
        .map(|x| {
            x.iter()
                .map(|&v| {
                    let a = (v - 0.5).abs();
                    1.0 + 0.5 * a - 0.5 * a * a
                })
                .product::<f64>()
        })
        .sum();
    let s2 = pair_sum(p, |x, y| {
        x.iter()
            .zip(y)
            .map(|(&a, &b)| {
                1.0 + 0.5 * (a - 0.5).abs() + 0.5 * (b - 0.5).abs() - 0.5 * (a - b).abs()
            })
            .product()
    });
    (13.0f64 / 12.0).powi(d) - 2.0 / n * s1 + s2 / (n * n)
}

/// Squared wrap-around L2 discrepancy.
pub fn wraparound_l2(p: &Points) -> f64 {
    let n = p.len() as f64;
    let d = p.dim() as i32;
    let s = pair_sum(p, |x, y| {
        x.iter()
            .zip(y)
            .map(|(&a, &b)| {
                let t = (a - b).abs();
                1.5 - t * (1.0 - t)
            })
            .product()
    });
    -(4.0f64 / 3.0).powi(d) + s / (n * n)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// scipy's documentation example (`numeric_constants.md`, space_1).
    fn space_1() -> Points {
        let raw = [[1., 3.], [2., 6.], [3., 2.], [4., 5.], [5., 1.], [6., 4.]];
        let rows: Vec<Vec<f64>> = raw
            .iter()
            .map(|r| r.iter().map(|v| (v * 2.0 - 1.0) / 12.0).collect())
            .collect();
        Points::from_rows(2, &rows)
    }

    #[test]
    fn match_reference_constants() {
        let m = metrics(&space_1());
        assert!((m.cd - 0.008142039609053464).abs() < 1e-12, "cd {}", m.cd);
        assert!((m.wd - 0.01684670781892894).abs() < 1e-12, "wd {}", m.wd);
        assert!((m.mid - 0.3726779962499649).abs() < 1e-12, "mid {}", m.mid);
        assert!(m.cov < 1e-12, "cov {}", m.cov);
    }

    #[test]
    fn grid_has_zero_cover_and_clumps_have_large_cover() {
        let grid: Vec<Vec<f64>> = (0..4)
            .flat_map(|i| {
                (0..4).map(move |j| vec![0.125 + 0.25 * i as f64, 0.125 + 0.25 * j as f64])
            })
            .collect();
        let g = Points::from_rows(2, &grid);
        assert!(cov(&g) < 1e-12);
        assert!((mid(&g) - 0.25).abs() < 1e-12);
        let mut clumped = grid.clone();
        clumped[0] = vec![0.125, 0.36];
        let c = Points::from_rows(2, &clumped);
        assert!(cov(&c) > 0.2);
    }
}
