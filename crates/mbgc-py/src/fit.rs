//! `fit`: one equation per response by genetic programming, as `mbgc fit` runs it (src/fit.rs):
//! the same GP settings and checks, the space, model class and similarity, a validation table
//! and a model to correct. The data are a table file (read as the command line reads it) or
//! columns in memory (a DataFrame's). The search runs without the GIL; each generation is
//! reported to a Python callable.

use std::path::PathBuf;
use std::sync::Mutex;

use pyo3::prelude::*;

use mbgc::dem::contact::ModelClass;
use mbgc::gp::select::Selection;
use mbgc::gp::Config;
use mbgc::metamodel::{fit as run, FitSettings, TrainingTable};
use mbgc::plot::fit_figures::fit_figures;
use mbgc::space::Space;

use crate::errors::{invalid, to_py, OrRaise};
use crate::model::NativeModel;

/// Named columns of a data frame.
type Columns = Vec<(String, Vec<f64>)>;

/// The GP settings of `mbgc fit`'s flags, by the flags' names.
#[derive(FromPyObject)]
pub struct GpOptions {
    #[pyo3(item)]
    seed: u64,
    #[pyo3(item)]
    population: usize,
    #[pyo3(item)]
    generations: usize,
    #[pyo3(item)]
    time_limit: Option<f64>,
    #[pyo3(item)]
    functions: String,
    #[pyo3(item)]
    parsimony: f64,
    #[pyo3(item)]
    islands: usize,
    #[pyo3(item)]
    restarts: usize,
    #[pyo3(item)]
    select: String,
    #[pyo3(item)]
    tournament: usize,
    #[pyo3(item)]
    max_length: usize,
    #[pyo3(item)]
    linear_scaling: bool,
}

impl GpOptions {
    /// The engine's configuration, refused as the command line refuses it.
    fn config(&self, py: Python<'_>) -> PyResult<Config> {
        // Values the engine would silently bend: an infinite parsimony made every tree equal.
        if !(self.parsimony.is_finite() && self.parsimony >= 0.0) {
            return Err(invalid(
                py,
                format!(
                    "--parsimony {}: expected a finite penalty >= 0 (default 0.001)",
                    self.parsimony
                ),
            ));
        }
        if let Some(t) = self.time_limit.filter(|t| !(t.is_finite() && *t > 0.0)) {
            return Err(invalid(
                py,
                format!("--time-limit {t}: expected a positive number of seconds"),
            ));
        }
        let selection = Selection::from_flag(&self.select)
            .map_err(|e| invalid(py, format!("--select: {e}")))?;
        let config = Config {
            population: self.population,
            generations: self.generations,
            islands: self.islands,
            tournament: self.tournament,
            parsimony: self.parsimony,
            functions: self.functions.clone(),
            max_length: self.max_length,
            linear_scaling: self.linear_scaling,
            time_limit: self.time_limit,
            seed: self.seed,
            restarts: self.restarts,
            selection,
            ..Config::default()
        };
        if let Some(size) = config.sizes().iter().find(|s| !s.holds()) {
            return Err(invalid(py, size.refusal(&size.flag())));
        }
        Ok(config)
    }
}

/// Fits `targets` on `inputs` of the table file `data_path` or of the in-memory `columns`
/// (named `label`). Returns the model, the warnings the command line prints and the figures
/// written.
#[pyfunction]
#[pyo3(signature = (data_path, columns, label, inputs, targets, options, test_fraction, space, model_class, similarity, validation_path, validation_columns, correct, figures, out, progress))]
#[allow(clippy::too_many_arguments)]
pub fn fit(
    py: Python<'_>,
    data_path: Option<PathBuf>,
    columns: Option<Columns>,
    label: &str,
    inputs: Vec<String>,
    targets: Vec<String>,
    options: GpOptions,
    test_fraction: f64,
    space: Option<PathBuf>,
    model_class: Option<String>,
    similarity: Option<String>,
    validation_path: Option<PathBuf>,
    validation_columns: Option<Columns>,
    correct: Option<Py<NativeModel>>,
    figures: Option<PathBuf>,
    out: Option<PathBuf>,
    progress: Option<Py<PyAny>>,
) -> PyResult<(NativeModel, Vec<String>, Vec<PathBuf>)> {
    let mut read: Vec<(&str, &std::path::Path)> = Vec::new();
    if let Some(d) = &data_path {
        read.push(("--data", d));
    }
    if let Some(v) = &validation_path {
        read.push(("--validation", v));
    }
    if let Some(s) = &space {
        read.push(("--space", s));
    }
    if let Some(out) = &out {
        mbgc::outputs::refuse_overwriting_inputs("--out", out, &read).or_raise(py)?;
    }
    if let Some(dir) = &figures {
        mbgc::outputs::refuse_figures_over_inputs("--figures", dir, &read).or_raise(py)?;
    }
    let config = options.config(py)?;
    let model_class = model_class
        .as_deref()
        .map(ModelClass::parse)
        .transpose()
        .map_err(|e| invalid(py, format!("--model-class: {e}")))?;
    let mut settings = FitSettings::new(inputs.clone(), targets.clone())
        .test_fraction(test_fraction)
        .config(config);
    settings.space = space
        .as_deref()
        .map(Space::from_file)
        .transpose()
        .or_raise(py)?;
    settings.model_class = model_class;
    settings.similarity = match &similarity {
        Some(name) => Some(similarity_of(py, name, &settings, data_path.as_deref())?),
        None => None,
    };
    settings.check().or_raise(py)?;
    let table = |path: &Option<PathBuf>, cols: Option<Columns>, name: &str| match (path, cols) {
        (Some(p), None) => TrainingTable::read_csv(p, &inputs, &targets).map(Some),
        (None, Some(c)) => TrainingTable::from_columns(name, c).map(Some),
        (None, None) => Ok(None),
        (Some(_), Some(_)) => Err(mbgc::Error::invalid(format!(
            "{name}: expected a table file or columns, not both"
        ))),
    };
    let Some(data) = table(&data_path, columns, label).or_raise(py)? else {
        return Err(invalid(py, "--data: expected a table file or a DataFrame"));
    };
    settings.validation = table(&validation_path, validation_columns, "validation").or_raise(py)?;
    settings.extends = correct.map(|m| Box::new(m.get().model.clone()));
    let error: Mutex<Option<PyErr>> = Mutex::new(None);
    let fitted = py
        .detach(|| {
            run(&data, &settings, |target, p| {
                let Some(callback) = &progress else { return };
                let mut error = error.lock().unwrap_or_else(|e| e.into_inner());
                if error.is_none() {
                    let args = (target, p.generation + 1, p.best_nmse);
                    if let Err(e) = Python::attach(|py| callback.call1(py, args).map(drop)) {
                        *error = Some(e);
                    }
                }
            })
        })
        .map_err(|e| to_py(py, e))?;
    if let Some(e) = error.into_inner().unwrap_or_else(|e| e.into_inner()) {
        return Err(e);
    }
    let figure_paths = match &figures {
        Some(dir) => py.detach(|| fit_figures(dir, &fitted)).or_raise(py)?,
        None => Vec::new(),
    };
    let mut warnings = fitted.warnings.clone();
    if fitted.model.experiment.is_none() && fitted.model.model_class.is_some() {
        if let Some(d) = &data_path {
            warnings.push(format!(
                "{} has no campaign record beside it ({}.meta.json): the model records no \
                 experiment and no box scale, so `validate` cannot check that it reruns the \
                 experiment the model was trained on",
                d.display(),
                d.display()
            ));
        }
    }
    let model = fitted.model;
    let label = match &out {
        Some(path) => {
            model.save(path).or_raise(py)?;
            path.display().to_string()
        }
        None => model.data.file.clone(),
    };
    Ok((NativeModel::new(model, label), warnings, figure_paths))
}

/// The similarity of experiment `name` under the model class the fit has (given, the space's,
/// or the campaign's that made the table), without the groups the space fixes: as `mbgc fit
/// --similarity` finds it.
fn similarity_of(
    py: Python<'_>,
    name: &str,
    settings: &FitSettings,
    data: Option<&std::path::Path>,
) -> PyResult<mbgc::similarity::Similarity> {
    let class = match settings
        .model_class
        .or_else(|| settings.space.as_ref().and_then(|s| s.model_class))
    {
        Some(c) => Some(c),
        None => match data
            .map(mbgc::campaign::Meta::read)
            .transpose()
            .or_raise(py)?
        {
            // "-": an experiment without a contact law.
            Some(Some(m)) if m.model_class != "-" => {
                Some(ModelClass::parse(&m.model_class).map_err(|e| {
                    invalid(
                        py,
                        format!(
                            "{}: model_class: {e}",
                            mbgc::campaign::meta_path(data.unwrap_or(std::path::Path::new("")))
                                .display()
                        ),
                    )
                })?)
            }
            _ => None,
        },
    };
    let experiment = mbgc::campaign::experiment_by_name(
        name,
        &mbgc::campaign::ExperimentSettings {
            box_scale: None,
            model_class: class,
            ..Default::default()
        },
    )
    .or_raise(py)?;
    let sim = experiment.similarity().ok_or_else(|| {
        invalid(
            py,
            format!(
                "--similarity {name}: {name} has no dimensionless groups{} (an effect parameter \
                 of a dimension other than a stress, such as a spring in N/m, would need its \
                 own); fit without it",
                class
                    .map(|c| format!(" with the effects {c}"))
                    .unwrap_or_default()
            ),
        )
    })?;
    Ok(match &settings.space {
        Some(space) => sim.without_constant_groups(|n| space.get(n).is_some_and(|p| p.is_fixed())),
        None => sim,
    })
}
