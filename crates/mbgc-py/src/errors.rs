//! The library's errors as Python exceptions. The classes live in `mbgc/errors.py` (so that they
//! can also derive from ValueError or OSError, which PyO3's `create_exception!` cannot); the
//! message is the error's Display text, the one the command line prints.

use pyo3::prelude::*;

/// The Python exception for `e`, an instance of the `mbgc.errors` class of its kind carrying the
/// file, the field and what was expected where the error names them.
pub fn to_py(py: Python<'_>, e: mbgc::Error) -> PyErr {
    let message = e.to_string();
    let (class, file, field, expected, errno) = match e {
        mbgc::Error::Input {
            file,
            field,
            expected,
        } => ("InputError", Some(file), Some(field), Some(expected), None),
        mbgc::Error::OutOfDomain {
            file,
            field,
            expected,
        } => (
            "OutOfDomainError",
            Some(file),
            Some(field),
            Some(expected),
            None,
        ),
        mbgc::Error::Io { file, cause } => {
            ("FileError", Some(file), None, None, cause.raw_os_error())
        }
        mbgc::Error::Invalid(_) => ("InvalidRequestError", None, None, None, None),
        mbgc::Error::NoSolution(_) => ("NoSolutionError", None, None, None, None),
        mbgc::Error::Infeasible(_) => ("InfeasibleError", None, None, None, None),
    };
    let made = py.import("mbgc.errors").and_then(|m| {
        let instance = m
            .getattr(class)?
            .call1((message.clone(), file, field, expected))?;
        if let Some(n) = errno {
            instance.setattr("errno", n)?;
        }
        Ok(PyErr::from_value(instance))
    });
    // Only a broken installation (mbgc.errors missing) lands here; the message is kept.
    made.unwrap_or_else(|import| {
        pyo3::exceptions::PyRuntimeError::new_err(format!("{message} (and {import})"))
    })
}

/// A refusal of a request, as the library's [`mbgc::Error::Invalid`] would be raised.
pub fn invalid(py: Python<'_>, message: impl Into<String>) -> PyErr {
    to_py(py, mbgc::Error::invalid(message))
}

/// `Result` of the library into a Python result.
pub trait OrRaise<T> {
    /// The value, or the error as its Python exception.
    fn or_raise(self, py: Python<'_>) -> PyResult<T>;
}

impl<T> OrRaise<T> for mbgc::Result<T> {
    fn or_raise(self, py: Python<'_>) -> PyResult<T> {
        self.map_err(|e| to_py(py, e))
    }
}
