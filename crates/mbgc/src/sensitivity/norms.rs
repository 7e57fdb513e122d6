//! Seed 000's Level 3 summaries of a sensitivity matrix: the norm of each parameter's column
//! (Eq. 17), its share of the norms' sum (the paper's normalisation), and the cross-correlation
//! of two columns (Eq. 18), CC = S_a^T S_b / sqrt(S_a^T S_a S_b^T S_b), which lies in [-1, 1];
//! |CC| near 1 means the two parameters move the response in the same pattern over the states
//! and cannot be told apart from it. The Pearson correlation (columns centred first) is given
//! too: the uncentred form counts a shared sign as agreement.

use serde::Serialize;

/// Column norms and cross-correlations of a sensitivity matrix (seed 000, Level 3).
#[derive(Debug, Clone, Serialize)]
pub struct NormSummary {
    /// Parameter names, one per column.
    pub parameters: Vec<String>,
    /// Euclidean norm of each parameter's sensitivity column over the states (Eq. 17).
    pub norms: Vec<f64>,
    /// norms / sum of norms.
    pub shares: Vec<f64>,
    /// Uncentred cross-correlation CC of every pair of columns (Eq. 18), in [-1, 1].
    pub cross_correlation: Vec<Vec<f64>>,
    /// Pearson correlation of every pair of columns (centred first), in [-1, 1].
    pub pearson: Vec<Vec<f64>>,
}

fn column(m: &[Vec<f64>], k: usize) -> Vec<f64> {
    m.iter().map(|r| r[k]).collect()
}

fn cosine(a: &[f64], b: &[f64]) -> f64 {
    let ab: f64 = a.iter().zip(b).map(|(x, y)| x * y).sum();
    let aa: f64 = a.iter().map(|x| x * x).sum();
    let bb: f64 = b.iter().map(|x| x * x).sum();
    if aa > 0.0 && bb > 0.0 {
        ab / (aa * bb).sqrt()
    } else {
        f64::NAN
    }
}

fn centred(a: &[f64]) -> Vec<f64> {
    let m = a.iter().sum::<f64>() / a.len().max(1) as f64;
    a.iter().map(|v| v - m).collect()
}

/// Summary of a matrix `m[row][parameter]`.
pub fn summarise(parameters: &[String], m: &[Vec<f64>]) -> NormSummary {
    let k = parameters.len();
    let cols: Vec<Vec<f64>> = (0..k).map(|j| column(m, j)).collect();
    let norms: Vec<f64> = cols
        .iter()
        .map(|c| c.iter().map(|v| v * v).sum::<f64>().sqrt())
        .collect();
    let total: f64 = norms.iter().sum();
    let shares = norms.iter().map(|n| n / total).collect();
    let cc = (0..k)
        .map(|a| (0..k).map(|b| cosine(&cols[a], &cols[b])).collect())
        .collect();
    let centred_cols: Vec<Vec<f64>> = cols.iter().map(|c| centred(c)).collect();
    let pearson = (0..k)
        .map(|a| {
            (0..k)
                .map(|b| cosine(&centred_cols[a], &centred_cols[b]))
                .collect()
        })
        .collect();
    NormSummary {
        parameters: parameters.to_vec(),
        norms,
        shares,
        cross_correlation: cc,
        pearson,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn norms_and_correlations_of_a_known_matrix() {
        // Column b = 2 a (fully correlated), c orthogonal to a.
        let m = vec![
            vec![1.0, 2.0, 1.0],
            vec![2.0, 4.0, 0.0],
            vec![0.0, 0.0, 3.0],
        ];
        let names: Vec<String> = ["a", "b", "c"].iter().map(|s| s.to_string()).collect();
        let s = summarise(&names, &m);
        assert!((s.norms[0] - 5f64.sqrt()).abs() < 1e-12);
        assert!((s.norms[1] - 2.0 * 5f64.sqrt()).abs() < 1e-12);
        assert!((s.shares.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        assert!((s.cross_correlation[0][1] - 1.0).abs() < 1e-12);
        let ac = 1.0 / (5f64.sqrt() * 10f64.sqrt());
        assert!((s.cross_correlation[0][2] - ac).abs() < 1e-12);
        assert!((s.pearson[0][1] - 1.0).abs() < 1e-12);
    }
}
