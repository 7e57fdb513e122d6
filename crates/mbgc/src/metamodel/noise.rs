//! The DEM noise of a model's responses, from replicate runs: the same inputs run again with
//! another seed. A model's validation error holds one run's noise besides the equations' own
//! error; knowing the noise tells the two apart.

use std::path::Path;

use super::table::read_columns_skipping_nan;
use crate::error::{Error, Result};

/// The noise that a replicate sd `sd` from `pairs` pairs is at least, with 95 % confidence
/// (`sd` itself when the pairs are not known): `sd sqrt(pairs / chi2_0.95(pairs))`, each pair
/// difference being one degree of freedom. A model's own error is its validation RMSE less the
/// noise; subtracting the point estimate of a loose noise can leave nothing of an error that is
/// there (12 pairs: the true sd may be 25 % lower).
pub fn lower_bound(sd: f64, pairs: Option<usize>) -> f64 {
    use statrs::distribution::{ChiSquared, ContinuousCDF};
    match pairs.filter(|&n| n > 0) {
        Some(n) => match ChiSquared::new(n as f64) {
            Ok(c) => sd * (n as f64 / c.inverse_cdf(0.95)).sqrt(),
            Err(_) => sd,
        },
        None => sd,
    }
}

/// The replicate noise of one response.
#[derive(Clone, Debug, PartialEq)]
pub struct ReplicateNoise {
    /// Response name.
    pub response: String,
    /// Standard deviation of one run at fixed inputs, in the response's unit: `sqrt(sum d^2 /
    /// 2n)` over the `pairs` differences `d` between a run and its replicate.
    pub sd: f64,
    /// Pairs (a validation run and its replicate) that measured the response both times.
    pub pairs: usize,
}

/// Pairs each run of `replicates` with the run of `validation` that has the same `inputs`, and
/// returns each response's replicate sd. A response no pair measured twice is an error naming
/// the files.
pub fn replicate_noise(
    validation: &Path,
    replicates: &Path,
    inputs: &[String],
    responses: &[String],
) -> Result<Vec<ReplicateNoise>> {
    let same = |a: &[f64], b: &[f64]| {
        a.iter()
            .zip(b)
            .all(|(x, y)| (x - y).abs() <= 1e-12 * x.abs().max(y.abs()))
    };
    let mut out = Vec::new();
    for r in responses {
        let mut names = inputs.to_vec();
        names.push(r.clone());
        let read = |p: &Path| -> Result<Vec<Vec<f64>>> {
            let c = read_columns_skipping_nan(p, &names, inputs.len())?;
            let rows = c.values.first().map_or(0, Vec::len);
            Ok((0..rows)
                .map(|i| c.values.iter().map(|col| col[i]).collect())
                .collect())
        };
        let (v, rep) = (read(validation)?, read(replicates)?);
        let n = inputs.len();
        let d: Vec<f64> = rep
            .iter()
            .filter_map(|b| {
                v.iter()
                    .find(|a| same(&a[..n], &b[..n]))
                    .map(|a| a[n] - b[n])
            })
            .collect();
        if d.is_empty() {
            return Err(Error::input(
                replicates.display().to_string(),
                r,
                format!(
                    "runs at the inputs of runs in {} ({}), measured twice: no run of the one \
                     repeats a run of the other",
                    validation.display(),
                    inputs.join(", ")
                ),
            ));
        }
        out.push(ReplicateNoise {
            response: r.clone(),
            sd: (d.iter().map(|x| x * x).sum::<f64>() / (2.0 * d.len() as f64)).sqrt(),
            pairs: d.len(),
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_noise_from_few_pairs_is_lowered_more_than_one_from_many() {
        assert_eq!(lower_bound(2.0, None), 2.0);
        let few = lower_bound(2.0, Some(12));
        let many = lower_bound(2.0, Some(200));
        // chi2_0.95(12) = 21.03, chi2_0.95(200) = 234.0
        assert!(
            (few - 2.0 * (12.0f64 / 21.026).sqrt()).abs() < 1e-3,
            "{few}"
        );
        assert!(
            (many - 2.0 * (200.0f64 / 233.994).sqrt()).abs() < 1e-3,
            "{many}"
        );
    }

    #[test]
    fn pairs_are_matched_by_their_inputs_and_pooled() {
        let dir = tempfile::tempdir().unwrap();
        let v = dir.path().join("v.csv");
        let r = dir.path().join("r.csv");
        std::fs::write(
            &v,
            "status,a,b,y\ndone,1,2,10\ndone,3,4,20\ndone,5,6,30\nfailed,7,8,NaN\n",
        )
        .unwrap();
        // Out of order, one row with no partner and one whose response was not measured.
        std::fs::write(
            &r,
            "status,a,b,y\ndone,5,6,33\ndone,1,2,9\ndone,9,9,1\ndone,3,4,NaN\n",
        )
        .unwrap();
        let names = |s: &[&str]| s.iter().map(|x| x.to_string()).collect::<Vec<_>>();
        let n = replicate_noise(&v, &r, &names(&["a", "b"]), &names(&["y"])).unwrap();
        // d = -3 and 1: sqrt(10 / 4).
        assert_eq!(n[0].pairs, 2);
        assert!((n[0].sd - 2.5f64.sqrt()).abs() < 1e-12);
        std::fs::write(&r, "status,a,b,y\ndone,9,9,1\n").unwrap();
        let e = replicate_noise(&v, &r, &names(&["a", "b"]), &names(&["y"]))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("r.csv") && e.contains("v.csv") && e.contains("y"),
            "{e}"
        );
    }
}
