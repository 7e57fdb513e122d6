//! Least squares with the statistics a parameter estimate needs: linear (QR-free normal
//! equations through a Cholesky factor, fine for the few well-scaled columns used here) and
//! nonlinear (Levenberg-Marquardt), both returning the estimate's covariance s^2 (J^T J)^-1
//! and the two-sided 95 % Student-t interval of every parameter.

use nalgebra::{DMatrix, DVector};
use statrs::distribution::{ContinuousCDF, StudentsT};

use crate::error::{Error, Result};

/// A fitted parameter vector with its uncertainty.
#[derive(Debug, Clone)]
pub struct Estimate {
    /// Fitted parameter values, in the caller's parameterisation (e.g. logarithms of constants).
    pub values: Vec<f64>,
    /// Standard errors, sqrt(diag(s^2 (J^T J)^-1)).
    pub std_errors: Vec<f64>,
    /// Two-sided 95 % intervals, value -+ t(0.975, dof) * std error.
    pub ci95: Vec<[f64; 2]>,
    /// Correlation matrix of the estimates.
    pub correlation: Vec<Vec<f64>>,
    /// Sum of squared residuals.
    pub sse: f64,
    /// Residual degrees of freedom (observations - parameters).
    pub dof: usize,
    /// Residuals r_i = model - data at the optimum.
    pub residuals: Vec<f64>,
}

/// The 0.975 quantile of Student's t with `dof` degrees of freedom.
pub fn t975(dof: usize) -> f64 {
    StudentsT::new(0.0, 1.0, dof.max(1) as f64)
        .map(|t| t.inverse_cdf(0.975))
        .unwrap_or(f64::NAN)
}

/// Covariance-based statistics from the Jacobian at the optimum and the residuals.
fn estimate(values: Vec<f64>, jac: &DMatrix<f64>, residuals: Vec<f64>) -> Result<Estimate> {
    let (n, p) = jac.shape();
    if n <= p {
        return Err(Error::invalid(format!(
            "least squares: {n} observations for {p} parameters; expected more observations \
             than parameters"
        )));
    }
    let jtj = jac.transpose() * jac;
    let inv = jtj.clone().try_inverse().ok_or_else(|| {
        Error::invalid(
            "least squares: the parameters are not identifiable from these data (J^T J is \
             singular: an input without spread, or two inputs proportional)",
        )
    })?;
    let sse: f64 = residuals.iter().map(|r| r * r).sum();
    let dof = n - p;
    let s2 = sse / dof as f64;
    let cov = inv * s2;
    let t = t975(dof);
    let std_errors: Vec<f64> = (0..p).map(|k| cov[(k, k)].max(0.0).sqrt()).collect();
    let ci95 = values
        .iter()
        .zip(&std_errors)
        .map(|(v, s)| [v - t * s, v + t * s])
        .collect();
    let correlation = (0..p)
        .map(|a| {
            (0..p)
                .map(|b| cov[(a, b)] / (std_errors[a] * std_errors[b]))
                .collect()
        })
        .collect();
    Ok(Estimate {
        values,
        std_errors,
        ci95,
        correlation,
        sse,
        dof,
        residuals,
    })
}

/// Ordinary least squares y ~ X b (`x[row][column]`).
pub fn linear(x: &[Vec<f64>], y: &[f64]) -> Result<Estimate> {
    let n = y.len();
    let p = x.first().map_or(0, Vec::len);
    if x.len() != n || p == 0 {
        return Err(Error::invalid(format!(
            "least squares: {} rows of inputs for {n} observations",
            x.len()
        )));
    }
    let a = DMatrix::from_fn(n, p, |r, c| x[r][c]);
    let b = DVector::from_column_slice(y);
    let jtj = a.transpose() * &a;
    let beta = jtj
        .cholesky()
        .map(|c| c.solve(&(a.transpose() * &b)))
        .ok_or_else(|| {
            Error::invalid(
                "least squares: the columns are linearly dependent (an input without spread, or \
                 two inputs proportional)",
            )
        })?;
    let res = &b - &a * &beta;
    estimate(
        beta.iter().copied().collect(),
        &a,
        res.iter().copied().collect(),
    )
}

/// Residuals r(p) = model(p) - data and their Jacobian, for [`levenberg_marquardt`].
pub trait Residuals {
    /// r(p) = model(p) - data, one entry per observation.
    fn residuals(&self, p: &[f64]) -> Vec<f64>;
    /// d r_i / d p_k as `[i][k]`.
    fn jacobian(&self, p: &[f64]) -> Vec<Vec<f64>>;
}

/// Levenberg-Marquardt from `start`; at most `iters` iterations. Fails if the residuals are not
/// finite at the start.
pub fn levenberg_marquardt(f: &dyn Residuals, start: &[f64], iters: usize) -> Result<Estimate> {
    let sse = |r: &[f64]| r.iter().map(|v| v * v).sum::<f64>();
    let mut p = start.to_vec();
    let mut r = f.residuals(&p);
    let mut cost = sse(&r);
    if !cost.is_finite() {
        return Err(Error::invalid(
            "nonlinear least squares: the model is not finite at the starting point",
        ));
    }
    let np = p.len();
    let mut lambda = 1e-3;
    for _ in 0..iters {
        let j = f.jacobian(&p);
        let jm = DMatrix::from_fn(r.len(), np, |a, b| j[a][b]);
        let jtj = jm.transpose() * &jm;
        let g = jm.transpose() * DVector::from_column_slice(&r);
        let mut improved = false;
        for _ in 0..30 {
            let mut a = jtj.clone();
            for k in 0..np {
                a[(k, k)] += lambda * jtj[(k, k)].max(1e-300);
            }
            let Some(step) = a.cholesky().map(|c| c.solve(&(-&g))) else {
                lambda *= 10.0;
                continue;
            };
            let trial: Vec<f64> = p.iter().zip(step.iter()).map(|(a, b)| a + b).collect();
            let rt = f.residuals(&trial);
            let ct = sse(&rt);
            if ct.is_finite() && ct < cost {
                let rel = (cost - ct) / cost.max(1e-300);
                p = trial;
                r = rt;
                cost = ct;
                lambda = (lambda / 3.0).max(1e-12);
                improved = true;
                if rel < 1e-12 {
                    let jac = f.jacobian(&p);
                    let jm = DMatrix::from_fn(r.len(), np, |a, b| jac[a][b]);
                    return estimate(p, &jm, r);
                }
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    let jac = f.jacobian(&p);
    let jm = DMatrix::from_fn(r.len(), np, |a, b| jac[a][b]);
    estimate(p, &jm, r)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_through_exact_points_has_zero_error_and_the_right_slope() {
        let x: Vec<Vec<f64>> = (0..5).map(|i| vec![1.0, i as f64]).collect();
        let y: Vec<f64> = (0..5).map(|i| 2.0 + 3.0 * i as f64).collect();
        let e = linear(&x, &y).unwrap();
        assert!((e.values[0] - 2.0).abs() < 1e-12 && (e.values[1] - 3.0).abs() < 1e-12);
        assert!(e.sse < 1e-20 && e.dof == 3);
    }

    #[test]
    fn slope_interval_matches_the_textbook_formula() {
        // y = 1 + 2x + r with residuals r known: se(slope) = s / sqrt(Sxx).
        let xs = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0];
        let r = [0.1, -0.2, 0.05, 0.15, -0.1, 0.0];
        let x: Vec<Vec<f64>> = xs.iter().map(|&v| vec![1.0, v]).collect();
        let y: Vec<f64> = xs.iter().zip(r).map(|(v, e)| 1.0 + 2.0 * v + e).collect();
        let e = linear(&x, &y).unwrap();
        let mx = 2.5;
        let sxx: f64 = xs.iter().map(|v| (v - mx) * (v - mx)).sum();
        let s = (e.sse / 4.0).sqrt();
        assert!((e.std_errors[1] - s / sxx.sqrt()).abs() < 1e-12);
        let t = t975(4);
        assert!((t - 2.776_445).abs() < 1e-5, "{t}");
        assert!((e.ci95[1][1] - e.values[1] - t * e.std_errors[1]).abs() < 1e-12);
    }

    #[test]
    fn proportional_columns_are_refused() {
        let x: Vec<Vec<f64>> = (0..5).map(|i| vec![i as f64, 2.0 * i as f64]).collect();
        let y: Vec<f64> = (0..5).map(|i| i as f64).collect();
        assert!(linear(&x, &y).is_err());
    }

    struct Exp {
        t: Vec<f64>,
        y: Vec<f64>,
    }
    impl Residuals for Exp {
        fn residuals(&self, p: &[f64]) -> Vec<f64> {
            self.t
                .iter()
                .zip(&self.y)
                .map(|(t, y)| p[0] * (-p[1] * t).exp() - y)
                .collect()
        }
        fn jacobian(&self, p: &[f64]) -> Vec<Vec<f64>> {
            self.t
                .iter()
                .map(|t| {
                    let e = (-p[1] * t).exp();
                    vec![e, -p[0] * t * e]
                })
                .collect()
        }
    }

    #[test]
    fn levenberg_marquardt_finds_an_exponential_decay() {
        let t: Vec<f64> = (0..20).map(|k| k as f64 * 0.2).collect();
        let y: Vec<f64> = t.iter().map(|t| 3.0 * (-0.7 * t).exp()).collect();
        let e = levenberg_marquardt(&Exp { t, y }, &[1.0, 0.1], 200).unwrap();
        assert!((e.values[0] - 3.0).abs() < 1e-8 && (e.values[1] - 0.7).abs() < 1e-8);
    }
}
