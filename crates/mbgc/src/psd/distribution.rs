//! Mass-based cumulative distributions Q3(x) of particle size, x in mm.
//!
//! The three two-parameter families of the MBGC paper (Richter & Will 2021, eqs. 1-3): GGS
//! (Gates-Gaudin-Schumann), RRSB (Rosin-Rammler-Sperling-Bennett) and log-normal. The log-normal
//! additionally converts between number, length, area and mass basis (Hatch-Choate).

use serde::Serialize;
use statrs::function::erf::{erfc, erfc_inv};

use crate::error::{Error, Result};

/// Standard normal cdf. Written with `erfc` so that the lower tail keeps its relative accuracy.
pub fn phi(z: f64) -> f64 {
    0.5 * erfc(-z / std::f64::consts::SQRT_2)
}

/// Inverse of [`phi`] on (0, 1); -inf at 0 and +inf at 1.
pub fn phi_inv(p: f64) -> f64 {
    -std::f64::consts::SQRT_2 * erfc_inv(2.0 * p)
}

/// The distribution families, with their command-line and JSON names.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Model {
    /// Gates-Gaudin-Schumann power law, bounded above by x_max ([`Ggs`]).
    Ggs,
    /// Rosin-Rammler-Sperling-Bennett (Weibull) distribution ([`Rrsb`]).
    Rrsb,
    /// Log-normal distribution of size on mass basis ([`LogNormal`]).
    #[serde(rename = "lognormal")]
    LogNormal,
}

impl Model {
    /// The three families, in the order fits are reported.
    pub const ALL: [Model; 3] = [Model::Ggs, Model::Rrsb, Model::LogNormal];

    /// The command-line and JSON name (`ggs`, `rrsb`, `lognormal`).
    pub fn name(self) -> &'static str {
        match self {
            Model::Ggs => "ggs",
            Model::Rrsb => "rrsb",
            Model::LogNormal => "lognormal",
        }
    }

    /// Builds a distribution from its two parameters in [`MassDistribution::params`] order.
    pub fn with_params(self, scale_mm: f64, shape: f64) -> Result<Distribution> {
        Ok(match self {
            Model::Ggs => Distribution::Ggs(Ggs::new(scale_mm, shape)?),
            Model::Rrsb => Distribution::Rrsb(Rrsb::new(scale_mm, shape)?),
            Model::LogNormal => Distribution::LogNormal(LogNormal::new(scale_mm, shape)?),
        })
    }
}

impl std::str::FromStr for Model {
    type Err = Error;

    /// The command-line and JSON name (`ggs`, `rrsb`, `lognormal`).
    fn from_str(s: &str) -> Result<Model> {
        Model::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| {
                Error::invalid(format!(
                    "PSD model \"{s}\": expected one of {}",
                    Model::ALL.map(Model::name).join(", ")
                ))
            })
    }
}

impl std::fmt::Display for Model {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A mass-based cumulative size distribution.
pub trait MassDistribution {
    /// Mass fraction of particles smaller than `x_mm` (cumulative passing, 0..1).
    fn q3(&self, x_mm: f64) -> f64;
    /// Size below which the mass fraction `p` lies (0 < p < 1).
    fn q3_inv(&self, p: f64) -> f64;
    /// The family this distribution belongs to.
    fn model(&self) -> Model;
    /// The two parameters, scale (mm) first, with the names used in tables and JSON.
    fn params(&self) -> [(&'static str, f64); 2];
}

fn check_param(model: Model, name: &str, v: f64, what: &str) -> Result<f64> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(Error::input(
            format!("{model} distribution"),
            name,
            format!("expected {what}, found {v}"),
        ))
    }
}

/// GGS: Q3 = (x / x_max)^m below x_max, 1 above.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Ggs {
    /// Largest particle size x_max, mm (Q3 = 1 at and above it); > 0.
    pub x_max_mm: f64,
    /// Distribution modulus m > 0, the slope of Q3 in log-log coordinates; larger means narrower.
    pub m: f64,
}

impl Ggs {
    /// Checks that both parameters are finite and positive.
    pub fn new(x_max_mm: f64, m: f64) -> Result<Self> {
        Ok(Ggs {
            x_max_mm: check_param(Model::Ggs, "x_max_mm", x_max_mm, "a positive size")?,
            m: check_param(Model::Ggs, "m", m, "a positive exponent")?,
        })
    }
}

impl MassDistribution for Ggs {
    fn q3(&self, x: f64) -> f64 {
        if x <= 0.0 {
            0.0
        } else if x >= self.x_max_mm {
            1.0
        } else {
            (x / self.x_max_mm).powf(self.m)
        }
    }
    fn q3_inv(&self, p: f64) -> f64 {
        self.x_max_mm * p.powf(1.0 / self.m)
    }
    fn model(&self) -> Model {
        Model::Ggs
    }
    fn params(&self) -> [(&'static str, f64); 2] {
        [("x_max_mm", self.x_max_mm), ("m", self.m)]
    }
}

/// RRSB: Q3 = 1 - exp(-(x / x')^n); x' is the size with 63.2 % passing.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Rrsb {
    /// Characteristic size x', mm, where Q3 = 1 - 1/e (63.2 % passing); > 0.
    pub x_prime_mm: f64,
    /// Uniformity exponent n > 0 (Weibull shape); larger means narrower.
    pub n: f64,
}

impl Rrsb {
    /// Checks that both parameters are finite and positive.
    pub fn new(x_prime_mm: f64, n: f64) -> Result<Self> {
        Ok(Rrsb {
            x_prime_mm: check_param(Model::Rrsb, "x_prime_mm", x_prime_mm, "a positive size")?,
            n: check_param(Model::Rrsb, "n", n, "a positive exponent")?,
        })
    }
}

impl MassDistribution for Rrsb {
    fn q3(&self, x: f64) -> f64 {
        if x <= 0.0 {
            return 0.0;
        }
        // expm1 keeps the fine tail accurate, where 1 - exp(-t) would cancel.
        -(-(x / self.x_prime_mm).powf(self.n)).exp_m1()
    }
    fn q3_inv(&self, p: f64) -> f64 {
        self.x_prime_mm * (-(-p).ln_1p()).powf(1.0 / self.n)
    }
    fn model(&self) -> Model {
        Model::Rrsb
    }
    fn params(&self) -> [(&'static str, f64); 2] {
        [("x_prime_mm", self.x_prime_mm), ("n", self.n)]
    }
}

/// Basis of a cumulative distribution: Q_r weights each particle by x^r.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Basis {
    /// Q0: each particle counts once.
    Number = 0,
    /// Q1: each particle weighted by its size x.
    Length = 1,
    /// Q2: each particle weighted by x^2 (surface area).
    Area = 2,
    /// Q3: each particle weighted by x^3 (mass, at uniform density); the basis sieve data are on.
    Mass = 3,
}

impl Basis {
    /// The exponent r of the weight x^r (0 for number, 3 for mass).
    pub fn r(self) -> i32 {
        self as i32
    }
}

/// Log-normal: Q3 = Phi(ln(x / x50_3) / sigma_ln).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LogNormal {
    /// Mass median diameter, mm (the metamodel's d50).
    #[serde(rename = "x50_3_mm")]
    pub x50_3: f64,
    /// Standard deviation of ln x; the same on every basis.
    #[serde(rename = "sigma_ln")]
    pub sigma: f64,
}

impl LogNormal {
    /// Checks that the mass median (mm) and sigma_ln are finite and positive.
    pub fn new(x50_3: f64, sigma: f64) -> Result<Self> {
        Ok(LogNormal {
            x50_3: check_param(Model::LogNormal, "x50_3_mm", x50_3, "a positive size")?,
            sigma: check_param(Model::LogNormal, "sigma_ln", sigma, "a positive spread")?,
        })
    }

    /// Hatch-Choate: ln x50_r = ln x50_3 + (r - 3) sigma^2.
    pub fn median(&self, basis: Basis) -> f64 {
        self.x50_3 * (f64::from(basis.r() - 3) * self.sigma * self.sigma).exp()
    }

    /// Cumulative distribution Q_r(x) on the given basis.
    pub fn cdf(&self, basis: Basis, x: f64) -> f64 {
        if x <= 0.0 {
            return 0.0;
        }
        phi((x / self.median(basis)).ln() / self.sigma)
    }
}

impl MassDistribution for LogNormal {
    fn q3(&self, x: f64) -> f64 {
        self.cdf(Basis::Mass, x)
    }
    fn q3_inv(&self, p: f64) -> f64 {
        self.x50_3 * (self.sigma * phi_inv(p)).exp()
    }
    fn model(&self) -> Model {
        Model::LogNormal
    }
    fn params(&self) -> [(&'static str, f64); 2] {
        [("x50_3_mm", self.x50_3), ("sigma_ln", self.sigma)]
    }
}

/// Any of the three families; serialises as `{"model": ..., <params>}`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "model", rename_all = "lowercase")]
pub enum Distribution {
    /// Gates-Gaudin-Schumann.
    Ggs(Ggs),
    /// Rosin-Rammler-Sperling-Bennett.
    Rrsb(Rrsb),
    /// Log-normal on mass basis.
    #[serde(rename = "lognormal")]
    LogNormal(LogNormal),
}

impl Distribution {
    fn inner(&self) -> &dyn MassDistribution {
        match self {
            Distribution::Ggs(d) => d,
            Distribution::Rrsb(d) => d,
            Distribution::LogNormal(d) => d,
        }
    }

    /// Parameters formatted for a table, e.g. `x50_3_mm = 11.16, sigma_ln = 0.26`.
    pub fn describe(&self) -> String {
        self.params()
            .iter()
            .map(|(k, v)| format!("{k} = {v:.4}"))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

impl MassDistribution for Distribution {
    fn q3(&self, x: f64) -> f64 {
        self.inner().q3(x)
    }
    fn q3_inv(&self, p: f64) -> f64 {
        self.inner().q3_inv(p)
    }
    fn model(&self) -> Model {
        self.inner().model()
    }
    fn params(&self) -> [(&'static str, f64); 2] {
        self.inner().params()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hatch_choate_constants() {
        let d = LogNormal::new(5e-6, 0.5).unwrap();
        let expected = [
            (Basis::Number, 0.933192798731),
            (Basis::Length, 0.8413447460685),
            (Basis::Area, 0.6914624612740),
            (Basis::Mass, 0.5),
        ];
        for (basis, cdf) in expected {
            let got = d.cdf(basis, 5e-6);
            assert!((got - cdf).abs() < 1e-10, "{basis:?}: {got} vs {cdf}");
        }
        let x50_0 = d.median(Basis::Number);
        assert!((x50_0 - 2.36183276e-6).abs() < 1e-14, "x50_0 = {x50_0}");
    }

    #[test]
    fn quantile_inverts_q3() {
        let dists = [
            Model::Ggs.with_params(16.0, 2.5).unwrap(),
            Model::Rrsb.with_params(12.0, 3.0).unwrap(),
            Model::LogNormal.with_params(11.16, 0.26).unwrap(),
        ];
        for d in dists {
            for p in [1e-6, 0.01, 0.3, 0.5, 0.9, 0.99] {
                let x = d.q3_inv(p);
                let err = (d.q3(x) / p - 1.0).abs();
                // statrs erfc_inv is good to ~1e-10 relative in the tails.
                assert!(err < 1e-9, "{d:?} p = {p}: relative error {err}");
            }
        }
    }

    #[test]
    fn bad_parameters_are_named() {
        let e = Model::Rrsb.with_params(-1.0, 2.0).unwrap_err().to_string();
        assert!(e.contains("rrsb") && e.contains("x_prime_mm"), "{e}");
        let e = LogNormal::new(1.0, f64::NAN).unwrap_err().to_string();
        assert!(e.contains("lognormal") && e.contains("sigma_ln"), "{e}");
    }

    #[test]
    fn serialises_with_model_tag() {
        let d = Model::LogNormal.with_params(11.16, 0.26).unwrap();
        let v = serde_json::to_value(d).unwrap();
        assert_eq!(v["model"], "lognormal");
        assert_eq!(v["x50_3_mm"], 11.16);
        assert_eq!(v["sigma_ln"], 0.26);
    }
}
