//! `calibrate`: a material's parameters from its measurements, by inverting saved metamodels,
//! as `mbgc calibrate` runs it (src/calibrate.rs): the same material reading, `--free`, options
//! and sessions; the result is the session's JSON (what `--json` prints), its calibrated TOML
//! (what `--out` writes) and the posterior draws the corner plot shows.

use pyo3::prelude::*;

use mbgc::calibrate::session::{self, SessionOptions};
use mbgc::material::Material;

use crate::builtin;
use crate::documents::Document;
use crate::errors::{invalid, to_py, OrRaise};
use crate::model::NativeModel;

/// One model's session: its JSON (`session`: what `--json` prints; beside it what the text
/// report shows: the material file, its fixed values and measurements, the free parameters,
/// their search box and those no equation reads), its calibrated TOML, the names of the posterior's axes and
/// the draws (one row per draw; empty without a posterior).
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
            let (m, note) = builtin::material(&path).or_raise(py)?;
            if let Some(note) = note {
                let category = py.get_type::<pyo3::exceptions::PyUserWarning>();
                let text = std::ffi::CString::new(note).unwrap_or_default();
                PyErr::warn(py, &category, &text, 2)?;
            }
            m
        }
        Document::Text { toml, label } => Material::from_toml_str(&toml, &label).or_raise(py)?,
    };
    for name in &free {
        let before = material.fixed.len();
        material.fixed.retain(|(n, _)| n != name);
        if material.fixed.len() == before {
            return Err(invalid(
                py,
                format!(
                    "--free {name}: {} does not fix {name} (it fixes: {})",
                    material.source,
                    material
                        .fixed
                        .iter()
                        .map(|(n, _)| n.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ));
        }
    }
    let opts = SessionOptions {
        starts,
        seed,
        bayes,
        samples,
        sigma_max,
    };
    opts.check().or_raise(py)?;
    let shipped;
    let models: Vec<&NativeModel> = if models.is_empty() {
        shipped = NativeModel::shipped_default(py)?;
        vec![&shipped]
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
            });
            (record.to_string(), s.calibrated_toml(), names, draws)
        })
        .collect();
    Ok((results, probabilities))
}
