//! `diagnose`: where the models fail on a measurement set and which effect is missing, as `mbgc
//! diagnose` runs it without `--build` (src/diagnose.rs): the same option checks, the shipped
//! shear-box models (base and cohesive) by default, the JSON report of `--json` and the
//! Markdown report the command prints.

use pyo3::prelude::*;

use mbgc::diagnose::report::{json, markdown};
use mbgc::diagnose::{diagnose as run, MeasurementSet, Options, Surrogate};
use mbgc::shipped;

use crate::documents::Document;
use crate::errors::{to_py, OrRaise};
use crate::model::NativeModel;

/// Diagnoses the measurement set (a file, or a dict's JSON) with the models; returns the JSON
/// report and the Markdown one.
#[pyfunction]
#[pyo3(signature = (measurements_path, measurements_json, measurements_label, models, starts, samples, seed, alpha))]
#[allow(clippy::too_many_arguments)]
pub fn diagnose(
    py: Python<'_>,
    measurements_path: Option<std::path::PathBuf>,
    measurements_json: Option<String>,
    measurements_label: &str,
    models: Vec<Py<NativeModel>>,
    starts: usize,
    samples: usize,
    seed: u64,
    alpha: f64,
) -> PyResult<(String, String)> {
    let opts = Options {
        starts,
        samples,
        seed,
        alpha,
    };
    opts.check().or_raise(py)?;
    let set = match Document::new(py, measurements_path, measurements_json, measurements_label)? {
        Document::File(path) => MeasurementSet::from_file(&path),
        Document::Text { toml, label } => MeasurementSet::from_toml_str(&toml, &label),
    }
    .or_raise(py)?;
    let surrogates = if models.is_empty() {
        shipped::models(shipped::DIAGNOSIS_MODELS).and_then(|models| {
            models
                .into_iter()
                .map(|(m, label)| Surrogate::from_model(m, &label))
                .collect::<mbgc::Result<Vec<_>>>()
        })
    } else {
        models
            .iter()
            .map(|m| {
                let m = m.get();
                Surrogate::from_model(m.model.clone(), &m.label)
            })
            .collect()
    }
    .or_raise(py)?;
    let d = py
        .detach(|| run(&set, &surrogates, &opts))
        .map_err(|e| to_py(py, e))?;
    Ok((json(&d).to_string(), markdown(&d).trim_end().to_string()))
}
