//! The `[model]` table that space, material and calibrated-parameter files share:
//!
//! ```toml
//! [model]
//! class = "hertz,mindlin,epsd2,sjkr"   # the effects of the contact law (see `--model-class`)
//! ```
//!
//! and the check that a file's parameters belong to the effects its class switches on.

use serde::Deserialize;

use crate::error::{Error, Result};
use mbgc_dem::contact::{ModelClass, Pair};

#[derive(Debug, Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a table with `class = \"hertz,mindlin,epsd2\"`"
)]
/// The `[model]` table as written; [`ModelTable::class`] checks and parses it.
pub struct ModelTable {
    class: Option<String>,
}

impl ModelTable {
    /// The class the table names; the error names the file and the field.
    pub fn class(&self, file: &str) -> Result<ModelClass> {
        let text = self.class.as_deref().ok_or_else(|| {
            Error::input(
                file,
                "model.class",
                "missing; expected the effects, e.g. class = \"hertz,mindlin,epsd2,sjkr\"",
            )
        })?;
        ModelClass::parse(text).map_err(|e| Error::input(file, "model.class", e.to_string()))
    }
}

/// Refuses a parameter of `names` that belongs to an effect `class` does not switch on (for
/// either kind of contact); `what` says where the names come from, e.g. `parameters`.
pub fn refuse_inactive_parameters<'a>(
    class: &ModelClass,
    names: impl IntoIterator<Item = &'a str>,
    file: &str,
    what: &str,
    class_source: &str,
) -> Result<()> {
    for n in names {
        class
            .refuse_inactive(n, &Pair::BOTH, class_source)
            .map_err(|e| Error::input(file, format!("{what}.{n}"), e.to_string()))?;
    }
    Ok(())
}
