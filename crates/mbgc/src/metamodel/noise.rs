//! The DEM noise of a model's responses, from replicate runs: the same inputs run again with
//! another seed. A model's validation error holds one run's noise besides the equations' own
//! error; knowing the noise tells the two apart.

use std::path::Path;

use super::model::Metamodel;
use super::table::read_columns_skipping_nan;
use super::training_table::TrainingTable;
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
    replicate_noise_scaled(validation, replicates, inputs, responses, &|_, _| 1.0)
}

/// [`replicate_noise`] with each pair's difference multiplied by `scale(response index, the
/// pair's inputs)`: a response that grows with a factor of the inputs (bulk density with rho_p)
/// is brought to one reference value of it.
pub fn replicate_noise_scaled(
    validation: &Path,
    replicates: &Path,
    inputs: &[String],
    responses: &[String],
    scale: &dyn Fn(usize, &[f64]) -> f64,
) -> Result<Vec<ReplicateNoise>> {
    let same = |a: &[f64], b: &[f64]| {
        a.iter()
            .zip(b)
            .all(|(x, y)| (x - y).abs() <= 1e-12 * x.abs().max(y.abs()))
    };
    let mut out = Vec::new();
    for (k, r) in responses.iter().enumerate() {
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
                    .map(|a| (a[n] - b[n]) * scale(k, &a[..n]))
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

/// Records in `model` each response's replicate sd from `replicates` (runs at inputs of the
/// `validation` runs with another seed). A response with a factor (bulk density = rho_p phi)
/// keeps its errors at its [`super::ResponseModel::error_reference`]: when the model has none
/// yet (a file from before it was recorded) it is set to the validation runs' mean factor, where
/// the model's validation RMSE and error model were measured, and each pair's difference is
/// brought to it. Returns notes for the caller: a reference set now over validation runs whose
/// factor varies (the old error model then mixed them).
pub fn record_replicate_noise(
    model: &mut Metamodel,
    validation: &Path,
    replicates: &Path,
) -> Result<(Vec<ReplicateNoise>, Vec<String>)> {
    let inputs = model.input_names();
    let responses: Vec<String> = model.responses.iter().map(|r| r.name.clone()).collect();
    let mut notes = Vec::new();
    let has_factor = |m: &Metamodel, k: usize| m.responses[k].has_factor();
    if (0..responses.len())
        .any(|k| has_factor(model, k) && model.responses[k].error_reference.is_none())
    {
        let t = TrainingTable::read_csv(validation, &inputs, &responses)?;
        let cols = inputs
            .iter()
            .map(|i| t.column(i).map(<[f64]>::to_vec))
            .collect::<Result<Vec<_>>>()?;
        for (k, name) in responses.iter().enumerate() {
            if !has_factor(model, k) || model.responses[k].error_reference.is_some() {
                continue;
            }
            let f: Vec<f64> = (0..t.rows())
                .map(|i| {
                    let x: Vec<f64> = cols.iter().map(|c| c[i]).collect();
                    model.factor_at(&model.responses[k], &x)
                })
                .filter(|f| f.is_finite() && *f > 0.0)
                .collect();
            if f.is_empty() {
                continue;
            }
            let mean = f.iter().sum::<f64>() / f.len() as f64;
            let (lo, hi) = f
                .iter()
                .fold((f64::INFINITY, 0.0f64), |(a, b), &v| (a.min(v), b.max(v)));
            if hi - lo > 1e-9 * mean {
                notes.push(format!(
                    "{}: the validation runs' factor ranges over [{lo}, {hi}]; its errors are \
                     now read at their mean {mean}, but the error model was fitted on them \
                     unscaled (train again to fit it at one reference)",
                    name
                ));
            }
            model.responses[k].error_reference = Some(mean);
        }
    }
    let noise = {
        let m: &Metamodel = model;
        replicate_noise_scaled(validation, replicates, &inputs, &responses, &|k, x| {
            // Into the reference's unit: the inverse of what a prediction's error is scaled by.
            let s = m.error_scale(&m.responses[k], x);
            if s.is_finite() && s > 0.0 {
                1.0 / s
            } else {
                1.0
            }
        })?
    };
    for (r, n) in model.responses.iter_mut().zip(&noise) {
        r.replicate_sd = Some(n.sd);
        r.replicate_pairs = Some(n.pairs);
    }
    Ok((noise, notes))
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
