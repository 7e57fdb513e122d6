//! Seed 000's Level 2: principal component analysis of an autoscaled matrix whose columns are
//! parameter sensitivities plus one bulk response. Each column is centred and divided by its
//! standard deviation, the covariance matrix Q = S^T S / (n - 1) (then the correlation matrix)
//! is diagonalised, and the components are ranked by eigenvalue. A parameter whose loading is
//! large in a leading component that also loads the response moves with that response.
//!
//! Signs: an eigenvector's sign is arbitrary; each is turned so that the response's loading is
//! non-negative, so that a parameter's loading sign says whether it rises or falls with the
//! response inside that component.

use nalgebra::{DMatrix, SymmetricEigen};
use serde::Serialize;

use crate::error::{Error, Result};

/// One principal component of the autoscaled matrix.
#[derive(Debug, Clone, Serialize)]
pub struct Component {
    /// Eigenvalue of the correlation matrix: the variance the component carries, in units of one
    /// column's (autoscaled) variance.
    pub eigenvalue: f64,
    /// Eigenvalue over the sum of eigenvalues.
    pub explained: f64,
    /// Column name -> loading (the eigenvector's entry), in the columns' order.
    pub loadings: Vec<(String, f64)>,
}

/// Principal components of an autoscaled sensitivity matrix, largest eigenvalue first.
#[derive(Debug, Clone, Serialize)]
pub struct Pca {
    /// Column names: parameter sensitivities, then usually the response.
    pub columns: Vec<String>,
    /// Rows (states or design points) the matrix had.
    pub rows: usize,
    /// All components, ranked by decreasing eigenvalue.
    pub components: Vec<Component>,
}

/// PCA of `columns` (each one a column of the matrix); `response` names the column whose
/// loading fixes the eigenvectors' signs (None: the largest loading is made positive).
pub fn pca(names: &[String], columns: &[Vec<f64>], response: Option<&str>) -> Result<Pca> {
    let k = columns.len();
    let n = columns.first().map_or(0, Vec::len);
    if k == 0 || n < 3 || columns.iter().any(|c| c.len() != n) {
        return Err(Error::invalid(format!(
            "pca: {k} columns of {n} rows; expected equal columns of at least 3 rows"
        )));
    }
    let mut scaled = DMatrix::zeros(n, k);
    for (j, (c, name)) in columns.iter().zip(names).enumerate() {
        if let Some(r) = c.iter().position(|v| !v.is_finite()) {
            return Err(Error::invalid(format!(
                "pca: column {name}, row {}: not a finite number",
                r + 1
            )));
        }
        let mean = c.iter().sum::<f64>() / n as f64;
        let var = c.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        if var <= 0.0 {
            return Err(Error::invalid(format!(
                "pca: column {name} is constant; autoscaling needs a column that varies (leave \
                 it out)"
            )));
        }
        let sd = var.sqrt();
        for (r, v) in c.iter().enumerate() {
            scaled[(r, j)] = (v - mean) / sd;
        }
    }
    let q = scaled.transpose() * &scaled / (n - 1) as f64;
    let eig = SymmetricEigen::new(q);
    let mut order: Vec<usize> = (0..k).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let total: f64 = eig.eigenvalues.iter().map(|v| v.max(0.0)).sum();
    let ri = response.and_then(|r| names.iter().position(|n| n == r));
    let components = order
        .iter()
        .map(|&c| {
            let v = eig.eigenvectors.column(c);
            let pivot = ri.unwrap_or_else(|| {
                (0..k)
                    .max_by(|&a, &b| v[a].abs().total_cmp(&v[b].abs()))
                    .unwrap_or(0)
            });
            let sign = if v[pivot] < 0.0 { -1.0 } else { 1.0 };
            Component {
                eigenvalue: eig.eigenvalues[c].max(0.0),
                explained: eig.eigenvalues[c].max(0.0) / total,
                loadings: names
                    .iter()
                    .zip(v.iter())
                    .map(|(n, x)| (n.clone(), sign * x))
                    .collect(),
            }
        })
        .collect();
    Ok(Pca {
        columns: names.to_vec(),
        rows: n,
        components,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(v: &[&str]) -> Vec<String> {
        v.iter().map(|s| s.to_string()).collect()
    }

    /// y = 3 a - b with a, b on an orthogonal grid and c independent noise: the first component
    /// loads y, a and b; c sits alone in a component of eigenvalue about 1.
    #[test]
    fn a_linear_model_loads_its_inputs_by_their_weights() {
        let mut a = Vec::new();
        let mut b = Vec::new();
        let mut c = Vec::new();
        let mut y = Vec::new();
        let mut k = 0usize;
        for i in 0..6 {
            for j in 0..6 {
                for l in 0..2 {
                    let (ai, bj) = (i as f64, j as f64);
                    let cl = if (i + j + l) % 2 == 0 { 1.0 } else { -1.0 };
                    a.push(ai);
                    b.push(bj);
                    c.push(cl);
                    y.push(3.0 * ai - bj);
                    k += 1;
                }
            }
        }
        assert_eq!(k, 72);
        let p = pca(&names(&["a", "b", "c", "y"]), &[a, b, c, y], Some("y")).unwrap();
        let sum: f64 = p.components.iter().map(|c| c.eigenvalue).sum();
        assert!(
            (sum - 4.0).abs() < 1e-9,
            "trace of a correlation matrix is its size"
        );
        let first = &p.components[0];
        let l = |n: &str| first.loadings.iter().find(|(m, _)| m == n).unwrap().1;
        // a and y are correlated 3/sqrt(10) = 0.949; b and y -1/sqrt(10).
        assert!(l("y") > 0.0 && l("a") > 0.0 && l("b") < 0.0, "{first:?}");
        assert!(l("a").abs() > 2.0 * l("b").abs());
        assert!(l("c").abs() < 1e-9, "{first:?}");
        // The correlation matrix has a zero eigenvalue: y is exactly a combination of a and b.
        assert!(p.components[3].eigenvalue < 1e-9);
        let c_comp = p
            .components
            .iter()
            .find(|comp| comp.loadings[2].1.abs() > 0.99)
            .expect("c has its own component");
        assert!((c_comp.eigenvalue - 1.0).abs() < 1e-9);
    }

    #[test]
    fn a_constant_column_is_refused_by_name() {
        let e = pca(
            &names(&["a", "k"]),
            &[vec![1.0, 2.0, 3.0], vec![5.0; 3]],
            None,
        );
        assert!(e.unwrap_err().to_string().contains("column k is constant"));
    }
}
