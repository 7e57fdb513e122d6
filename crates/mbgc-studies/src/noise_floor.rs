//! The seed-to-seed spread of single shear-box runs: the RMSE an exact metamodel would still show
//! on a validation table of single runs, against which the metamodel studies judge their errors.

use std::path::Path;

use anyhow::Context as _;

/// Seed-to-seed spread of the shear box's two responses.
#[derive(Clone, Debug, PartialEq)]
pub struct NoiseFloor {
    /// Standard deviation of the shear angle, deg (root of the mean variance over the points).
    pub angle_sd: f64,
    /// The same of the relative bulk density (sd / mean).
    pub bulk_rel_sd: f64,
    /// Points (design rows) the spread was measured at.
    pub points: usize,
    /// Runs behind it.
    pub runs: usize,
}

/// Seed-to-seed spread inside the campaign's space: validation rows rerun with another seed
/// (`training_data/<name>_replicates.csv`: some of the validation design's points, matched by
/// their inputs), sd = rms difference / sqrt 2.
/// `None` when the replicate table does not exist or shares no row with the validation table.
pub fn replicate_noise(validation: &Path, replicates: &Path) -> anyhow::Result<Option<NoiseFloor>> {
    if !replicates.exists() {
        return Ok(None);
    }
    let (v, r) = (done_rows(validation)?, done_rows(replicates)?);
    let (mut da, mut db, mut runs) = (Vec::new(), Vec::new(), 0);
    for (row, a2, b2) in &r {
        if let Some((_, a1, b1)) = v.iter().find(|(x, _, _)| x == row) {
            runs += 1;
            if (a1 - a2).is_finite() {
                da.push(a1 - a2);
            }
            if (b1 - b2).is_finite() {
                db.push((b1 - b2) / (0.5 * (b1 + b2)));
            }
        }
    }
    let sd = |d: &[f64]| (d.iter().map(|x| x * x).sum::<f64>() / (2.0 * d.len() as f64)).sqrt();
    Ok((runs > 0).then(|| NoiseFloor {
        angle_sd: sd(&da),
        bulk_rel_sd: sd(&db),
        points: runs,
        runs: 2 * runs,
    }))
}

/// `(inputs, shear_angle, bulk_density)` of every done run of a campaign table, the inputs as
/// written (the columns between `model_class` and the first response); NaN for a response the
/// run did not measure.
fn done_rows(path: &Path) -> anyhow::Result<Vec<(String, f64, f64)>> {
    let mut r = csv::Reader::from_path(path).with_context(|| path.display().to_string())?;
    let header = r.headers()?.clone();
    let col = |name: &str| {
        header
            .iter()
            .position(|c| c == name)
            .with_context(|| format!("{}: no column {name}", path.display()))
    };
    let (first, st, a, b) = (
        col("model_class")? + 1,
        col("status")?,
        col("shear_angle")?,
        col("bulk_density")?,
    );
    let num = |rec: &csv::StringRecord, i: usize| rec[i].parse().unwrap_or(f64::NAN);
    let mut out = Vec::new();
    for rec in r.records() {
        let rec = rec.with_context(|| path.display().to_string())?;
        if &rec[st] == "done" {
            // The design's columns: a backend's name is not an input.
            let inputs: Vec<&str> = (first..a)
                .filter(|&i| &header[i] != "backend")
                .map(|i| &rec[i])
                .collect();
            out.push((inputs.join(","), num(&rec, a), num(&rec, b)));
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shipped replicates rerun the first 12 validation points; matched by their inputs,
    /// they give the noise docs/metamodel.md reports.
    #[test]
    fn shipped_replicates_match_their_validation_rows_by_inputs() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let n = replicate_noise(
            &root.join("training_data/shear_box_validation.csv"),
            &root.join("training_data/shear_box_replicates.csv"),
        )
        .unwrap()
        .unwrap();
        assert_eq!(n.points, 12);
        assert!((n.angle_sd - 1.06).abs() < 0.005, "{}", n.angle_sd);
        assert!(
            (n.bulk_rel_sd - 0.0026).abs() < 0.00005,
            "{}",
            n.bulk_rel_sd
        );
    }
}
