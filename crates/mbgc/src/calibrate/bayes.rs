//! Bayesian calibration (seed 003): TMCMC posterior of the free parameters and of the relative
//! model error, the evidence of the model class, model-class probabilities and propagation of the
//! posterior to any response the metamodel predicts.
//!
//! Prediction-error model: `measured_i = g_i(theta) + e_i`, `e_i ~ N(0, sd_i^2 + (sigma g_i)^2)`,
//! with `sd_i` the measurement's standard deviation and `sigma` a relative model error with a
//! uniform prior on `[0, sigma_max]`; the parameters have a uniform prior on the search box.

use super::problem::Problem;
use super::tmcmc::{tmcmc, TmcmcOptions, TmcmcResult, UniformBox};
use crate::error::{Error, Result};
use serde::Serialize;

/// Posterior statistics of one parameter or predicted response over the equally weighted samples.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct Summary {
    /// The parameter's or response's name (`sigma` for the relative model error).
    pub name: String,
    /// Posterior mean, in the quantity's unit.
    pub mean: f64,
    /// Posterior standard deviation (1/n normalisation), same unit.
    pub sd: f64,
    /// Coefficient of variation sd / |mean|.
    pub cov: f64,
    /// 5 % quantile (nearest order statistic).
    pub q05: f64,
    /// 95 % quantile: with `q05`, a 90 % credible interval.
    pub q95: f64,
}

/// The posterior of one calibration, sampled by TMCMC (Ching & Chen 2007, as Hadjidoukas et al.
/// 2014, "seed 003", use it for DEM) under the prediction-error model above: parameter and
/// response summaries and the evidence of the model class.
#[derive(Clone, Debug, Serialize)]
pub struct Posterior {
    /// Equally weighted posterior samples drawn.
    pub samples: usize,
    /// Tempering stages TMCMC needed to go from prior to posterior.
    pub stages: usize,
    /// Natural log of the evidence p(data | model class), the prior-averaged likelihood: compare
    /// it across model classes (see [`class_probabilities`]).
    pub ln_evidence: f64,
    /// Free parameters, then `sigma` (relative model error).
    pub parameters: Vec<Summary>,
    /// Posterior-robust mean and sd of every response of the model (seed 003 Eqs. 14-15).
    pub responses: Vec<Summary>,
    /// The equally weighted posterior samples (free parameters, then sigma).
    #[serde(skip)]
    pub draws: Vec<Vec<f64>>,
    /// Their names.
    #[serde(skip)]
    pub names: Vec<String>,
}

/// ln N(y; mu, var).
fn ln_normal(y: f64, mu: f64, var: f64) -> f64 {
    -0.5 * ((y - mu).powi(2) / var + var.ln() + (2.0 * std::f64::consts::PI).ln())
}

/// Log-likelihood of `theta = (free parameters..., sigma)`.
pub fn ln_likelihood(p: &Problem, theta: &[f64]) -> f64 {
    let (x, sigma) = theta.split_at(p.dim());
    let sigma = sigma.first().copied().unwrap_or(0.0);
    if p.violation(x) > 0.0 {
        return f64::NEG_INFINITY;
    }
    let pred = p.predictions(x);
    let sds = p.target_sds(x);
    let mut l = 0.0;
    for ((t, g), sd) in p.targets.iter().zip(&pred).zip(&sds) {
        if !g.is_finite() || !sd.is_finite() {
            return f64::NEG_INFINITY;
        }
        l += ln_normal(t.value, *g, sd * sd + (sigma * g).powi(2));
    }
    l
}

fn summary(name: &str, values: &mut [f64]) -> Summary {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let sd = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n).sqrt();
    values.sort_by(f64::total_cmp);
    let q =
        |q: f64| values[((q * (values.len() - 1) as f64).round() as usize).min(values.len() - 1)];
    Summary {
        name: name.to_string(),
        mean,
        sd,
        cov: sd / mean.abs().max(1e-300),
        q05: q(0.05),
        q95: q(0.95),
    }
}

/// Runs TMCMC on the problem (a constraint is part of the prior: violating points have zero
/// likelihood, so the evidence is that of the constrained prior times its volume share).
pub fn sample(p: &Problem, samples: usize, sigma_max: f64, seed: u64) -> Result<TmcmcResult> {
    if sigma_max.is_nan() || sigma_max < 0.0 || sigma_max.is_infinite() {
        return Err(Error::invalid(format!(
            "--sigma-max: expected a relative error >= 0, got {sigma_max}"
        )));
    }
    let mut lower = p.lower.clone();
    let mut upper = p.upper.clone();
    if sigma_max > 0.0 {
        lower.push(0.0);
        upper.push(sigma_max);
    }
    let prior = UniformBox { lower, upper };
    // The metamodel costs microseconds, so the chains can afford burn-in: with one step per
    // stage the evidence scatters by ~1 in ln Z from 4 dimensions on (tmcmc.rs tests).
    let opts = TmcmcOptions {
        samples,
        seed,
        burn_in: 10,
        ..TmcmcOptions::default()
    };
    tmcmc(&prior, |th| ln_likelihood(p, th), &opts).map_err(Error::invalid)
}

/// Posterior summaries and propagation.
pub fn posterior(p: &Problem, samples: usize, sigma_max: f64, seed: u64) -> Result<Posterior> {
    let r = sample(p, samples, sigma_max, seed)?;
    let mut names: Vec<String> = p.free_names().iter().map(|s| s.to_string()).collect();
    if sigma_max > 0.0 {
        names.push("sigma".into());
    }
    let parameters: Vec<Summary> = names
        .iter()
        .enumerate()
        .map(|(j, n)| summary(n, &mut r.samples.iter().map(|s| s[j]).collect::<Vec<_>>()))
        .collect();
    let responses = p
        .model
        .responses
        .iter()
        .map(|resp| {
            let mut v: Vec<f64> = r
                .samples
                .iter()
                .map(|s| p.model.predict_point(resp, &p.full(&s[..p.dim()])))
                .collect();
            summary(&resp.name, &mut v)
        })
        .collect();
    Ok(Posterior {
        samples: r.samples.len(),
        stages: r.stages.len(),
        ln_evidence: r.ln_evidence,
        parameters,
        responses,
        draws: r.samples,
        names,
    })
}

/// Posterior probabilities of model classes from their log-evidences (equal prior odds).
pub fn class_probabilities(ln_evidence: &[f64]) -> Vec<f64> {
    let m = ln_evidence
        .iter()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    let w: Vec<f64> = ln_evidence.iter().map(|l| (l - m).exp()).collect();
    let s: f64 = w.iter().sum();
    w.iter().map(|v| v / s).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn class_probabilities_follow_bayes_factors() {
        let p = class_probabilities(&[-10.0, -10.0 + 2f64.ln(), -1000.0]);
        assert!((p[0] - 1.0 / 3.0).abs() < 1e-12 && (p[1] - 2.0 / 3.0).abs() < 1e-12);
        assert!(p[2] < 1e-300);
    }
}
