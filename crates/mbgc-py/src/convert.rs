//! Numbers and documents between Python and the library: float columns as native-endian bytes
//! (numpy's `tobytes`/`frombuffer`, no copy through Python floats), and Python dicts (as JSON
//! text) as the TOML text the library's file readers parse.

use pyo3::prelude::*;

use crate::errors::invalid;

/// The f64 values of `bytes` (native endian, as numpy writes them).
pub fn floats(py: Python<'_>, bytes: &[u8], what: &str) -> PyResult<Vec<f64>> {
    if !bytes.len().is_multiple_of(8) {
        return Err(invalid(
            py,
            format!(
                "{what}: expected float64 values (a multiple of 8 bytes), got {} bytes",
                bytes.len()
            ),
        ));
    }
    Ok(bytes
        .chunks_exact(8)
        .map(|c| f64::from_ne_bytes(c.try_into().expect("8 bytes")))
        .collect())
}

/// `values` as native-endian bytes.
pub fn bytes_of(values: impl IntoIterator<Item = f64>) -> Vec<u8> {
    values.into_iter().flat_map(f64::to_ne_bytes).collect()
}

/// The TOML text of a document given as JSON (a Python dict through `json.dumps`); `label`
/// names it in errors. TOML has no null, so a `None` is refused naming its key. Keys keep the
/// dict's order (the order of a space's parameters, of a material's measurements): the JSON is
/// read straight into a TOML table, which keeps insertion order, not into serde_json's sorted map.
pub fn toml_of_json(json: &str, label: &str) -> mbgc::Result<String> {
    let bad = |e: &dyn std::fmt::Display| {
        mbgc::Error::input(label, "document", format!("a dict of TOML values ({e})"))
    };
    let value: serde_json::Value = serde_json::from_str(json).map_err(|e| bad(&e))?;
    if !value.is_object() {
        return Err(mbgc::Error::input(
            label,
            "document",
            "a dict of keys and values",
        ));
    }
    if let Some(path) = null_at(&value, &mut String::new()) {
        return Err(mbgc::Error::input(
            label,
            path,
            "a value; TOML has no None (leave the key out instead)",
        ));
    }
    let table: toml::Table = serde_json::from_str(json).map_err(|e| bad(&e))?;
    toml::to_string(&table).map_err(|e| bad(&e))
}

/// The dotted path of the first null in `v`.
fn null_at(v: &serde_json::Value, prefix: &mut String) -> Option<String> {
    match v {
        serde_json::Value::Null => Some(prefix.clone()),
        serde_json::Value::Object(map) => map.iter().find_map(|(k, x)| {
            let len = prefix.len();
            if !prefix.is_empty() {
                prefix.push('.');
            }
            prefix.push_str(k);
            let found = null_at(x, prefix);
            prefix.truncate(len);
            found
        }),
        serde_json::Value::Array(items) => items.iter().enumerate().find_map(|(i, x)| {
            let len = prefix.len();
            prefix.push_str(&format!("[{i}]"));
            let found = null_at(x, prefix);
            prefix.truncate(len);
            found
        }),
        _ => None,
    }
}
