//! `diagnose`: where the models fail on a measurement set and which effect is missing, as `mbgc
//! diagnose` runs it without `--build` (src/diagnose.rs): the same option checks, the shipped
//! shear-box models (base and cohesive) by default, the JSON report of `--json` and the
//! Markdown report the command prints.

use pyo3::prelude::*;

use mbgc::diagnose::report::markdown;
use mbgc::diagnose::{diagnose as run, MeasurementSet, Options, Surrogate};

use crate::builtin;
use crate::documents::Document;
use crate::errors::{invalid, to_py, OrRaise};
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
    if !(alpha > 0.0 && alpha < 1.0) {
        return Err(invalid(
            py,
            format!("--alpha: expected a level between 0 and 1, got {alpha}"),
        ));
    }
    let max = mbgc::calibrate::tmcmc::MAX_SAMPLES;
    if !(100..=max).contains(&samples) {
        return Err(invalid(
            py,
            format!("--samples: expected 100 to {max} TMCMC samples per stage, got {samples}"),
        ));
    }
    let max_starts = mbgc::calibrate::session::MAX_STARTS;
    if starts == 0 || starts > max_starts {
        return Err(invalid(
            py,
            format!("--starts {starts}: expected 1 to {max_starts}"),
        ));
    }
    let set = match Document::new(py, measurements_path, measurements_json, measurements_label)? {
        Document::File(path) => MeasurementSet::from_file(&path),
        Document::Text { toml, label } => MeasurementSet::from_toml_str(&toml, &label),
    }
    .or_raise(py)?;
    let surrogates = if models.is_empty() {
        [builtin::SHEAR_BOX_MODEL, builtin::SHEAR_BOX_SJKR_MODEL]
            .iter()
            .map(|name| builtin::model(name).and_then(|(m, l)| Surrogate::from_model(m, &l)))
            .collect::<mbgc::Result<Vec<_>>>()
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
    let opts = Options {
        starts,
        samples,
        seed,
        alpha,
    };
    let d = py
        .detach(|| run(&set, &surrogates, &opts))
        .map_err(|e| to_py(py, e))?;
    Ok((json(&d).to_string(), markdown(&d).trim_end().to_string()))
}

/// The JSON report of `mbgc diagnose --json` (src/diagnose.rs's `json`), without `built`:
/// the keys first, then the rest.
fn json(d: &mbgc::diagnose::Diagnosis) -> serde_json::Value {
    serde_json::json!({
        "set": d.set,
        "class": d.class,
        "chi2_dof": d.chi2_dof,
        "p_value": d.p_value,
        "residuals": d.base.residuals,
        "structure": d.base.structure,
        "ranking": d.ranking,
        "unavailable": d.unavailable,
        "verdict": d.verdict,
        "base": d.base,
        "extended": d.extended,
        "settings": d.settings,
    })
}
