//! Local sensitivities at one point of a saved metamodel (a calibrated material): which
//! measurement pins which parameter.
//!
//! At the point x the model's gradients give, per response r and parameter k, the elasticity
//! (x_k / y_r) dy_r/dx_k (the per cent change of the response per per cent of the parameter)
//! and the standardised slope g_rk = dy_r/dx_k / sigma_r, with sigma_r the response's
//! uncertainty (its measurement or model error). The Fisher information F = sum_r g_r g_r^T of the
//! free parameters then gives each parameter's linearised standard deviation sqrt((F^-1)_kk),
//! their correlations, and each response's share g_rk^2 / F_kk of the information on parameter
//! k: the share near 1 names the measurement that pins it. A singular F means some combination
//! of the free parameters moves no response: the measurements cannot identify them all.

use nalgebra::DMatrix;
use serde::Serialize;

use crate::error::{Error, Result};
use crate::metamodel::Metamodel;

/// Sensitivities of one response at the point.
#[derive(Debug, Clone, Serialize)]
pub struct ResponseSensitivity {
    /// Response name, as in the metamodel.
    pub response: String,
    /// Metamodel prediction of the response at the point, in the response's unit.
    pub value: f64,
    /// Uncertainty of the response (measurement or model error), in its unit; > 0, it weights the
    /// response's information.
    pub sigma: f64,
    /// Per free parameter: d y / d x.
    pub gradient: Vec<f64>,
    /// Per free parameter: (x / y) d y / d x.
    pub elasticity: Vec<f64>,
}

/// Which measurement pins which parameter at one point: gradients, elasticities and the Fisher
/// information of the free parameters.
#[derive(Debug, Clone, Serialize)]
pub struct LocalSensitivity {
    /// The free parameters (the model's inputs not held fixed), in the model's order.
    pub parameters: Vec<String>,
    /// The point analysed: every model input with its physical value.
    pub point: Vec<(String, f64)>,
    /// Per response analysed, in the order requested.
    pub responses: Vec<ResponseSensitivity>,
    /// sqrt(diag(F^-1)), or None when F is singular.
    pub parameter_sd: Option<Vec<f64>>,
    /// Correlation matrix of the free parameters from F^-1, or None when F is singular; |rho| near
    /// 1 means the measurements cannot separate the two parameters.
    pub correlation: Option<Vec<Vec<f64>>>,
    /// `[parameter][response]`: the response's share of the information on the parameter.
    pub information_share: Vec<Vec<f64>>,
}

/// Local sensitivities of `model` at the physical point `x` (all inputs, in the model's order).
/// `sigma[r]` per response of `responses`; `fixed` names inputs left out of F.
pub fn at_point(
    model: &Metamodel,
    x: &[f64],
    responses: &[String],
    sigma: &[f64],
    fixed: &[String],
) -> Result<LocalSensitivity> {
    let names = model.input_names();
    for f in fixed {
        if !names.contains(f) {
            return Err(Error::invalid(format!(
                "--fixed {f}: not an input of the model (inputs: {})",
                names.join(", ")
            )));
        }
    }
    let free: Vec<usize> = (0..names.len())
        .filter(|k| !fixed.contains(&names[*k]))
        .collect();
    if free.is_empty() {
        return Err(Error::invalid("local sensitivity: every input is fixed"));
    }
    let mut out = Vec::new();
    for (name, &s) in responses.iter().zip(sigma) {
        let rm = model
            .response(name)
            .ok_or_else(|| Error::invalid(format!("response {name}: not in the model")))?;
        if !(s.is_finite() && s > 0.0) {
            return Err(Error::invalid(format!(
                "response {name}: uncertainty {s}; expected a positive number"
            )));
        }
        let (y, g) = model.value_and_gradient(rm, x).ok_or_else(|| {
            Error::invalid(format!(
                "response {name}: the equation is not finite at this point"
            ))
        })?;
        let gradient: Vec<f64> = free.iter().map(|&k| g[k]).collect();
        let elasticity = free.iter().map(|&k| g[k] * x[k] / y).collect();
        out.push(ResponseSensitivity {
            response: name.clone(),
            value: y,
            sigma: s,
            gradient,
            elasticity,
        });
    }
    let p = free.len();
    let fisher = DMatrix::from_fn(p, p, |a, b| {
        out.iter()
            .map(|r| r.gradient[a] * r.gradient[b] / (r.sigma * r.sigma))
            .sum::<f64>()
    });
    let information_share = (0..p)
        .map(|k| {
            out.iter()
                .map(|r| (r.gradient[k] / r.sigma).powi(2) / fisher[(k, k)])
                .collect()
        })
        .collect();
    // Singular, or so ill-conditioned that the inverse means nothing.
    let eig = fisher.clone().symmetric_eigen();
    let (lo, hi) = eig
        .eigenvalues
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &v| {
            (a.min(v), b.max(v.abs()))
        });
    let cov = if lo > 1e-12 * hi {
        fisher.try_inverse()
    } else {
        None
    };
    let parameter_sd = cov
        .as_ref()
        .map(|c| (0..p).map(|k| c[(k, k)].sqrt()).collect::<Vec<f64>>());
    let correlation = cov.as_ref().zip(parameter_sd.as_ref()).map(|(c, sd)| {
        (0..p)
            .map(|a| (0..p).map(|b| c[(a, b)] / (sd[a] * sd[b])).collect())
            .collect()
    });
    Ok(LocalSensitivity {
        parameters: free.iter().map(|&k| names[k].clone()).collect(),
        point: names.iter().cloned().zip(x.iter().copied()).collect(),
        responses: out,
        parameter_sd,
        correlation,
        information_share,
    })
}
