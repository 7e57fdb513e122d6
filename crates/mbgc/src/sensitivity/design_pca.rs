//! Seed 000's Level 2 on a design: at every design point the contact-law sensitivities of the
//! parameters that vary (at one fixed contact state, the generalised forms of the paper's
//! Table 4) form the columns, the bulk response measured at that point is one more column, and
//! the autoscaled matrix goes through [`pca`](super::pca). With the state fixed, a parameter's
//! column is a fixed function of that parameter alone, so the analysis asks how the response
//! co-varies with those functions over the design.

use super::contact_derivatives::{Properties, State, PARAMETERS};
use super::pca::{pca, Pca};
use super::sensitivity_matrix::{over_design, Equation};
use crate::error::{Error, Result};

/// The parameters of [`PARAMETERS`] that take more than one value over the points.
pub fn varied(points: &[Properties]) -> Vec<usize> {
    (0..PARAMETERS.len())
        .filter(|&k| {
            let v: Vec<f64> = points.iter().map(|p| p.values()[k]).collect();
            v.iter().any(|x| *x != v[0])
        })
        .collect()
}

/// What [`design_pca`] found.
#[derive(Debug, Clone)]
pub struct DesignPca {
    /// The PCA of the autoscaled matrix [sensitivities | response].
    pub pca: Pca,
    /// Points left out for a non-finite response.
    pub dropped: usize,
    /// Parameters whose sensitivity is the same at every point in this equation (a parameter
    /// that does not enter it, such as mu_r in the contact force): left out, named here.
    pub constant: Vec<String>,
}

/// PCA of the matrix [sensitivities of `params` | response]. Points with a non-finite response
/// are left out, and so are parameters whose sensitivity column does not vary.
pub fn design_pca(
    points: &[Properties],
    response_name: &str,
    response: &[f64],
    state: &State,
    eq: Equation,
    params: &[usize],
) -> Result<DesignPca> {
    if params.is_empty() {
        return Err(Error::invalid(
            "pca: no contact-law parameter varies over the design (E_p, e_pp, mu_pp, mu_r_pp)",
        ));
    }
    let keep: Vec<usize> = (0..points.len())
        .filter(|&i| response[i].is_finite())
        .collect();
    let kept: Vec<Properties> = keep.iter().map(|&i| points[i]).collect();
    let rows = over_design(&kept, state, eq);
    let mut names = Vec::new();
    let mut cols: Vec<Vec<f64>> = Vec::new();
    let mut constant = Vec::new();
    for &k in params {
        let c: Vec<f64> = rows.iter().map(|r| r[k]).collect();
        if c.iter().all(|v| *v == c[0]) {
            constant.push(PARAMETERS[k].to_string());
        } else {
            names.push(PARAMETERS[k].to_string());
            cols.push(c);
        }
    }
    if cols.is_empty() {
        return Err(Error::invalid(format!(
            "pca, {} equation: no parameter's sensitivity varies over the design",
            eq.name()
        )));
    }
    names.push(response_name.to_string());
    cols.push(keep.iter().map(|&i| response[i]).collect());
    let p = pca(&names, &cols, Some(response_name))
        .map_err(|e| Error::invalid(format!("{} equation: {e}", eq.name())))?;
    Ok(DesignPca {
        pca: p,
        dropped: points.len() - keep.len(),
        constant,
    })
}
