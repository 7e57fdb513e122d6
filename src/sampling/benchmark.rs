//! Comparison of the design methods, after seed 004 (Richter & Will 2021, Figs. 7 and 8): many
//! seeds per method, MID and COV in 2 and 10 dimensions; plus the extension check (a design
//! extended from half its size against a one-shot design) and the generation time of large
//! designs.

use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;

use super::{extend_design, lhs::Lhs, metrics::metrics, Method, Points};
use crate::error::Result;

#[derive(Debug, Clone, Serialize)]
pub struct QualityRun {
    pub method: &'static str,
    pub dim: usize,
    pub seed: u64,
    pub mid: f64,
    pub cov: f64,
    pub cd: f64,
    pub wd: f64,
}

/// One-shot designs of `n` points for every method, dimension and seed.
pub fn quality(
    methods: &[Method],
    dims: &[usize],
    n: usize,
    seeds: &[u64],
) -> Result<Vec<QualityRun>> {
    let jobs: Vec<(Method, usize, u64)> = methods
        .iter()
        .flat_map(|&m| {
            dims.iter()
                .flat_map(move |&d| seeds.iter().map(move |&s| (m, d, s)))
        })
        .collect();
    jobs.par_iter()
        .map(|&(m, d, s)| {
            let p = extend_design(m.sampler().as_ref(), &Points::new(d), n, s)?;
            let q = metrics(&p);
            Ok(QualityRun {
                method: m.name(),
                dim: d,
                seed: s,
                mid: q.mid,
                cov: q.cov,
                cd: q.cd,
                wd: q.wd,
            })
        })
        .collect()
}

#[derive(Debug, Clone, Serialize)]
pub struct ExtensionRun {
    pub method: &'static str,
    pub dim: usize,
    /// Where the first half came from: the same method and seed ("own") or a maximin LHS from
    /// another seed ("foreign"), standing for a user's design.
    pub base: &'static str,
    pub mid_base: f64,
    pub mid_extended: f64,
    pub mid_one_shot: f64,
}

impl ExtensionRun {
    /// MID of the extended design against what it could reach: the one-shot design's MID, or
    /// the base's own MID if that is smaller, since new points cannot move the old ones apart.
    pub fn ratio(&self) -> f64 {
        self.mid_extended / self.mid_one_shot.min(self.mid_base)
    }
}

/// Designs of `n` points built as `n/2` points extended by `n/2`, against one-shot designs of `n`.
pub fn extension(
    methods: &[Method],
    dims: &[usize],
    n: usize,
    seeds: &[u64],
) -> Result<Vec<ExtensionRun>> {
    let jobs: Vec<(Method, usize, u64, bool)> = methods
        .iter()
        .filter(|m| m.sampler().sequential())
        .flat_map(|&m| {
            dims.iter().flat_map(move |&d| {
                seeds
                    .iter()
                    .flat_map(move |&s| [(m, d, s, false), (m, d, s, true)])
            })
        })
        .collect();
    jobs.par_iter()
        .map(|&(m, d, s, foreign)| {
            let sampler = m.sampler();
            let half = n / 2;
            let mut base = if foreign {
                extend_design(&Lhs::maximin(), &Points::new(d), half, s + 1000)?
            } else {
                extend_design(sampler.as_ref(), &Points::new(d), half, s)?
            };
            let mid_base = metrics(&base).mid;
            let new = extend_design(sampler.as_ref(), &base, n - half, s)?;
            base.append(&new);
            let one = extend_design(sampler.as_ref(), &Points::new(d), n, s)?;
            Ok(ExtensionRun {
                method: m.name(),
                dim: d,
                base: if foreign { "foreign" } else { "own" },
                mid_base,
                mid_extended: metrics(&base).mid,
                mid_one_shot: metrics(&one).mid,
            })
        })
        .collect()
}

#[derive(Debug, Clone, Serialize)]
pub struct Timing {
    pub method: &'static str,
    pub n: usize,
    pub dim: usize,
    /// Fastest of the repetitions, seconds.
    pub best_s: f64,
    /// Median of the repetitions, seconds.
    pub median_s: f64,
}

/// Wall time to generate one design of `n` points in `dim` dimensions, per method.
pub fn timing(methods: &[Method], n: usize, dim: usize, repeats: usize) -> Result<Vec<Timing>> {
    methods
        .iter()
        .map(|&m| {
            let sampler = m.sampler();
            let mut times = Vec::with_capacity(repeats);
            for r in 0..repeats.max(1) {
                let t = Instant::now();
                let p = extend_design(sampler.as_ref(), &Points::new(dim), n, r as u64 + 1)?;
                times.push(t.elapsed().as_secs_f64());
                std::hint::black_box(p);
            }
            times.sort_by(f64::total_cmp);
            Ok(Timing {
                method: m.name(),
                n,
                dim,
                best_s: times[0],
                median_s: times[times.len() / 2],
            })
        })
        .collect()
}

/// Mean, minimum and maximum.
pub fn summary(v: &[f64]) -> (f64, f64, f64) {
    let mean = v.iter().sum::<f64>() / v.len() as f64;
    let min = v.iter().copied().fold(f64::INFINITY, f64::min);
    let max = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    (mean, min, max)
}

/// Values of one metric for one method and dimension, in seed order.
pub fn select(
    runs: &[QualityRun],
    method: &str,
    dim: usize,
    f: impl Fn(&QualityRun) -> f64,
) -> Vec<f64> {
    runs.iter()
        .filter(|r| r.method == method && r.dim == dim)
        .map(f)
        .collect()
}
