//! The native half of the `mbgc` Python package (`mbgc._mbgc`): thin calls of the library, as
//! the command line makes them, that take and return plain values (paths, JSON text, float64
//! bytes). The package's Python modules (python/mbgc/) turn those into DataFrames, arrays and
//! result objects; its tests are the pytest suite in tests/.

use pyo3::prelude::*;

mod calibrate;
mod convert;
mod diagnose;
mod documents;
mod errors;
mod fit;
mod model;
mod sample;
mod simulate;

/// The experiments `simulate` knows, by their command-line names.
#[pyfunction]
fn experiment_names() -> Vec<&'static str> {
    mbgc::campaign::experiment_names()
}

/// The sampling methods `sample` knows, by their command-line names.
#[pyfunction]
fn sampling_methods() -> Vec<&'static str> {
    mbgc::sampling::Method::ALL
        .map(mbgc::sampling::Method::name)
        .to_vec()
}

#[pymodule]
fn _mbgc(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<model::NativeModel>()?;
    m.add_function(wrap_pyfunction!(calibrate::calibrate, m)?)?;
    m.add_function(wrap_pyfunction!(diagnose::diagnose, m)?)?;
    m.add_function(wrap_pyfunction!(sample::sample, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(fit::fit, m)?)?;
    m.add_function(wrap_pyfunction!(experiment_names, m)?)?;
    m.add_function(wrap_pyfunction!(sampling_methods, m)?)?;
    Ok(())
}
