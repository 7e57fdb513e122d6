//! `calibrate`: a material's parameters from its measurements, by inverting saved metamodels,
//! as `mbgc calibrate` runs it (src/calibrate.rs): the same material reading, `--free`, options
//! and sessions; the result is the session's JSON (what `--json` prints), its calibrated TOML
//! (what `--out` writes) and the posterior draws the corner plot shows.

use pyo3::prelude::*;

use mbgc::calibrate::report;
use mbgc::calibrate::session::{self, SessionOptions};
use mbgc::material::Material;
use mbgc::shipped;

use crate::documents::Document;
use crate::errors::{to_py, OrRaise};
use crate::model::NativeModel;

/// One model's session: its JSON (`session`: what `--json` prints; beside it the material
/// file, its fixed values and measurements, the free parameters, their search box, those no
/// equation reads, and `report`: the text `mbgc calibrate` prints), its calibrated TOML, the
/// names of the posterior's axes and the draws (one row per draw; empty without a posterior).
type SessionResult = (String, String, Vec<String>, Vec<Vec<f64>>);

/// Calibrates the material (a file, or a dict's JSON) against each model (the shipped
/// shear-box model when none is given). Returns one session per model and, with a posterior
/// and several models, the model classes' probabilities.
#[pyfunction]
#[pyo3(signature = (material_path, material_json, material_label, models, free, starts, seed, bayes, samples, sigma_max))]
#[allow(clippy::too_many_arguments)]
pub fn calibrate(
    py: Python<'_>,
    material_path: Option<std::path::PathBuf>,
    material_json: Option<String>,
    material_label: &str,
    models: Vec<Py<NativeModel>>,
    free: Vec<String>,
    starts: usize,
    seed: u64,
    bayes: bool,
    samples: usize,
    sigma_max: f64,
) -> PyResult<(Vec<SessionResult>, Option<Vec<f64>>)> {
    let mut material = match Document::new(py, material_path, material_json, material_label)? {
        Document::File(path) => {
            let (m, note) = shipped::material(&path).or_raise(py)?;
            if let Some(note) = note {
                let category = py.get_type::<pyo3::exceptions::PyUserWarning>();
                let text = std::ffi::CString::new(note).unwrap_or_default();
                PyErr::warn(py, &category, &text, 2)?;
            }
            m
        }
        Document::Text { toml, label } => Material::from_toml_str(&toml, &label).or_raise(py)?,
    };
    material.free(&free).or_raise(py)?;
    let opts = SessionOptions {
        starts,
        seed,
        bayes,
        samples,
        sigma_max,
    };
    opts.check().or_raise(py)?;
    let defaults: Vec<NativeModel>;
    let models: Vec<&NativeModel> = if models.is_empty() {
        defaults = shipped::models(shipped::CALIBRATION_MODELS)
            .or_raise(py)?
            .into_iter()
            .map(|(m, label)| NativeModel::new(m, label))
            .collect();
        defaults.iter().collect()
    } else {
        models.iter().map(Py::get).collect()
    };
    let sessions = py
        .detach(|| {
            models
                .iter()
                .map(|m| session::run(&material, &m.model, &m.label, &opts))
                .collect::<mbgc::Result<Vec<_>>>()
        })
        .map_err(|e| to_py(py, e))?;
    let probabilities =
        (models.len() > 1 && bayes).then(|| session::class_probabilities(&sessions).1);
    let results = sessions
        .iter()
        .map(|s| {
            let (names, draws) = s
                .posterior
                .as_ref()
                .map(|p| (p.names.clone(), p.draws.clone()))
                .unwrap_or_default();
            let record = serde_json::json!({
                "session": s.json(),
                "source": s.source,
                "fixed": s.fixed,
                "measured": s.measured.iter().map(|m| serde_json::json!({
                    "name": m.name, "value": m.value, "sd": m.sd,
                })).collect::<Vec<_>>(),
                "free": s.free,
                "bounds": s.bounds,
                "unused": s.unused,
                "report": report::text(s, ".solutions"),
            });
            (record.to_string(), s.calibrated_toml(), names, draws)
        })
        .collect();
    Ok((results, probabilities))
}
