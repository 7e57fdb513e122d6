//! The figures of a fit: for each response a parity plot and a residual histogram over its
//! training, test and validation rows (`mbgc fit` draws them unless `--no-figures`).

use std::path::{Path, PathBuf};

use super::parity::{parity, residual_histogram, Split};
use crate::error::Result;
use crate::metamodel::Fit;

/// Writes `<response>_parity.svg` and `<response>_residuals.svg` into `dir` for every response
/// of the fit and returns their paths in that order.
pub fn fit_figures(dir: &Path, fit: &Fit) -> Result<Vec<PathBuf>> {
    let mut figures = Vec::new();
    for s in &fit.splits {
        let mut splits = vec![Split {
            label: "train",
            observed: &s.train.observed,
            predicted: &s.train.predicted,
        }];
        for (label, v) in [("test", &s.test), ("validation", &s.validation)] {
            if let Some(v) = v {
                splits.push(Split {
                    label,
                    observed: &v.observed,
                    predicted: &v.predicted,
                });
            }
        }
        let target = &s.response;
        let parity_path = dir.join(format!("{target}_parity.svg"));
        let hist_path = dir.join(format!("{target}_residuals.svg"));
        parity(&parity_path, target, &splits)?;
        residual_histogram(&hist_path, target, &splits)?;
        figures.push(parity_path);
        figures.push(hist_path);
    }
    Ok(figures)
}
