//! The documents a call names by file or gives as a dict: a material, a measurement set, a
//! space. A dict arrives as JSON text and is read as the TOML file it stands for, so it is
//! checked, and its errors worded, exactly as that file would be.

use std::path::PathBuf;

use pyo3::prelude::*;

use crate::convert::toml_of_json;
use crate::errors::{invalid, OrRaise};

/// A document as the caller gave it.
pub enum Document {
    /// A file, read by the library's `from_file`.
    File(PathBuf),
    /// TOML text made from a dict, and the label that names it in errors.
    Text { toml: String, label: String },
}

impl Document {
    /// The document of `path` or of `json` (a dict as JSON text, named `label`): exactly one.
    pub fn new(
        py: Python<'_>,
        path: Option<PathBuf>,
        json: Option<String>,
        label: &str,
    ) -> PyResult<Document> {
        match (path, json) {
            (Some(p), None) => Ok(Document::File(p)),
            (None, Some(j)) => Ok(Document::Text {
                toml: toml_of_json(&j, label).or_raise(py)?,
                label: label.to_string(),
            }),
            _ => Err(invalid(
                py,
                format!("{label}: expected a file path or a dict"),
            )),
        }
    }
}
