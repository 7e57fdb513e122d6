//! A saved metamodel in Python: loaded from a file, JSON text or the shipped ones, predicting on
//! float columns as `mbgc predict` does (its domain checks included), and its equations exported.

use std::path::PathBuf;

use pyo3::prelude::*;
use pyo3::types::PyBytes;

use mbgc::export::{export, sympy, Format};
use mbgc::metamodel::Metamodel;
use mbgc::shipped;

use crate::convert::{bytes_of, floats};
use crate::errors::{invalid, OrRaise};

/// A metamodel and the name it is reported under (its path, as `--model` gives it).
#[pyclass(frozen, module = "mbgc._mbgc")]
pub struct NativeModel {
    pub model: Metamodel,
    pub label: String,
}

impl NativeModel {
    pub fn new(model: Metamodel, label: String) -> Self {
        NativeModel { model, label }
    }
}

#[pymethods]
impl NativeModel {
    /// Reads a model file written by `mbgc fit` or `mbgc train`.
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let model = Metamodel::load(&path).or_raise(py)?;
        Ok(NativeModel::new(model, path.display().to_string()))
    }

    /// A model from the text of its JSON file; `label` names it in errors and reports.
    #[staticmethod]
    fn from_json(py: Python<'_>, text: &str, label: &str) -> PyResult<Self> {
        let model = Metamodel::from_json_str(text, label).or_raise(py)?;
        Ok(NativeModel::new(model, label.to_string()))
    }

    /// A model shipped with mbgc, by its short name or path: `shear_box` (the default of a
    /// calibration) or another of `mbgc::shipped::names()`.
    #[staticmethod]
    fn shipped(py: Python<'_>, name: &str) -> PyResult<Self> {
        let (model, label) = shipped::model(name).or_raise(py)?;
        Ok(NativeModel::new(model, label))
    }

    #[getter]
    fn label(&self) -> String {
        self.label.clone()
    }

    fn input_names(&self) -> Vec<String> {
        self.model.input_names()
    }

    fn response_names(&self) -> Vec<String> {
        self.model
            .responses
            .iter()
            .map(|r| r.name.clone())
            .collect()
    }

    /// Parameters the model's campaign held at one value: `(name, value)`.
    fn constants(&self) -> Vec<(String, f64)> {
        self.model
            .constants
            .iter()
            .map(|c| (c.name.clone(), c.value))
            .collect()
    }

    /// The model file's JSON text.
    fn to_json(&self, py: Python<'_>) -> PyResult<String> {
        serde_json::to_string(&self.model).map_err(|e| invalid(py, format!("model JSON: {e}")))
    }

    /// Writes the model file (atomically).
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        self.model.save(&path).or_raise(py)
    }

    /// The equations as `mbgc export --format FORMAT` writes them (rust, latex or sympy).
    fn export(&self, py: Python<'_>, format: &str) -> PyResult<String> {
        let format: Format = format.parse().or_raise(py)?;
        Ok(export(&self.model, format))
    }

    /// `(response, sympy-readable equation in the physical inputs)` per response, and the
    /// inputs' names as the equations spell them (distinct Python identifiers).
    fn sympy_equations(&self) -> (Vec<(String, String)>, Vec<String>) {
        let eqs = self
            .model
            .responses
            .iter()
            .enumerate()
            .map(|(k, r)| (r.name.clone(), sympy::equation(&self.model, k)))
            .collect();
        (eqs, sympy::input_names(&self.model))
    }

    /// Predictions of every response for `rows` rows: `inputs` holds the model's input columns
    /// in model order, one after the other, as float64 bytes; `held` the columns of the data
    /// named like the model's constants (`held_names`), which must hold the constant's value.
    /// Returns the responses' columns as bytes, how many rows lie outside the model's valid
    /// domain, and what is wrong with the first of them (as `mbgc predict` warns).
    fn predict<'py>(
        &self,
        py: Python<'py>,
        rows: usize,
        inputs: &[u8],
        held_names: Vec<String>,
        held: &[u8],
    ) -> PyResult<(Bound<'py, PyBytes>, usize, Option<String>)> {
        let m = &self.model;
        let n_in = m.inputs.len();
        let flat = floats(py, inputs, "inputs")?;
        let held_flat = floats(py, held, "held")?;
        if flat.len() != n_in * rows || held_flat.len() != held_names.len() * rows {
            return Err(invalid(
                py,
                format!(
                    "predict: expected {n_in} input and {} held columns of {rows} values",
                    held_names.len()
                ),
            ));
        }
        let constants = held_names
            .iter()
            .map(|n| {
                m.constants
                    .iter()
                    .find(|c| &c.name == n)
                    .ok_or_else(|| invalid(py, format!("predict: {n} is not a constant")))
            })
            .collect::<PyResult<Vec<_>>>()?;
        let (out, outside, first) = py.detach(|| {
            let cols: Vec<Vec<f64>> = flat.chunks(rows.max(1)).map(<[f64]>::to_vec).collect();
            let cols = if rows == 0 {
                vec![Vec::new(); n_in]
            } else {
                cols
            };
            let held_cols: Vec<&[f64]> = held_flat.chunks(rows.max(1)).collect();
            let preds: Vec<Vec<f64>> = m.responses.iter().map(|r| m.predict(r, &cols)).collect();
            let mut outside = 0;
            let mut first = None;
            for row in 0..rows {
                let x: Vec<f64> = cols.iter().map(|c| c[row]).collect();
                let why = if let Some((name, v, d)) = m.outside_domain(&x).first() {
                    Some(format!(
                        "row {row}: {name} = {v} outside [{}, {}]",
                        d[0], d[1]
                    ))
                } else if let Some(c) = m.violated_constraint(&x) {
                    Some(format!(
                        "row {row}: outside the model's limit {c} (its training runs stayed inside)"
                    ))
                } else {
                    constants
                        .iter()
                        .zip(&held_cols)
                        .map(|(c, col)| (c, col[row]))
                        .find(|(c, v)| v.is_nan() || (v - c.value).abs() > 1e-9 * c.value.abs())
                        .map(|(c, v)| {
                            format!(
                                "row {row}: {} = {v}, but the model holds only at {} = {} (its \
                                 campaign held it fixed)",
                                c.name, c.name, c.value
                            )
                        })
                };
                if let Some(w) = why {
                    outside += 1;
                    first.get_or_insert(w);
                }
            }
            (bytes_of(preds.into_iter().flatten()), outside, first)
        });
        Ok((PyBytes::new(py, &out), outside, first))
    }
}
