//! Transitional Markov chain Monte Carlo (TMCMC) for Bayesian calibration and evidence.
//!
//! The algorithm of Ching & Chen (2007, J. Eng. Mech. 133(7):816) with the changes of Betz,
//! Papaioannou & Straub (2016, J. Eng. Mech. 142(5):04016016):
//!
//! 1. draw `samples` points from the prior and evaluate the log-likelihood;
//! 2. choose the next tempering exponent `p_{j+1}` by bisection so that the coefficient of
//!    variation of the plausibility weights `w_i = L(theta_i)^(p_{j+1} - p_j)` equals
//!    `cov_target` (1 by default), or take `p = 1` if that step already stays below it;
//! 3. add `ln(mean(w))` (log-sum-exp) to the log-evidence;
//! 4. resample chain seeds proportionally to the weights and run random-walk Metropolis chains
//!    on `prior * L^p_{j+1}` with a Gaussian proposal of covariance `beta^2 * Sigma_w`
//!    (`Sigma_w` the weighted sample covariance of the stage);
//! 5. adapt `beta` from the stage's acceptance rate, `beta <- beta * exp(acc - acc*)`
//!    (the Papaioannou et al. 2015 / Betz et al. 2016 rule), and repeat until `p = 1`.
//!
//! Every chain has its own `ChaCha8Rng` seeded from `(seed, stage, chain)`, so the chains can
//! run on rayon threads and the result is the same for a seed whatever the thread count.

use crate::numeric::{quantile_sorted, splitmix64};
use nalgebra::{DMatrix, DVector};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use rayon::prelude::*;

/// A prior distribution over the calibration parameters.
pub trait Prior: Sync {
    /// Number of parameters.
    fn dim(&self) -> usize;
    /// One draw from the prior.
    fn sample(&self, rng: &mut ChaCha8Rng) -> Vec<f64>;
    /// Normalised ln density (the evidence is only right if it integrates to 1); `-inf` outside
    /// the support.
    fn ln_pdf(&self, x: &[f64]) -> f64;
    /// Checks the parameters of the prior; [`tmcmc`] calls it before sampling.
    fn validate(&self) -> Result<(), String> {
        Ok(())
    }
}

/// Independent uniform prior on the box `[lower, upper]`.
#[derive(Debug, Clone, PartialEq)]
pub struct UniformBox {
    /// Lower bound per dimension (finite).
    pub lower: Vec<f64>,
    /// Upper bound per dimension (finite, above the lower one).
    pub upper: Vec<f64>,
}

impl UniformBox {
    /// A validated box.
    pub fn new(lower: Vec<f64>, upper: Vec<f64>) -> Result<Self, String> {
        let b = Self { lower, upper };
        b.validate()?;
        Ok(b)
    }
}

impl Prior for UniformBox {
    fn dim(&self) -> usize {
        self.lower.len()
    }

    fn sample(&self, rng: &mut ChaCha8Rng) -> Vec<f64> {
        self.lower
            .iter()
            .zip(&self.upper)
            .map(|(&l, &u)| l + (u - l) * rng.random::<f64>())
            .collect()
    }

    fn ln_pdf(&self, x: &[f64]) -> f64 {
        if x.len() != self.lower.len() {
            return f64::NEG_INFINITY;
        }
        let mut ln_p = 0.0;
        for ((&xi, &l), &u) in x.iter().zip(&self.lower).zip(&self.upper) {
            // `!(a <= b)` so that NaN coordinates fall outside the support too.
            if !(l <= xi && xi <= u) {
                return f64::NEG_INFINITY;
            }
            ln_p -= (u - l).ln();
        }
        ln_p
    }

    fn validate(&self) -> Result<(), String> {
        if self.lower.len() != self.upper.len() {
            return Err(format!(
                "uniform prior: {} lower bounds but {} upper bounds",
                self.lower.len(),
                self.upper.len()
            ));
        }
        for (k, (&l, &u)) in self.lower.iter().zip(&self.upper).enumerate() {
            if !(l.is_finite() && u.is_finite()) {
                return Err(format!(
                    "uniform prior: bounds of dim {k} must be finite ({l}, {u})"
                ));
            }
            if l >= u {
                return Err(format!(
                    "uniform prior: lower bound {l} >= upper bound {u} in dim {k}"
                ));
            }
        }
        Ok(())
    }
}

/// Independent Gaussian prior `N(mean_k, sd_k^2)` per dimension.
#[derive(Debug, Clone, PartialEq)]
pub struct GaussianPrior {
    /// Mean per dimension.
    pub mean: Vec<f64>,
    /// Standard deviation per dimension (> 0).
    pub sd: Vec<f64>,
}

impl Prior for GaussianPrior {
    fn dim(&self) -> usize {
        self.mean.len()
    }

    fn sample(&self, rng: &mut ChaCha8Rng) -> Vec<f64> {
        self.mean
            .iter()
            .zip(&self.sd)
            .map(|(&m, &s)| m + s * rng.sample::<f64, _>(StandardNormal))
            .collect()
    }

    fn ln_pdf(&self, x: &[f64]) -> f64 {
        if x.len() != self.mean.len() {
            return f64::NEG_INFINITY;
        }
        let ln_2pi = (2.0 * std::f64::consts::PI).ln();
        let mut ln_p = 0.0;
        for ((&xi, &m), &s) in x.iter().zip(&self.mean).zip(&self.sd) {
            let z = (xi - m) / s;
            ln_p -= 0.5 * (ln_2pi + z * z) + s.ln();
        }
        if ln_p.is_nan() {
            f64::NEG_INFINITY
        } else {
            ln_p
        }
    }

    fn validate(&self) -> Result<(), String> {
        if self.mean.len() != self.sd.len() {
            return Err(format!(
                "Gaussian prior: {} means but {} standard deviations",
                self.mean.len(),
                self.sd.len()
            ));
        }
        for (k, (&m, &s)) in self.mean.iter().zip(&self.sd).enumerate() {
            if !(m.is_finite() && s.is_finite() && s > 0.0) {
                return Err(format!(
                    "Gaussian prior: dim {k} needs a finite mean and sd > 0 (got {m}, {s})"
                ));
            }
        }
        Ok(())
    }
}

/// Settings of [`tmcmc`].
#[derive(Debug, Clone, PartialEq)]
pub struct TmcmcOptions {
    /// Samples per stage (and final posterior samples).
    pub samples: usize,
    /// States recorded per chain after burn-in; `ceil(samples / chain_length)` seeds are drawn.
    /// Values > 1 save likelihood calls but give fewer, correlated lineages (more ln Z scatter
    /// than spending the same calls on `burn_in`).
    pub chain_length: usize,
    /// Metropolis steps per chain discarded before recording. 0 is classic TMCMC, fine in
    /// 1-2 dimensions; from ~4 dimensions one step per stage leaves the population too
    /// correlated (ln Z scattered by ~0.8 on the 4-D test problems) and 10-20 are advisable.
    pub burn_in: usize,
    /// Target coefficient of variation of the plausibility weights.
    pub cov_target: f64,
    /// Maximum number of tempering stages before giving up.
    pub max_stages: usize,
    /// Seed of every random stream (prior draws, resampling, each chain): equal seeds give equal
    /// results on any number of threads.
    pub seed: u64,
    /// Initial proposal scale; `<= 0` or non-finite means `2.4 / sqrt(dim)`.
    pub initial_beta: f64,
    /// Acceptance rate that the `beta` adaptation steers towards.
    pub target_acceptance: f64,
}

impl Default for TmcmcOptions {
    fn default() -> Self {
        Self {
            samples: 2000,
            chain_length: 1,
            burn_in: 0,
            cov_target: 1.0,
            max_stages: 100,
            seed: 0,
            initial_beta: 0.0,
            target_acceptance: 0.23,
        }
    }
}

/// Diagnostics of one tempering stage.
#[derive(Debug, Clone, PartialEq)]
pub struct StageInfo {
    /// Tempering exponent reached by this stage.
    pub p: f64,
    /// Metropolis acceptance rate of the stage's chains.
    pub acceptance: f64,
    /// Proposal scale used in this stage.
    pub beta: f64,
    /// `ln(mean of the plausibility weights)`, this stage's term of the log-evidence.
    pub ln_mean_weight: f64,
}

/// Output of [`tmcmc`].
#[derive(Debug, Clone, PartialEq)]
pub struct TmcmcResult {
    /// Final posterior samples, equally weighted.
    pub samples: Vec<Vec<f64>>,
    /// ln likelihood of each sample.
    pub ln_likelihood: Vec<f64>,
    /// Natural log of the model evidence.
    pub ln_evidence: f64,
    /// Diagnostics of each tempering stage, in order (the last reaches `p = 1`).
    pub stages: Vec<StageInfo>,
}

impl TmcmcResult {
    fn dim(&self) -> usize {
        self.samples.first().map_or(0, Vec::len)
    }

    /// Posterior mean per dimension.
    pub fn mean(&self) -> Vec<f64> {
        let n = self.samples.len() as f64;
        let mut m = vec![0.0; self.dim()];
        for s in &self.samples {
            for (mk, &x) in m.iter_mut().zip(s) {
                *mk += x / n;
            }
        }
        m
    }

    /// Posterior standard deviation per dimension (1/(n-1) normalisation).
    pub fn std(&self) -> Vec<f64> {
        let m = self.mean();
        let denom = (self.samples.len() as f64 - 1.0).max(1.0);
        let mut v = vec![0.0; m.len()];
        for s in &self.samples {
            for ((vk, &x), &mk) in v.iter_mut().zip(s).zip(&m) {
                *vk += (x - mk) * (x - mk);
            }
        }
        v.iter().map(|vk| (vk / denom).sqrt()).collect()
    }

    /// Posterior coefficient of variation `std / |mean|` per dimension.
    pub fn cov(&self) -> Vec<f64> {
        self.std()
            .iter()
            .zip(self.mean())
            .map(|(s, m)| s / m.abs())
            .collect()
    }

    /// Empirical `q`-quantile of dimension `dim` (linear interpolation between order
    /// statistics); NaN for `q` outside `[0, 1]`. Panics if `dim` is out of range.
    pub fn quantile(&self, dim: usize, q: f64) -> f64 {
        let mut v: Vec<f64> = self.samples.iter().map(|s| s[dim]).collect();
        if v.is_empty() || !(0.0..=1.0).contains(&q) {
            return f64::NAN;
        }
        v.sort_by(f64::total_cmp);
        quantile_sorted(&v, q)
    }
}

/// Most samples per stage: 1e6 samples of a 12-dimensional posterior hold about 100 MB per
/// stage; more would exhaust memory long before the estimate improved.
pub const MAX_SAMPLES: usize = 1_000_000;

/// Samples the posterior `prior * exp(ln_likelihood)` and estimates its log-evidence.
///
/// `ln_likelihood` returns `-inf` for impossible points (NaN is treated as `-inf`; `+inf` is an
/// error).
pub fn tmcmc<F: Fn(&[f64]) -> f64 + Sync>(
    prior: &dyn Prior,
    ln_likelihood: F,
    opts: &TmcmcOptions,
) -> Result<TmcmcResult, String> {
    let d = prior.dim();
    if d == 0 {
        return Err("tmcmc: the prior has dimension 0".into());
    }
    prior.validate()?;
    let n = opts.samples;
    if !(10..=MAX_SAMPLES).contains(&n) {
        return Err(format!(
            "tmcmc: samples = {n}; expected 10 to {MAX_SAMPLES} per stage (each stage keeps \
             them all with their likelihoods)"
        ));
    }
    if opts.chain_length == 0 {
        return Err("tmcmc: chain_length must be at least 1".into());
    }
    if !(opts.cov_target.is_finite() && opts.cov_target > 0.0) {
        return Err(format!(
            "tmcmc: cov_target must be > 0 (got {})",
            opts.cov_target
        ));
    }
    if !(opts.target_acceptance > 0.0 && opts.target_acceptance < 1.0) {
        return Err(format!(
            "tmcmc: target_acceptance must be in (0, 1) (got {})",
            opts.target_acceptance
        ));
    }
    let ln_l = |x: &[f64]| {
        let v = ln_likelihood(x);
        if v.is_nan() {
            f64::NEG_INFINITY
        } else {
            v
        }
    };

    // Stage 0: prior draws from one sequential stream, likelihoods in parallel.
    let mut rng = ChaCha8Rng::seed_from_u64(mix(opts.seed, u64::MAX, 0));
    let mut theta: Vec<Vec<f64>> = (0..n).map(|_| prior.sample(&mut rng)).collect();
    if let Some(bad) = theta.iter().find(|t| t.len() != d) {
        return Err(format!(
            "tmcmc: prior sample has {} coordinates, dim() is {d}",
            bad.len()
        ));
    }
    let mut lnl: Vec<f64> = theta.par_iter().map(|t| ln_l(t)).collect();
    let mut lnp: Vec<f64> = theta.iter().map(|t| prior.ln_pdf(t)).collect();
    check_no_pos_inf(&lnl)?;
    if lnl.iter().all(|&l| l == f64::NEG_INFINITY) {
        return Err(format!(
            "tmcmc: the likelihood is zero (-inf) at all {n} prior samples"
        ));
    }

    let mut beta = if opts.initial_beta.is_finite() && opts.initial_beta > 0.0 {
        opts.initial_beta
    } else {
        2.4 / (d as f64).sqrt()
    };
    let n_chains = n.div_ceil(opts.chain_length);
    let steps = opts.burn_in + opts.chain_length;
    let mut p = 0.0;
    let mut ln_z = 0.0;
    let mut stages: Vec<StageInfo> = Vec::new();

    while p < 1.0 {
        if stages.len() >= opts.max_stages {
            return Err(format!(
                "tmcmc: max_stages = {} reached at tempering exponent p = {p:.3e}",
                opts.max_stages
            ));
        }
        let stage = stages.len() as u64;
        let p_new = next_exponent(&lnl, p, opts.cov_target);
        let dp = p_new - p;

        // Plausibility weights and this stage's evidence factor, in logs against underflow.
        let ln_w: Vec<f64> = lnl.iter().map(|&l| tempered(dp, l)).collect();
        let lse = log_sum_exp(&ln_w);
        let ln_mean_weight = lse - (n as f64).ln();
        ln_z += ln_mean_weight;
        let w: Vec<f64> = ln_w.iter().map(|&lw| (lw - lse).exp()).collect();

        let chol = proposal_factor(&theta, &w, beta);

        let mut rs_rng = ChaCha8Rng::seed_from_u64(mix(opts.seed, stage, u64::MAX));
        let seeds = systematic_resample(&w, n_chains, &mut rs_rng);

        let chains: Vec<(Vec<State>, usize)> = seeds
            .par_iter()
            .enumerate()
            .map(|(c, &i)| {
                let mut crng = ChaCha8Rng::seed_from_u64(mix(opts.seed, stage, c as u64));
                run_chain(
                    prior,
                    &ln_l,
                    &chol,
                    p_new,
                    (theta[i].clone(), lnp[i], lnl[i]),
                    opts.burn_in,
                    steps,
                    &mut crng,
                )
            })
            .collect();

        let mut accepted = 0;
        theta.clear();
        lnl.clear();
        lnp.clear();
        for (states, acc) in chains {
            accepted += acc;
            for (t, lp, ll) in states {
                if theta.len() < n {
                    theta.push(t);
                    lnp.push(lp);
                    lnl.push(ll);
                }
            }
        }
        check_no_pos_inf(&lnl)?;
        let acceptance = accepted as f64 / (n_chains * steps) as f64;
        stages.push(StageInfo {
            p: p_new,
            acceptance,
            beta,
            ln_mean_weight,
        });
        // Clamped so one stage of zero acceptance cannot collapse the proposal for good.
        beta = (beta * (acceptance - opts.target_acceptance).exp()).clamp(1e-3, 10.0);
        p = p_new;
    }

    Ok(TmcmcResult {
        samples: theta,
        ln_likelihood: lnl,
        ln_evidence: ln_z,
        stages,
    })
}

/// A chain state: `(theta, ln prior, ln likelihood)`.
type State = (Vec<f64>, f64, f64);

/// One random-walk Metropolis chain on `prior * L^p`; returns the recorded states
/// `(theta, ln prior, ln L)` and the number of accepted moves.
#[allow(clippy::too_many_arguments)]
fn run_chain<G: Fn(&[f64]) -> f64>(
    prior: &dyn Prior,
    ln_l: &G,
    chol: &DMatrix<f64>,
    p: f64,
    start: State,
    burn_in: usize,
    steps: usize,
    rng: &mut ChaCha8Rng,
) -> (Vec<State>, usize) {
    let d = start.0.len();
    let (mut x, mut lp, mut ll) = start;
    let mut out = Vec::with_capacity(steps - burn_in);
    let mut accepted = 0;
    let mut z = DVector::<f64>::zeros(d);
    for step in 0..steps {
        for zk in z.iter_mut() {
            *zk = rng.sample(StandardNormal);
        }
        let dx = chol * &z;
        let y: Vec<f64> = x.iter().zip(dx.iter()).map(|(a, b)| a + b).collect();
        let u: f64 = rng.random();
        let lp_y = prior.ln_pdf(&y);
        // Outside the prior's support: reject without paying for a likelihood evaluation.
        if lp_y > f64::NEG_INFINITY {
            let ll_y = ln_l(&y);
            let ln_ratio = (lp_y + tempered(p, ll_y)) - (lp + tempered(p, ll));
            // NaN ratios (both targets -inf) compare false and are rejected.
            if u.ln() < ln_ratio {
                x = y;
                lp = lp_y;
                ll = ll_y;
                accepted += 1;
            }
        }
        if step >= burn_in {
            out.push((x.clone(), lp, ll));
        }
    }
    (out, accepted)
}

/// `p * ln L`, keeping impossible points impossible at `p = 0` (avoids `0 * -inf = NaN`).
fn tempered(p: f64, ln_l: f64) -> f64 {
    if ln_l == f64::NEG_INFINITY {
        f64::NEG_INFINITY
    } else {
        p * ln_l
    }
}

/// Next tempering exponent: the largest `p' <= 1` whose weights `L^(p' - p)` have a
/// coefficient of variation at most `target`. The c.o.v. grows monotonically with the step
/// (log of `E[w^2]/E[w]^2` is a difference of a convex cumulant function), so bisection works.
fn next_exponent(ln_l: &[f64], p: f64, target: f64) -> f64 {
    let room = 1.0 - p;
    if weight_cov(ln_l, room) <= target {
        return 1.0;
    }
    let (mut lo, mut hi) = (0.0, room);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if weight_cov(ln_l, mid) > target {
            hi = mid;
        } else {
            lo = mid;
        }
        if hi - lo <= 1e-10 * hi {
            break;
        }
    }
    // lo stays 0 only when the zero-likelihood points alone push the c.o.v. over the target
    // (stage 0); a tiny positive step then just drops them.
    let dp = if lo > 0.0 { lo } else { hi };
    (p + dp).min(1.0)
}

/// Coefficient of variation (sample std / mean) of `exp(dp * ln L)`, scaled by the maximum so
/// it never overflows (the c.o.v. is scale-free).
fn weight_cov(ln_l: &[f64], dp: f64) -> f64 {
    let max = ln_l
        .iter()
        .map(|&l| tempered(dp, l))
        .fold(f64::NEG_INFINITY, f64::max);
    let n = ln_l.len() as f64;
    let w: Vec<f64> = ln_l
        .iter()
        .map(|&l| (tempered(dp, l) - max).exp())
        .collect();
    let mean = w.iter().sum::<f64>() / n;
    let var = w.iter().map(|wi| (wi - mean) * (wi - mean)).sum::<f64>() / (n - 1.0);
    var.sqrt() / mean
}

fn log_sum_exp(v: &[f64]) -> f64 {
    let max = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if max == f64::NEG_INFINITY {
        return max;
    }
    max + v.iter().map(|&x| (x - max).exp()).sum::<f64>().ln()
}

/// Lower Cholesky factor of `beta^2 * Sigma_w`, with Sigma_w the weighted sample covariance.
/// A growing diagonal jitter rescues covariances that are singular in floating point (e.g. all
/// weight on a few points or a likelihood that pins a parameter).
fn proposal_factor(theta: &[Vec<f64>], w: &[f64], beta: f64) -> DMatrix<f64> {
    let d = theta[0].len();
    let mut mu = DVector::<f64>::zeros(d);
    for (t, &wi) in theta.iter().zip(w) {
        if wi > 0.0 {
            for k in 0..d {
                mu[k] += wi * t[k];
            }
        }
    }
    let mut cov = DMatrix::<f64>::zeros(d, d);
    for (t, &wi) in theta.iter().zip(w) {
        if wi > 0.0 {
            for a in 0..d {
                let da = t[a] - mu[a];
                for b in 0..=a {
                    cov[(a, b)] += wi * da * (t[b] - mu[b]);
                }
            }
        }
    }
    for a in 0..d {
        for b in 0..a {
            cov[(b, a)] = cov[(a, b)];
        }
    }
    let scale = cov.trace() / d as f64;
    let scale = if scale.is_finite() && scale > 0.0 {
        scale
    } else {
        1.0
    };
    let mut jitter = 0.0;
    let l = loop {
        let mut c = cov.clone();
        for k in 0..d {
            c[(k, k)] += jitter;
        }
        if let Some(ch) = c.cholesky() {
            break ch.l();
        }
        jitter = if jitter == 0.0 {
            1e-10 * scale
        } else {
            jitter * 10.0
        };
        if jitter > scale {
            // Give up on the correlations rather than loop forever.
            break DMatrix::from_diagonal(&DVector::from_fn(d, |k, _| {
                cov[(k, k)].max(1e-10 * scale).sqrt()
            }));
        }
    };
    l * beta
}

/// Systematic resampling: `m` indices drawn proportionally to the normalised weights `w`,
/// never an index of zero weight.
fn systematic_resample(w: &[f64], m: usize, rng: &mut ChaCha8Rng) -> Vec<usize> {
    let live: Vec<usize> = (0..w.len()).filter(|&i| w[i] > 0.0).collect();
    let total: f64 = live.iter().map(|&i| w[i]).sum();
    let u0: f64 = rng.random();
    let mut out = Vec::with_capacity(m);
    let mut j = 0;
    let mut cum = w[live[0]] / total;
    for k in 0..m {
        let u = (k as f64 + u0) / m as f64;
        while u >= cum && j + 1 < live.len() {
            j += 1;
            cum += w[live[j]] / total;
        }
        out.push(live[j]);
    }
    out
}

fn check_no_pos_inf(ln_l: &[f64]) -> Result<(), String> {
    if ln_l.contains(&f64::INFINITY) {
        Err("tmcmc: ln_likelihood returned +inf".into())
    } else {
        Ok(())
    }
}
/// Stream seed for `(seed, stage, chain)`.
fn mix(seed: u64, stage: u64, chain: u64) -> u64 {
    splitmix64(splitmix64(splitmix64(seed) ^ stage) ^ chain)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Instant;

    const LN_2PI: f64 = 1.837_877_066_409_345_3;

    fn opts(seed: u64) -> TmcmcOptions {
        TmcmcOptions {
            samples: 2000,
            seed,
            ..Default::default()
        }
    }

    /// With one Metropolis step per stage the population is a few hundred barely moved
    /// lineages; in 4-D that scatters ln Z by ~0.8 (20 seeds). 20 burn-in steps per chain
    /// (Betz et al. 2016) bring the scatter to ~0.06, so the tolerances test the estimator.
    fn mixed(seed: u64) -> TmcmcOptions {
        TmcmcOptions {
            burn_in: 20,
            ..opts(seed)
        }
    }

    /// ln N(x; mu, var I), normalised.
    fn ln_normal(x: &[f64], mu: f64, var: f64) -> f64 {
        let ss: f64 = x.iter().map(|&xi| (xi - mu) * (xi - mu)).sum();
        -0.5 * x.len() as f64 * (LN_2PI + var.ln()) - 0.5 * ss / var
    }

    fn report(name: &str, r: &TmcmcResult, exact: f64, t: Instant) -> f64 {
        let err = r.ln_evidence - exact;
        eprintln!(
            "{name}: ln Z = {:.4} (exact {exact:.4}, error {err:+.4}), {} stages, acc {:?}, {:.0} ms",
            r.ln_evidence,
            r.stages.len(),
            r.stages
                .iter()
                .map(|s| (s.acceptance * 100.0).round() / 100.0)
                .collect::<Vec<_>>(),
            t.elapsed().as_secs_f64() * 1e3
        );
        err
    }

    #[test]
    fn two_gaussian_mixture_4d() {
        let t = Instant::now();
        let prior = UniformBox::new(vec![-2.0; 4], vec![2.0; 4]).unwrap();
        let like = |x: &[f64]| {
            let a = 0.1f64.ln() + ln_normal(x, 0.5, 0.01);
            let b = 0.9f64.ln() + ln_normal(x, -0.5, 0.01);
            log_sum_exp(&[a, b])
        };
        let r = tmcmc(&prior, like, &mixed(7)).unwrap();
        let err = report("mixture 4-D", &r, -5.545177444, t);
        assert!(err.abs() < 0.3, "ln Z error {err}");
        let frac = r.samples.iter().filter(|s| s[0] > 0.0).count() as f64 / r.samples.len() as f64;
        eprintln!("mixture 4-D: fraction at + mode {frac:.3}");
        assert!((0.04..=0.2).contains(&frac), "fraction at + mode {frac}");
        assert_eq!(r.stages.last().unwrap().p, 1.0);
    }

    #[test]
    fn gaussian_likelihood_uniform_prior_2d() {
        let t = Instant::now();
        let prior = UniformBox::new(vec![-5.0; 2], vec![5.0; 2]).unwrap();
        let r = tmcmc(&prior, |x: &[f64]| ln_normal(x, 0.0, 1.0), &mixed(11)).unwrap();
        let err = report("Gaussian 2-D", &r, -4.605171333, t);
        assert!(err.abs() < 0.1, "ln Z error {err}");
        for s in r.std() {
            assert!((s - 1.0).abs() < 0.1, "posterior sd {s}");
        }
    }

    #[test]
    fn gaussian_prior_one_observation() {
        let t = Instant::now();
        let prior = GaussianPrior {
            mean: vec![0.0],
            sd: vec![1.0],
        };
        let like = |x: &[f64]| -0.5 * (LN_2PI + 0.25f64.ln()) - 0.5 * (1.0 - x[0]).powi(2) / 0.25;
        // Default mixing (one step per chain) is enough in 1-D.
        let r = tmcmc(&prior, like, &opts(3)).unwrap();
        let err = report("Gaussian prior", &r, -1.430510309, t);
        assert!(err.abs() < 0.1, "ln Z error {err}");
        let (m, s) = (r.mean()[0], r.std()[0]);
        eprintln!("Gaussian prior: posterior mean {m:.4} (0.8), sd {s:.4} (0.4472)");
        assert!((m - 0.8).abs() < 0.05, "mean {m}");
        assert!((s - 0.2f64.sqrt()).abs() < 0.05, "sd {s}");
        let med = r.quantile(0, 0.5);
        assert!((med - 0.8).abs() < 0.05, "median {med}");
    }

    #[test]
    fn beta_bernoulli_50_of_100() {
        let t = Instant::now();
        let prior = UniformBox::new(vec![0.0], vec![1.0]).unwrap();
        let like = |x: &[f64]| 50.0 * x[0].ln() + 50.0 * (1.0 - x[0]).ln();
        let r = tmcmc(&prior, like, &mixed(5)).unwrap();
        let err = report("Beta-Bernoulli", &r, -71.398962169, t);
        assert!(err.abs() < 0.1, "ln Z error {err}");
        // Posterior Beta(51, 51): mean 0.5, sd = sqrt(51*51 / (102^2 * 103)) = 0.0493.
        assert!((r.mean()[0] - 0.5).abs() < 0.01);
        assert!((r.std()[0] - 0.0493).abs() < 0.01);
    }

    #[test]
    fn zero_likelihood_region_is_dropped() {
        // L = N(0, I_2) on theta_0 > 0 only: Z is half that of the untruncated case.
        let t = Instant::now();
        let prior = UniformBox::new(vec![-5.0; 2], vec![5.0; 2]).unwrap();
        let like = |x: &[f64]| {
            if x[0] > 0.0 {
                ln_normal(x, 0.0, 1.0)
            } else {
                f64::NAN // NaN must behave like -inf
            }
        };
        let r = tmcmc(&prior, like, &mixed(13)).unwrap();
        // The stage-0 fraction of finite likelihoods alone has sd ~0.02 in ln Z.
        let err = report("truncated Gaussian", &r, -4.605171333 - 2f64.ln(), t);
        assert!(err.abs() < 0.15, "ln Z error {err}");
        assert!(r.samples.iter().all(|s| s[0] > 0.0));
    }

    #[test]
    fn deterministic_for_seed_and_thread_count() {
        let prior = UniformBox::new(vec![-2.0; 3], vec![2.0; 3]).unwrap();
        let like = |x: &[f64]| ln_normal(x, 0.3, 0.05);
        let o = TmcmcOptions {
            samples: 500,
            chain_length: 3,
            burn_in: 2,
            seed: 99,
            ..Default::default()
        };
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| tmcmc(&prior, like, &o).unwrap())
        };
        let a = run(1);
        let b = run(2);
        let c = tmcmc(&prior, like, &o).unwrap();
        assert_eq!(a, b);
        assert_eq!(a, c);
        assert_eq!(a.samples.len(), 500);
        let other = tmcmc(&prior, like, &TmcmcOptions { seed: 100, ..o }).unwrap();
        assert_ne!(a.samples, other.samples);
    }

    #[test]
    fn errors() {
        let like = |_: &[f64]| 0.0;
        let ok = UniformBox::new(vec![0.0], vec![1.0]).unwrap();
        let empty = UniformBox {
            lower: vec![],
            upper: vec![],
        };
        let e = tmcmc(&empty, like, &opts(0)).unwrap_err();
        assert!(e.contains("dimension 0"), "{e}");
        let e = tmcmc(
            &ok,
            like,
            &TmcmcOptions {
                samples: 9,
                ..opts(0)
            },
        )
        .unwrap_err();
        assert!(e.contains("expected 10 to"), "{e}");
        let bad = UniformBox {
            lower: vec![0.0, 1.0],
            upper: vec![1.0, 1.0],
        };
        let e = tmcmc(&bad, like, &opts(0)).unwrap_err();
        assert!(e.contains("lower bound"), "{e}");
        assert!(UniformBox::new(vec![2.0], vec![1.0]).is_err());
        let e = tmcmc(&ok, |_: &[f64]| f64::NEG_INFINITY, &opts(0)).unwrap_err();
        assert!(e.contains("-inf"), "{e}");
        let sharp = |x: &[f64]| -1e6 * (x[0] - 0.5).powi(2);
        let e = tmcmc(
            &ok,
            sharp,
            &TmcmcOptions {
                max_stages: 2,
                ..opts(0)
            },
        )
        .unwrap_err();
        assert!(e.contains("max_stages"), "{e}");
        let e = tmcmc(&ok, |_: &[f64]| f64::INFINITY, &opts(0)).unwrap_err();
        assert!(e.contains("+inf"), "{e}");
    }

    #[test]
    fn constant_likelihood_is_one_stage() {
        let prior = UniformBox::new(vec![0.0; 2], vec![2.0; 2]).unwrap();
        let r = tmcmc(&prior, |_: &[f64]| -1.5, &opts(1)).unwrap();
        assert_eq!(r.stages.len(), 1);
        assert!((r.ln_evidence + 1.5).abs() < 1e-12);
    }

    #[test]
    fn summary_statistics() {
        let r = TmcmcResult {
            samples: vec![vec![1.0, -2.0], vec![2.0, -4.0], vec![3.0, -6.0]],
            ln_likelihood: vec![0.0; 3],
            ln_evidence: 0.0,
            stages: vec![],
        };
        assert_eq!(r.mean(), vec![2.0, -4.0]);
        assert_eq!(r.std(), vec![1.0, 2.0]);
        assert_eq!(r.cov(), vec![0.5, 0.5]);
        assert_eq!(r.quantile(0, 0.25), 1.5);
        assert_eq!(r.quantile(1, 1.0), -2.0);
        assert!(r.quantile(0, 1.5).is_nan());
    }
}
