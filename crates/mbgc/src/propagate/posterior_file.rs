//! The posterior samples `mbgc calibrate --bayes --posterior-out` writes, read back: one row per
//! sample with every model input, the relative model error `sigma`, the sample's `weight`, and
//! the `model` and `material` the calibration was of.

use std::path::Path;

use crate::error::{read_to_string, Error, Result};

/// The columns after the model inputs, in this order.
pub const TRAILING_COLUMNS: [&str; 4] = ["sigma", "weight", "model", "material"];

/// A posterior as rows of samples.
#[derive(Debug, Clone, PartialEq)]
pub struct PosteriorFile {
    /// The model inputs, in the file's order.
    pub inputs: Vec<String>,
    /// One row per sample: the inputs' values.
    pub rows: Vec<Vec<f64>>,
    /// The relative model error of each sample (0 where it was not sampled).
    pub sigma: Vec<f64>,
    /// The weight of each sample (finite, >= 0, not all 0; they need not sum to 1).
    pub weights: Vec<f64>,
    /// The model the posterior is of (one per file).
    pub model: String,
    /// The material calibrated (one per file).
    pub material: String,
}

impl PosteriorFile {
    /// Reads a posterior file; a missing column, a value that is not a finite number, a negative
    /// or NaN weight, weights all 0, or rows of more than one model or material are refused,
    /// naming the file, the line and the column.
    pub fn read(path: &Path) -> Result<PosteriorFile> {
        PosteriorFile::parse(&read_to_string(path)?, &path.display().to_string())
    }

    /// [`PosteriorFile::read`] on text; `file` names it in errors.
    pub fn parse(text: &str, file: &str) -> Result<PosteriorFile> {
        let mut reader = csv::ReaderBuilder::new()
            .has_headers(true)
            .from_reader(text.as_bytes());
        let header: Vec<String> = reader
            .headers()
            .map_err(|e| Error::input(file, "header", format!("a CSV header ({e})")))?
            .iter()
            .map(|h| h.trim().to_string())
            .collect();
        let k = header.len().saturating_sub(TRAILING_COLUMNS.len());
        if header.len() <= TRAILING_COLUMNS.len() || header[k..] != TRAILING_COLUMNS {
            return Err(Error::input(
                file,
                "header",
                format!(
                    "the model inputs, then {} (as calibrate --posterior-out writes them), found \
                     {}",
                    TRAILING_COLUMNS.join(","),
                    header.join(",")
                ),
            ));
        }
        let inputs = header[..k].to_vec();
        if let Some(dup) = inputs
            .iter()
            .enumerate()
            .find(|(i, c)| inputs[..*i].contains(c))
        {
            return Err(Error::input(
                file,
                "header",
                format!("distinct column names, found {} twice", dup.1),
            ));
        }
        let mut post = PosteriorFile {
            inputs,
            rows: Vec::new(),
            sigma: Vec::new(),
            weights: Vec::new(),
            model: String::new(),
            material: String::new(),
        };
        for (i, rec) in reader.records().enumerate() {
            let line = i + 2;
            let rec = rec.map_err(|e| Error::input(file, format!("line {line}"), e.to_string()))?;
            if rec.len() != header.len() {
                return Err(Error::input(
                    file,
                    format!("line {line}"),
                    format!("{} fields, found {}", header.len(), rec.len()),
                ));
            }
            let number = |j: usize| -> Result<f64> {
                let field = rec[j].trim();
                field
                    .parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| {
                        Error::input(
                            file,
                            format!("line {line}, column {}", header[j]),
                            format!("a finite number, found \"{field}\""),
                        )
                    })
            };
            post.rows.push((0..k).map(number).collect::<Result<_>>()?);
            post.sigma.push(number(k)?);
            let w = number(k + 1)?;
            if w < 0.0 {
                return Err(Error::input(
                    file,
                    format!("line {line}, column weight"),
                    format!("a weight >= 0, found {w}"),
                ));
            }
            post.weights.push(w);
            for (j, slot) in [(k + 2, &mut post.model), (k + 3, &mut post.material)] {
                if i == 0 {
                    *slot = rec[j].to_string();
                } else if *slot != rec[j] {
                    return Err(Error::input(
                        file,
                        format!("line {line}, column {}", header[j]),
                        format!(
                            "one {} per file (line 2 has \"{slot}\"), found \"{}\"",
                            header[j], &rec[j]
                        ),
                    ));
                }
            }
        }
        if post.rows.is_empty() {
            return Err(Error::input(
                file,
                "rows",
                "at least one sample, found none",
            ));
        }
        if post.weights.iter().sum::<f64>() <= 0.0 {
            return Err(Error::input(file, "weight", "weights that are not all 0"));
        }
        Ok(post)
    }

    /// The value of input `name` in sample `row`.
    pub fn value(&self, row: usize, name: &str) -> Option<f64> {
        let j = self.inputs.iter().position(|c| c == name)?;
        self.rows.get(row).map(|r| r[j])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = "mu_pp,d50,sigma,weight,model,material\n\
                        0.3,11.2,0.08,0.5,models/shear_box.json,Gravel 8/16\n\
                        0.4,11.2,0.06,0.5,models/shear_box.json,Gravel 8/16\n";

    #[test]
    fn reads_the_columns_calibrate_writes() {
        let p = PosteriorFile::parse(GOOD, "p.csv").unwrap();
        assert_eq!(p.inputs, ["mu_pp", "d50"]);
        assert_eq!(p.rows, [vec![0.3, 11.2], vec![0.4, 11.2]]);
        assert_eq!(p.sigma, [0.08, 0.06]);
        assert_eq!(p.weights, [0.5, 0.5]);
        assert_eq!(
            (p.model.as_str(), p.material.as_str()),
            ("models/shear_box.json", "Gravel 8/16")
        );
        assert_eq!(p.value(1, "mu_pp"), Some(0.4));
        assert_eq!(p.value(1, "rho_p"), None);
    }

    #[test]
    fn bad_files_are_refused_naming_the_line_and_column() {
        let cases = [
            ("mu_pp,sigma,weight,model\n0.3,0.1,1,m\n", "header"),
            ("mu_pp,sigma,weight,model,material\n", "at least one sample"),
            (
                "mu_pp,sigma,weight,model,material\n0.3,0.1,NaN,m,x\n",
                "line 2, column weight",
            ),
            (
                "mu_pp,sigma,weight,model,material\n0.3,0.1,-1,m,x\n",
                "a weight >= 0",
            ),
            (
                "mu_pp,sigma,weight,model,material\nabc,0.1,1,m,x\n",
                "line 2, column mu_pp",
            ),
            (
                "mu_pp,sigma,weight,model,material\n0.3,0.1,0,m,x\n",
                "not all 0",
            ),
            (
                "mu_pp,sigma,weight,model,material\n0.3,0.1,1,m,x\n0.3,0.1,1,n,x\n",
                "line 3, column model",
            ),
            (
                "mu_pp,mu_pp,sigma,weight,model,material\n1,1,0.1,1,m,x\n",
                "twice",
            ),
            ("mu_pp,sigma,weight,model,material\n0.3,0.1,1,m\n", "line 2"),
        ];
        for (text, want) in cases {
            let e = PosteriorFile::parse(text, "post.csv")
                .unwrap_err()
                .to_string();
            assert!(e.contains("post.csv") && e.contains(want), "{want}: {e}");
        }
    }
}
